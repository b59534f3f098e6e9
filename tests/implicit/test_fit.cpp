// SPDX-License-Identifier: MIT
// Mesh-part fitting (2013 §4.1): reproduces a sphere and a capped cylinder, closes a limb at its
// joint, gradients against finite differences, determinism, bad input.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

#include "isokit/core/error.h"
#include "isokit/core/math.h"
#include "isokit/implicit/fit.h"
#include "isokit/implicit/fit_quality.h"
#include "isokit/implicit/primitives.h"
#include "test_util.h"

using namespace isokit;
using namespace isokit::implicit;

namespace {

/// Surface of revolution around the segment `a`–`b`: rings at parameters along a profile
/// `(axial offset, radius)`; `cap0` / `cap1` add pole vertices closing the ends.
MeshPart revolve(const std::vector<std::pair<double, double>>& profile, const Vec3d& a, const Vec3d& b,
                 int segments, bool cap0, bool cap1, const Vec3d& pole0, const Vec3d& pole1) {
  MeshPart m;
  const Rigid3d f = bone_frame(a, b);
  for (const auto& [z, rad] : profile)
    for (int s = 0; s < segments; ++s) {
      const double t = 2 * kPi * s / segments;
      m.vertices.push_back(f.apply({rad * std::cos(t), rad * std::sin(t), z}));
    }
  const int rings = int(profile.size());
  for (int r = 0; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const int i0 = r * segments + s, i1 = r * segments + (s + 1) % segments;
      const int j0 = i0 + segments, j1 = i1 + segments;
      m.triangles.push_back({i0, i1, j1});
      m.triangles.push_back({i0, j1, j0});
    }
  if (cap0) {
    m.vertices.push_back(f.apply(pole0));
    const int p = int(m.vertices.size()) - 1;
    for (int s = 0; s < segments; ++s) m.triangles.push_back({p, (s + 1) % segments, s});
  }
  if (cap1) {
    m.vertices.push_back(f.apply(pole1));
    const int p = int(m.vertices.size()) - 1, base = (rings - 1) * segments;
    for (int s = 0; s < segments; ++s) m.triangles.push_back({p, base + s, base + (s + 1) % segments});
  }
  m.bone_start = a;
  m.bone_end = b;
  return m;
}

/// Where the field's 0.5 level (d = 0) crosses the ray `o + t u`, t in (0, tmax]: bisection on
/// the HRBF distance (in the part's local frame).
double iso_along(const FittedPart& fp, const Vec3d& o_world, const Vec3d& u_world, double tmax) {
  const Vec3d o = fp.local_to_world.apply_inverse(o_world);
  const Vec3d u = fp.local_to_world.rotate_inverse(u_world);
  auto d = [&](double t) { return fp.local->hrbf().distance(o + u * t).value; };
  double lo = 0, hi = tmax;
  REQUIRE(d(lo) < 0);
  REQUIRE(d(hi) > 0);
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (d(mid) < 0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

MeshPart sphere_part(double R, const Vec3d& c, const Vec3d& axis) {
  std::vector<std::pair<double, double>> prof;
  const int rings = 24;
  for (int i = 1; i < rings; ++i) {
    const double th = kPi * i / rings;  // from the -axis pole
    prof.push_back({-R * std::cos(th) + 0.5 * R, R * std::sin(th)});
  }
  // bone from c - axis R/2 to c + axis R/2; frame z along the axis, origin at bone start
  return revolve(prof, c - axis * (0.5 * R), c + axis * (0.5 * R), 32, true, true, {0, 0, -0.5 * R},
                 {0, 0, 1.5 * R});
}

}  // namespace

TEST_CASE("fitting a sampled sphere reproduces it", "[fit]") {
  const double R = 0.8;
  const Vec3d c{0.3, -1.0, 2.0};
  Vec3d axis{0.3, 0.5, 0.8};
  axis = axis / norm(axis);
  MeshPart part = sphere_part(R, c, axis);
  part.name = "ball";
  const FittedPart fp = fit_part(part);
  CHECK(fp.closure_points == 2);
  CHECK(fp.samples.size() >= 45);
  CHECK(fp.samples.size() <= 60);
  // r = bone-to-farthest-sample distance: about R for a sphere around a bone of length R.
  CHECK(fp.r == Approx(R).epsilon(0.05));
  test::Rng rng(21);
  double worst = 0;
  for (int i = 0; i < 300; ++i) {
    const Vec3d u = rng.unit();
    worst = std::max(worst, std::abs(iso_along(fp, c, u, 2 * R) - R));
  }
  INFO("max radial error of the 0.5 iso-surface: " << worst / R << " R");
  CHECK(worst <= 0.02 * R);  // measured 0.0077 R (polygonal input mesh of 24 x 32 facets)
  // Inside > 0.5: near 1 at the sphere's centre, on the bone.
  const Vec3d lc = fp.local_to_world.apply_inverse(c);
  CHECK(fp.local->eval_d(lc).value > 0.9);
}

namespace {

/// A capsule of radius `R` around the segment (0,0,0)-(0,0,L), as a closed mesh.
MeshPart capsule_part(double R, double L) {
  std::vector<std::pair<double, double>> prof;
  for (int i = 1; i < 8; ++i)
    prof.push_back({-R * std::cos(0.5 * kPi * i / 8), R * std::sin(0.5 * kPi * i / 8)});
  for (int i = 0; i <= 10; ++i) prof.push_back({L * i / 10, R});
  for (int i = 1; i < 8; ++i)
    prof.push_back({L + R * std::sin(0.5 * kPi * i / 8), R * std::cos(0.5 * kPi * i / 8)});
  return revolve(prof, {0, 0, 0}, {0, 0, L}, 32, true, true, {0, 0, -R}, {0, 0, L + R});
}

}  // namespace

TEST_CASE("fitting a capped cylinder reproduces it", "[fit]") {
  const double R = 0.4, L = 2.0;
  const MeshPart part = capsule_part(R, L);
  const FittedPart fp = fit_part(part);
  CHECK(fp.r == Approx(R).epsilon(0.02));
  test::Rng rng(22);
  double worst = 0;
  for (int i = 0; i < 300; ++i) {
    const Vec3d o{0, 0, rng.uniform(0, L)};
    const Vec3d u = rng.unit();
    const double t = iso_along(fp, o, u, L + 2 * R);
    const Vec3d p = o + u * t;
    const double dist = norm(p - Vec3d{0, 0, std::clamp(p.z, 0.0, L)}) - R;  // capsule SDF
    worst = std::max(worst, std::abs(dist));
  }
  INFO("max distance of the 0.5 iso-surface to the capsule: " << worst / R << " R");
  CHECK(worst <= 0.08 * R);  // measured 0.061 R (seed 1, 50 samples; the caps are the worst)
}

TEST_CASE("fit distances both ways: small for a fitted capsule, large for a bad field", "[fit]") {
  const double R = 0.4, L = 2.0;
  const MeshPart part = capsule_part(R, L);
  const FittedPart fp = fit_part(part);
  SECTION("the fitted primitive: both ways within a lattice spacing") {
    const FitDistances d = fit_distances(*fp.field(), fp.local_to_world, part.vertices, part.triangles);
    INFO("vertex->surface max " << d.to_surface_max / R << " R, surface->vertex max "
                                << d.from_surface_max / R << " R over " << d.surface_points << " points");
    CHECK(d.vertices == int(part.vertices.size()));
    CHECK(d.surface_points > 500);
    CHECK(d.to_surface_p95 <= d.to_surface_max);
    CHECK(d.to_surface_max <= 0.1 * R);
    CHECK(d.from_surface_max <= 0.1 * R);
  }
  SECTION("the exact capsule field: the mesh's own facets are the only error") {
    const CapsuleField exact({0, 0, 0}, {0, 0, float(L)}, float(R), float(R));
    const FitDistances d = fit_distances(exact, Rigid3d{}, part.vertices, part.triangles);
    CHECK(d.to_surface_max <= 0.02 * R);
    CHECK(d.from_surface_max <= 0.03 * R);
  }
  SECTION("a field twice too wide: both ways about R") {
    const CapsuleField wide({0, 0, 0}, {0, 0, float(L)}, float(2 * R), float(R));
    const FitDistances d = fit_distances(wide, Rigid3d{}, part.vertices, part.triangles);
    CHECK(d.to_surface_p95 >= 0.9 * R);
    CHECK(d.from_surface_max >= 0.9 * R);
  }
  SECTION("a field over half the part: vertices -> surface large, surface -> vertices at most R (its cap)") {
    const CapsuleField half({0, 0, 0}, {0, 0, float(L / 2)}, float(R), float(R));
    const FitDistances d = fit_distances(half, Rigid3d{}, part.vertices, part.triangles);
    CHECK(d.to_surface_max >= 0.9 * L / 2);
    CHECK(d.from_surface_max <= 1.05 * R);
  }
  SECTION("excluded surface points are left out; no 0.5 level: infinite, not NaN") {
    const CapsuleField exact({0, 0, 0}, {0, 0, float(L)}, float(R), float(R));
    const FitDistances d = fit_distances(exact, Rigid3d{}, part.vertices, part.triangles,
                                         [](const Vec3d& p) { return p.z > 1.0; });
    CHECK(d.surface_points > 0);
    const FitDistances all = fit_distances(exact, Rigid3d{}, part.vertices, part.triangles);
    CHECK(d.surface_points < all.surface_points);
    struct Dim final : Field {  // 0.25 on a box, nowhere 0.5
      FieldSample eval(const Vec3f&) const override { return {0.25f, {}}; }
      Box3f support() const override { return {{-1, -1, -1}, {1, 1, 3}}; }
    };
    const FitDistances none = fit_distances(Dim{}, Rigid3d{}, part.vertices, part.triangles);
    CHECK(std::isinf(none.to_surface_max));
    CHECK(none.from_surface_max == 0);
    CHECK_THROWS_AS(
        fit_distances(exact, Rigid3d{}, part.vertices, part.triangles, {}, FitDistanceOptions{4, 10}),
        InputError);
  }
}

TEST_CASE("a fitted limb part closes smoothly at its joint", "[fit]") {
  // Open tube (no caps) from the joint at z = 0 to z = L: the closure point at -R on the axis
  // makes the end cap follow the sphere of radius s = R centred on the joint (2013 Fig. 4).
  const double R = 0.3, L = 1.5;
  std::vector<std::pair<double, double>> prof;
  for (int i = 0; i <= 15; ++i) prof.push_back({L * i / 15, R});
  const MeshPart part = revolve(prof, {0, 0, 0}, {0, 0, L}, 24, false, false, {}, {});
  double worst_closed = 0, worst_open = 0;
  PartFitOptions paper;  // the paper's closure points (the default)
  paper.closure = PartFitOptions::Closure::joints;
  PartFitOptions open_opts = paper;
  open_opts.close_start = false;
  const FittedPart closed = fit_part(part, paper);
  const FittedPart open = fit_part(part, open_opts);
  for (int i = 0; i <= 40; ++i) {
    const double th = 0.5 * kPi + 0.5 * kPi * i / 40;  // from the side (90°) to the axis (180°)
    for (double phi : {0.0, 1.3, 2.9, 4.4}) {
      const Vec3d u{std::sin(th) * std::cos(phi), std::sin(th) * std::sin(phi), std::cos(th)};
      worst_closed = std::max(worst_closed, std::abs(iso_along(closed, {0, 0, 0}, u, 4 * R) - R));
      worst_open = std::max(worst_open, std::abs(iso_along(open, {0, 0, 0}, u, 6 * R) - R));
    }
  }
  INFO("closed: " << worst_closed / R << " R, without closure: " << worst_open / R << " R");
  CHECK(worst_closed <= 0.1 * R);        // measured 0.064 R; without the closure point 0.68 R
  CHECK(worst_open > 2 * worst_closed);  // the closure point is what removes the bump
}

TEST_CASE("openings close a part's holes at their joints (branching parts)", "[fit]") {
  // An open tube along an arbitrary axis, closed by openings instead of the bone-end closures
  // (what a hips or chest part gets at each child joint): the cap's 0.5 level crosses the axis
  // `opening_offset × s` beyond each joint (s = R here), and the field vanishes beyond it.
  const double R = 0.3, L = 1.5;
  Vec3d axis{0.3, -0.4, 0.87};
  axis = axis / norm(axis);
  const Vec3d a{0.2, -0.1, 0.3}, b = a + axis * L;
  std::vector<std::pair<double, double>> prof;
  for (int i = 0; i <= 15; ++i) prof.push_back({L * i / 15, R});
  MeshPart part = revolve(prof, a, b, 24, false, false, {}, {});
  part.name = "pelvis";
  part.openings = {{a, axis * -1.0}, {b, axis}};
  for (double k : {0.1, 0.5, 1.0}) {
    PartFitOptions o;
    o.closure = PartFitOptions::Closure::joints;
    o.close_start = o.close_end = false;
    o.opening_offset = k;
    const FittedPart fp = fit_part(part, o);
    INFO("opening_offset " << k);
    REQUIRE(fp.closure_points == 2);
    const Vec3d c0 = fp.local_to_world.apply(fp.samples[fp.samples.size() - 2].position);
    const Vec3d c1 = fp.local_to_world.apply(fp.samples.back().position);
    CHECK(norm(c0 - (a - axis * (k * R))) < 1e-9);
    CHECK(norm(c1 - (b + axis * (k * R))) < 1e-9);
    // The 0.5 level along the axis, from the tube's middle outwards: at the closure points.
    const Vec3d mid = a + axis * (0.5 * L);
    CHECK(iso_along(fp, mid, axis * -1.0, 0.5 * L + 2 * R) == Approx(0.5 * L + k * R).margin(0.02 * R));
    CHECK(iso_along(fp, mid, axis, 0.5 * L + 2 * R) == Approx(0.5 * L + k * R).margin(0.02 * R));
    // Beyond the support the field is exactly 0; inside, on the axis, above 0.5.
    CHECK(fp.local->eval_d(fp.local_to_world.apply_inverse(b + axis * (3 * R))).value < 0.5);
    CHECK(fp.local->eval_d(fp.local_to_world.apply_inverse(mid)).value > 0.9);
  }
  PartFitOptions o;
  o.closure = PartFitOptions::Closure::joints;
  o.close_start = o.close_end = false;
  MeshPart bad = part;
  bad.openings[1].direction = {0, 0, 0};
  CHECK_THROWS_WITH(fit_part(bad, o),
                    Catch::Contains("pelvis: opening 1") && Catch::Contains("unit direction"));
  o.opening_offset = -0.5;
  CHECK_THROWS_WITH(fit_part(part, o), Catch::Contains("pelvis: opening_offset"));
}

TEST_CASE("fitted primitive and its grid: gradients against central differences", "[fit]") {
  const MeshPart part = sphere_part(1.0, {0, 0, 0}, {0, 0, 1});
  const FittedPart fp = fit_part(part);
  REQUIRE(fp.grid != nullptr);
  CHECK(fp.grid->resolution() == 32);
  test::Rng rng(23);
  const Box3f box = fp.local->support();
  double worst = 0, worst_grid_value = 0, worst_grid_grad = 0, max_grad = 0;
  for (int i = 0; i < 3000; ++i) {
    const Vec3d p{rng.uniform(box.lo.x, box.hi.x), rng.uniform(box.lo.y, box.hi.y),
                  rng.uniform(box.lo.z, box.hi.z)};
    const auto e = fp.local->eval_d(p);
    const Vec3d fd =
        test::central_gradient([&](const Vec3d& q) { return fp.local->eval_d(q).value; }, p, 1e-5);
    worst = std::max(worst, norm(e.gradient - fd));
    max_grad = std::max(max_grad, norm(e.gradient));
    const FieldSample g = fp.grid->eval(test::to_float(p));
    worst_grid_value = std::max(worst_grid_value, std::abs(double(g.value) - e.value));
    worst_grid_grad = std::max(worst_grid_grad, norm(test::to_double(g.gradient) - e.gradient));
  }
  INFO("grid errors: value " << worst_grid_value << ", gradient " << worst_grid_grad << " (max |grad| "
                             << max_grad << ")");
  CHECK(worst <= 1e-6);
  CHECK(worst_grid_value <= 0.02);
  CHECK(worst_grid_grad <= 0.1 * max_grad);
}

TEST_CASE("fitting is deterministic for a seed", "[fit]") {
  const MeshPart part = sphere_part(1.0, {0, 0, 0}, {1, 0, 0});
  PartFitOptions o;
  o.sample_grid = false;
  const FittedPart a = fit_part(part, o), b = fit_part(part, o);
  REQUIRE(a.samples.size() == b.samples.size());
  for (std::size_t i = 0; i < a.samples.size(); ++i) CHECK(a.samples[i].position == b.samples[i].position);
  o.seed = 7;
  const FittedPart c = fit_part(part, o);
  CHECK(!(c.samples[0].position == a.samples[0].position));
}

TEST_CASE("fitting rejects degenerate parts by name, the rest of a rig still fits", "[fit]") {
  MeshPart good = sphere_part(1.0, {0, 0, 0}, {0, 0, 1});
  good.name = "upper_arm";
  MeshPart empty;
  empty.name = "ghost";
  empty.bone_end = {0, 0, 1};
  MeshPart zero = good;
  zero.name = "zero_bone";
  zero.bone_end = zero.bone_start;
  MeshPart nan = good;
  nan.name = "nan_part";
  nan.vertices[5].x = std::numeric_limits<double>::quiet_NaN();
  MeshPart culled = good;  // bone far beyond the mesh: every sample is culled
  culled.name = "culled";
  culled.bone_start = {0, 0, 5};
  culled.bone_end = {0, 0, 6};
  CHECK_THROWS_WITH(fit_part(empty), Catch::Contains("ghost") && Catch::Contains("empty"));
  CHECK_THROWS_WITH(fit_part(zero), Catch::Contains("zero_bone") && Catch::Contains("zero length"));
  CHECK_THROWS_WITH(fit_part(nan), Catch::Contains("nan_part: vertex 5"));
  CHECK_THROWS_WITH(fit_part(culled), Catch::Contains("culled") && Catch::Contains("fewer than 4"));
  MeshPart inward = good;
  inward.name = "inside_out";
  for (auto& t : inward.triangles) std::swap(t[1], t[2]);
  CHECK_THROWS_WITH(fit_part(inward), Catch::Contains("inside_out") && Catch::Contains("oriented inward"));
  PartFitOptions o;
  o.sample_grid = false;
  std::vector<std::string> errors;
  const auto fitted = fit_parts({good, zero, good}, o, &errors);
  CHECK(fitted[0].local != nullptr);
  CHECK(fitted[1].local == nullptr);
  CHECK(fitted[2].local != nullptr);
  CHECK(errors[0].empty());
  CHECK_THAT(errors[1], Catch::Contains("zero_bone"));
}
