// SPDX-License-Identifier: MIT
// Analytic primitives: gradients against central differences, compact support, C1 across the
// support border, the 0.5 iso-surface, rigid transforms, and bad input.
#include <catch2/catch.hpp>

#include <functional>
#include <memory>

#include "isokit/core/error.h"
#include "isokit/implicit/primitives.h"
#include "test_util.h"

using namespace isokit;
using namespace isokit::implicit;

namespace {

struct Shape {
  std::string name;
  std::function<FieldSampleT<double>(const Vec3d&)> eval_d;  // same math in double
  std::shared_ptr<const Field> field;                        // the float class
  double radius, width;
  std::function<double(const Vec3d&)> surface_distance;  // signed, < 0 inside
};

std::vector<Shape> random_shapes(test::Rng& rng, int count) {
  std::vector<Shape> shapes;
  for (int i = 0; i < count; ++i) {
    const double radius = rng.uniform(0.05, 2.0);
    const double width = rng.uniform(0.2, 1.0) * radius;
    if (i % 2 == 0) {
      const SphereParamsT<double> s{rng.vec(-2, 2), radius, width};
      shapes.push_back({"sphere", [s](const Vec3d& p) { return eval_sphere(s, p); },
                        std::make_shared<SphereField>(test::to_float(s.center), float(radius), float(width)),
                        radius, width, [s](const Vec3d& p) { return norm(p - s.center) - s.radius; }});
    } else {
      const CapsuleParamsT<double> c{rng.vec(-2, 2), rng.vec(-2, 2), radius, width};
      shapes.push_back(
          {"capsule", [c](const Vec3d& p) { return eval_capsule(c, p); },
           std::make_shared<CapsuleField>(test::to_float(c.a), test::to_float(c.b), float(radius),
                                          float(width)),
           radius, width,
           [c](const Vec3d& p) { return norm(p - closest_on_segment(c.a, c.b, p)) - c.radius; }});
    }
  }
  return shapes;
}

Vec3d random_point_near(test::Rng& rng, const Field& f) {
  const Box3f b = f.support();
  const Vec3d lo = test::to_double(b.lo), hi = test::to_double(b.hi);
  const Vec3d pad = (hi - lo) * 0.1;
  return {rng.uniform(lo.x - pad.x, hi.x + pad.x), rng.uniform(lo.y - pad.y, hi.y + pad.y),
          rng.uniform(lo.z - pad.z, hi.z + pad.z)};
}

}  // namespace

TEST_CASE("primitive gradients agree with central differences", "[implicit][primitives]") {
  test::Rng rng(21);
  for (const Shape& s : random_shapes(rng, 40)) {
    INFO(s.name << " radius " << s.radius << " width " << s.width);
    for (int i = 0; i < 300; ++i) {
      const Vec3d p = random_point_near(rng, *s.field);
      const double dist = s.surface_distance(p);
      // Skip points where the distance itself is not differentiable (on the axis).
      if (dist < -s.radius + 1e-3 * s.radius) continue;
      const double h = 1e-6 * s.radius;
      const Vec3d fd = test::central_gradient([&](const Vec3d& q) { return s.eval_d(q).value; }, p, h);
      const Vec3d g = s.eval_d(p).gradient;
      const double scale = 1.0 / s.width;  // |∇f| <= 15 / (16 width)
      CHECK(norm(g - fd) <= 1e-6 * scale);
      // The float class evaluates the same formula.
      const FieldSample sf = s.field->eval(test::to_float(p));
      CHECK(sf.value == Approx(s.eval_d(p).value).margin(1e-5));
      CHECK(norm(test::to_double(sf.gradient) - g) <= 1e-4 * scale);
    }
  }
}

TEST_CASE("primitives: 0.5 on the surface, > 0.5 inside, gradient inward", "[implicit][primitives]") {
  test::Rng rng(22);
  for (const Shape& s : random_shapes(rng, 40)) {
    for (int i = 0; i < 200; ++i) {
      const Vec3d p = random_point_near(rng, *s.field);
      const auto v = s.eval_d(p);
      const double dist = s.surface_distance(p);
      if (dist < -1e-9) CHECK(v.value > 0.5);
      if (dist > 1e-9) CHECK(v.value < 0.5);
      // Gradient points toward smaller distance (inward) wherever it is non-zero.
      if (norm(v.gradient) > 1e-9) {
        const Vec3d step = v.gradient / norm(v.gradient) * (1e-4 * s.radius);
        CHECK(s.surface_distance(p + step) < dist);
      }
    }
  }
  const SphereParamsT<double> unit{{0, 0, 0}, 1.0, 0.5};
  CHECK(eval_sphere(unit, Vec3d{1, 0, 0}).value == 0.5);
  CHECK(eval_sphere(unit, Vec3d{0, 0, 0}).value == 1.0);
  CHECK(norm(eval_sphere(unit, Vec3d{0, 0, 0}).gradient) == 0.0);
}

