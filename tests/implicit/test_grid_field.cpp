// SPDX-License-Identifier: MIT
// The grid field against the analytic field it samples: measured error bounds at 32^3,
// second-order convergence, exactness at nodes and outside the box, and bad input.
#include <catch2/catch.hpp>

#include <algorithm>
#include <memory>

#include "isokit/core/error.h"
#include "isokit/implicit/grid_field.h"
#include "isokit/implicit/primitives.h"
#include "test_util.h"

using namespace isokit;
using namespace isokit::implicit;

namespace {

struct Errors {
  double value = 0, gradient = 0;  // max absolute errors over the samples
};

Errors measure(const Field& exact, const GridField& grid, int samples, std::uint32_t seed) {
  test::Rng rng(seed);
  const Box3f b = grid.support();
  Errors e;
  for (int i = 0; i < samples; ++i) {
    const Vec3f p{float(rng.uniform(b.lo.x, b.hi.x)), float(rng.uniform(b.lo.y, b.hi.y)),
                  float(rng.uniform(b.lo.z, b.hi.z))};
    const FieldSample a = exact.eval(p), g = grid.eval(p);
    e.value = std::max(e.value, double(std::abs(a.value - g.value)));
    e.gradient = std::max(e.gradient, double(norm(a.gradient - g.gradient)));
  }
  return e;
}

}  // namespace

// Error bounds proved here at the paper's 32^3, for a limb-like capsule (length 1, radius 0.25,
// support width 0.25, so |∇f| <= 15/(16 * 0.25) = 3.75; grid spacing 1/31 across, 2/31 along):
// value error <= 0.02 (2% of the field range) and gradient error <= 0.25 (6.7% of the largest
// gradient). Measured: 0.0146 and 0.214 over 200k random points (the worst cells straddle the
// steepest part of t_r, |t_r''| <= 1.44 / r^2). docs/implicit.md records these numbers.
TEST_CASE("grid field at 32^3 matches the capsule it samples within the stated bounds", "[implicit][grid]") {
  const CapsuleField capsule({0, 0, 0}, {0, 0, 1}, 0.25f, 0.25f);
  const GridField grid(capsule);
  REQUIRE(grid.resolution() == 32);
  const Errors e = measure(capsule, grid, 200000, 31);
  WARN("32^3 capsule: max value error " << e.value << ", max gradient error " << e.gradient);
  CHECK(e.value <= 0.02);
  CHECK(e.gradient <= 0.25);
}

TEST_CASE("grid field errors fall as h^2 (trilinear interpolation)", "[implicit][grid]") {
  const SphereField sphere({0.1f, -0.2f, 0.3f}, 0.7f, 0.5f);
  Errors prev;
  for (int n : {16, 32, 64}) {
    const GridField grid(sphere, Box3f{}, GridFieldOptions{n, 64});
    const Errors e = measure(sphere, grid, 50000, 32);
    if (n > 16) {
      INFO("resolution " << n << ": value " << e.value << " (was " << prev.value << "), gradient "
                         << e.gradient << " (was " << prev.gradient << ")");
      CHECK(prev.value / e.value > 3.0);
      CHECK(prev.gradient / e.gradient > 3.0);
    }
    prev = e;
  }
}

TEST_CASE("grid field is exact at nodes and exactly 0 outside its box", "[implicit][grid]") {
  const CapsuleField capsule({-0.3f, 0.1f, 0}, {0.4f, 0.2f, 0.5f}, 0.3f);
  const GridField grid(capsule, Box3f{}, GridFieldOptions{17, 0});
  const Box3f b = grid.support();
  const Vec3f step = b.size() / 16.f;
  for (int k = 0; k < 17; k += 3)
    for (int j = 0; j < 17; j += 5)
      for (int i = 0; i < 17; i += 2) {
        const Vec3f p{b.lo.x + step.x * float(i), b.lo.y + step.y * float(j), b.lo.z + step.z * float(k)};
        // Inside the box, a node evaluates to its stored sample (up to the node position
        // rounding of lo + i * step, and the storage's quantisation).
        CHECK(grid.eval(p).value ==
              Approx(capsule.eval(p).value).margin(1e-5 + grid.quantisation_bound()[0]));
      }
  test::Rng rng(33);
  for (int i = 0; i < 2000; ++i) {
    const Vec3f p = test::to_float(rng.vec(-3, 3));
    if (b.contains(p)) continue;
    const FieldSample s = grid.eval(p);
    CHECK(s.value == 0.f);
    CHECK(s.gradient == Vec3f{});
  }
}

TEST_CASE("grid sampling does not depend on the grain size", "[implicit][grid]") {
  const SphereField sphere({0, 0, 0}, 1.f);
  const GridField serial(sphere, Box3f{}, GridFieldOptions{24, 0});
  const GridField parallel(sphere, Box3f{}, GridFieldOptions{24, 3});
  CHECK(serial.nodes() == parallel.nodes());
}

TEST_CASE("grid field rejects bad input with a named error", "[implicit][grid][errors]") {
  const SphereField sphere({0, 0, 0}, 1.f);
  CHECK_THROWS_WITH(GridField(sphere, Box3f{}, GridFieldOptions{1}), Catch::Contains("resolution"));
  CHECK_THROWS_WITH(GridField(sphere, Box3f{}, GridFieldOptions{-5}), Catch::Contains("resolution"));
  CHECK_THROWS_WITH(GridField(sphere, Box3f{}, GridFieldOptions{100000}), Catch::Contains("resolution"));
  // A flat box (zero extent on one axis) and a non-finite box.
  CHECK_THROWS_WITH(GridField(sphere, Box3f{{-3, -3, 0}, {3, 3, 0}}), Catch::Contains("box"));
  CHECK_THROWS_WITH(GridField(sphere, Box3f{{-3, -3, -3}, {3, INFINITY, 3}}), Catch::Contains("not finite"));
  CHECK_THROWS_WITH(GridField(sphere, Box3f{{-3, -3, -3}, {3, std::nanf(""), 3}}), Catch::Contains("box"));
  // A box that cuts the support would leave a discontinuity at its faces.
  CHECK_THROWS_WITH(GridField(sphere, Box3f{{-1, -1, -1}, {1, 1, 1}}), Catch::Contains("does not contain"));
  CHECK_NOTHROW(GridField(sphere, Box3f{{-3, -3, -3}, {3, 3, 3}}, GridFieldOptions{8}));
}
