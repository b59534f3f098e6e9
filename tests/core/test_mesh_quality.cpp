// SPDX-License-Identifier: MIT
// isokit/core/mesh_quality.h: the triangle normal, the inverted-triangle test and the
// bounding-box diagonal, in float and double, checked on properties over random inputs.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "isokit/core/mesh_quality.h"
#include "test_util.h"

using namespace isokit;

namespace {

Vec3f to_float(const Vec3d& v) {
  return {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)};
}

}  // namespace

TEST_CASE("triangle normal: orthogonal to the edges, twice the area long, outward when counter-clockwise",
          "[core]") {
  CHECK(triangle_normal(Vec3d{0, 0, 0}, Vec3d{1, 0, 0}, Vec3d{0, 1, 0}) == Vec3d{0, 0, 1});
  CHECK(triangle_normal(Vec3d{0, 0, 0}, Vec3d{0, 1, 0}, Vec3d{1, 0, 0}) == Vec3d{0, 0, -1});
  test::Rng rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3d a = rng.vec(-2, 2), b = rng.vec(-2, 2), c = rng.vec(-2, 2);
    const Vec3d n = triangle_normal(a, b, c);
    CHECK(std::abs(dot(n, b - a)) < 1e-12);
    CHECK(std::abs(dot(n, c - a)) < 1e-12);
    // Heron: the area from the edge lengths.
    const double x = norm(b - a), y = norm(c - b), z = norm(a - c), s = (x + y + z) / 2;
    const double area = std::sqrt(std::max(0.0, s * (s - x) * (s - y) * (s - z)));
    CHECK(norm(n) == Approx(2 * area).margin(1e-9));
    // The same triangle from another corner has the same normal; the reversed one the opposite.
    CHECK(norm(triangle_normal(b, c, a) - n) < 1e-12);
    CHECK(norm(triangle_normal(a, c, b) + n) < 1e-12);
    // Float agrees with double within float rounding.
    const Vec3f nf = triangle_normal(to_float(a), to_float(b), to_float(c));
    CHECK(norm(Vec3d{nf.x, nf.y, nf.z} - n) < 1e-5 * (1 + norm(n)));
  }
}

TEST_CASE("inverted triangle: the normal along +grad f at the centroid, zero gradient never", "[core]") {
  // A sphere field: gradients point inward, so an outward (counter-clockwise) triangle is fine.
  auto inward = [](const Vec3d& p) { return p * -1.0; };
  test::Rng rng(11);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3d u = rng.unit();
    Vec3d t = cross(u, std::abs(u.x) < 0.9 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0});
    t = t / norm(t);
    const Vec3d w = cross(u, t);
    const double h = rng.uniform(0.01, 0.2);
    // Counter-clockwise seen from outside (around +u).
    const Vec3d a = u + t * h, b = u + w * h, c = u - t * h;
    const Vec3d g = inward(triangle_centroid(a, b, c));
    CHECK_FALSE(is_inverted(triangle_normal(a, b, c), g));
    CHECK(is_inverted(triangle_normal(a, c, b), g));
    CHECK_FALSE(is_inverted(triangle_normal(a, c, b), Vec3d{}));
    const Vec3f af = to_float(a), bf = to_float(b), cf = to_float(c), gf = to_float(g);
    CHECK_FALSE(is_inverted(triangle_normal(af, bf, cf), gf));
    CHECK(is_inverted(triangle_normal(af, cf, bf), gf));
  }
  CHECK(triangle_centroid(Vec3d{0, 0, 0}, Vec3d{3, 0, 0}, Vec3d{0, 3, 6}) == Vec3d{1, 1, 2});
}

TEST_CASE("bounding-box diagonal: 0 without extent, the formula written out bit for bit", "[core]") {
  CHECK(bbox_diagonal<double>(nullptr, 0) == 0.0);
  const Vec3f one{1, 2, 3};
  CHECK(bbox_diagonal(&one, 1) == 0.f);
  const std::vector<Vec3d> corners{{-1, 0, 2}, {1, 2, 3}, {0, 1, 2.5}};
  CHECK(bbox_diagonal(corners.data(), corners.size()) == Approx(std::sqrt(4.0 + 4.0 + 1.0)));
  test::Rng rng(3);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<Vec3f> pts(static_cast<std::size_t>(rng.integer(1, 40)));
    for (Vec3f& p : pts) p = to_float(rng.vec(-10, 10));
    Vec3f lo = pts[0], hi = pts[0];
    for (const Vec3f& p : pts) {
      lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
      hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
    const float dx = hi.x - lo.x, dy = hi.y - lo.y, dz = hi.z - lo.z;
    const float expected = std::sqrt((dx * dx + dy * dy) + dz * dz);
    CHECK(bbox_diagonal(pts.data(), pts.size()) == expected);
    // The accessor form (points in any layout, here widened to double) computes in double.
    const double wide = bbox_diagonal<double>(pts.size(), [&](std::size_t k) {
      return Vec3d{pts[k].x, pts[k].y, pts[k].z};
    });
    const double ex = double(hi.x) - lo.x, ey = double(hi.y) - lo.y, ez = double(hi.z) - lo.z;
    CHECK(wide == std::sqrt((ex * ex + ey * ey) + ez * ez));
    CHECK(wide == Approx(expected).epsilon(1e-6));
  }
}