TEST_CASE("primitives are exactly 0 outside their support and C1 across its border",
          "[implicit][primitives]") {
  test::Rng rng(23);
  for (const Shape& s : random_shapes(rng, 40)) {
    const Box3f box = s.field->support();
    for (int i = 0; i < 300; ++i) {
      const Vec3d p = random_point_near(rng, *s.field);
      const Vec3f pf = test::to_float(p);
      if (!box.contains(pf)) {
        const FieldSample v = s.field->eval(pf);
        CHECK(v.value == 0.f);
        CHECK(v.gradient == Vec3f{});
      }
      if (s.surface_distance(p) >= s.width) {
        CHECK(s.eval_d(p).value == 0.0);
        CHECK(norm(s.eval_d(p).gradient) == 0.0);
      }
    }
    // Approach the outer support shell along a ray: value = O(e^3), gradient = O(e^2).
    const Vec3d dir = rng.unit();
    const Vec3d origin =
        s.name == "sphere"
            ? test::to_double(std::static_pointer_cast<const SphereField>(s.field)->params().center)
            : test::to_double(std::static_pointer_cast<const CapsuleField>(s.field)->params().a);
    // Find the shell by bisection on the signed distance along the ray.
    double lo = 0, hi = 10 * (s.radius + s.width) + 10;
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (lo + hi);
      (s.surface_distance(origin + dir * mid) < s.width ? lo : hi) = mid;
    }
    for (double e : {1e-2, 1e-3, 1e-4}) {
      const double eps = e * s.width;
      const auto v = s.eval_d(origin + dir * (lo - eps));
      // With e = eps / r: t_r(r - eps) <= (5/4) e^3 and |t_r'(r - eps)| <= (15/4) e^2 / r.
      CHECK(v.value <= 1.25 * e * e * e * 1.001 + 1e-15);
      CHECK(norm(v.gradient) <= 3.75 * e * e / s.width * 1.001 + 1e-15);
    }
  }
}

TEST_CASE("rigidly transformed primitives move rigidly", "[implicit][primitives]") {
  test::Rng rng(24);
  auto capsule = std::make_shared<CapsuleField>(Vec3f{0, 0, 0}, Vec3f{0, 0, 1}, 0.3f, 0.2f);
  for (int trial = 0; trial < 50; ++trial) {
    Rigid3f xf;
    const Mat3T<double> R = rng.rotation();
    for (int k = 0; k < 9; ++k) xf.R.m[k] = float(R.m[k]);
    xf.t = test::to_float(rng.vec(-3, 3));
    const TransformedField moved(capsule, xf);
    const Box3f box = moved.support();
    for (int i = 0; i < 100; ++i) {
      const Vec3f local = test::to_float(rng.vec(-0.6, 1.6));
      const FieldSample a = capsule->eval(local), b = moved.eval(xf.apply(local));
      CHECK(b.value == Approx(a.value).margin(1e-5));
      CHECK(norm(b.gradient - xf.rotate(a.gradient)) <= 1e-4f);
      if (a.value > 0.f) CHECK(box.contains(xf.apply(local)));
    }
    // with_transform shares the local field and only changes the placement.
    const TransformedField back = moved.with_transform(Rigid3f{});
    CHECK(back.eval({0.2f, 0.f, 0.5f}).value == capsule->eval({0.2f, 0.f, 0.5f}).value);
  }
}

TEST_CASE("primitives reject bad parameters with a named error", "[implicit][primitives][errors]") {
  const float nan = std::nanf(""), inf = INFINITY;
  CHECK_THROWS_WITH(SphereField({0, 0, 0}, -1.f), Catch::Contains("SphereField radius"));
  CHECK_THROWS_WITH(SphereField({0, 0, 0}, nan), Catch::Contains("SphereField radius"));
  CHECK_THROWS_WITH(SphereField({0, 0, 0}, 1.f, inf), Catch::Contains("support_width"));
  CHECK_THROWS_WITH(SphereField({nan, 0, 0}, 1.f), Catch::Contains("center"));
  CHECK_THROWS_WITH(CapsuleField({0, 0, 0}, {0, inf, 0}, 1.f), Catch::Contains("endpoints"));
  CHECK_THROWS_WITH(CapsuleField({0, 0, 0}, {0, 1, 0}, 0.f, 0.5f), Catch::Contains("radius"));
  CHECK_THROWS_AS(CapsuleField({0, 0, 0}, {0, 1, 0}, 1.f, -0.5f), InputError);

  auto s = std::make_shared<SphereField>(Vec3f{0, 0, 0}, 1.f);
  Rigid3f scaled;
  scaled.R.m[0] = 2.f;
  CHECK_THROWS_WITH(TransformedField(s, scaled), Catch::Contains("not rigid"));
  Rigid3f mirrored;
  mirrored.R.m[0] = -1.f;
  CHECK_THROWS_WITH(TransformedField(s, mirrored), Catch::Contains("not rigid"));
  Rigid3f bad_t;
  bad_t.t.y = nan;
  CHECK_THROWS_WITH(TransformedField(s, bad_t), Catch::Contains("non-finite"));
  CHECK_THROWS_AS(TransformedField(nullptr, Rigid3f{}), InputError);
}
