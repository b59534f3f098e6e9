// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include <cmath>
#include <functional>

#include "isokit/operators/analytic.h"
#include "test_util.h"

using namespace isokit;
using operators::OpSample;

namespace {

/// Checks ∂g/∂f1, ∂g/∂f2 against central differences at random points. Points where the two
/// step sizes disagree (a kink of the operator within the stencil) are skipped; at least
/// `min_checked` of the points must be checked.
void check_derivatives(const std::function<OpSample(float, float)>& op, std::uint32_t seed,
                       double min_checked) {
  test::Rng rng(seed);
  int checked = 0;
  const int total = 3000;
  for (int i = 0; i < total; ++i) {
    const float f1 = float(rng.uniform(0.01, 0.99)), f2 = float(rng.uniform(0.01, 0.99));
    const OpSample s = op(f1, f2);
    auto fd = [&](int axis, float h) {
      const OpSample hi = axis == 0 ? op(f1 + h, f2) : op(f1, f2 + h);
      const OpSample lo = axis == 0 ? op(f1 - h, f2) : op(f1, f2 - h);
      return (double(hi.g) - double(lo.g)) / (2.0 * h);
    };
    const double a1 = fd(0, 2e-3f), b1 = fd(0, 1e-3f), a2 = fd(1, 2e-3f), b2 = fd(1, 1e-3f);
    if (std::abs(a1 - b1) > 2e-3 || std::abs(a2 - b2) > 2e-3) continue;  // kink inside the stencil
    // A kink can also hide from central differences: compare one-sided ones.
    const float h = 1e-3f;
    const double fw1 = (double(op(f1 + h, f2).g) - s.g) / h, bw1 = (double(s.g) - op(f1 - h, f2).g) / h;
    const double fw2 = (double(op(f1, f2 + h).g) - s.g) / h, bw2 = (double(s.g) - op(f1, f2 - h).g) / h;
    if (std::abs(fw1 - bw1) > 1e-2 || std::abs(fw2 - bw2) > 1e-2) continue;
    ++checked;
    CHECK(s.dg1 == Approx(b1).margin(5e-3));
    CHECK(s.dg2 == Approx(b2).margin(5e-3));
  }
  CHECK(checked >= min_checked * total);
}

}  // namespace

TEST_CASE("sum blend: value, derivatives, clamping", "[operators][analytic]") {
  check_derivatives(operators::sum_blend, 11, 0.95);
  CHECK(operators::sum_blend(0.3f, 0.4f).g == Approx(0.7f));
  CHECK(operators::sum_blend(0.8f, 0.4f).g == 1.f);
}

TEST_CASE("clean union: union on and inside the surface, rounded outside, boundary properties",
          "[operators][analytic]") {
  check_derivatives(operators::clean_union, 12, 0.9);
  test::Rng rng(5);
  int rounded = 0;
  for (int i = 0; i < 2000; ++i) {
    const float f1 = float(rng.uniform(0, 1)), f2 = float(rng.uniform(0, 1));
    const OpSample s = operators::clean_union(f1, f2);
    const float m = std::max(f1, f2);
    CHECK(s.g >= m - 1e-6f);                   // never below the union
    if (m >= 0.5f) CHECK(s.g == m);            // exact union on the 0.5 level and inside
    if (m < 0.5f) CHECK(s.g <= 0.5f + 1e-5f);  // the 0.5 surface is the union's surface
    if (s.g > m + 1e-4f) ++rounded;
  }
  CHECK(rounded > 100);  // the outside iso-curves really are blended
  for (float f : {0.f, 0.1f, 0.3f, 0.5f, 0.8f, 1.f}) {
    CHECK(operators::clean_union(f, 0.f).g == Approx(f));
    CHECK(operators::clean_union(0.f, f).g == Approx(f));
    CHECK(operators::clean_union(1.f, f).g == Approx(1.f));
  }
}

TEST_CASE("2013 gradient-based blend (Appendix A): derivatives, union limits, continuity",
          "[operators][analytic]") {
  for (float d : {0.f, 0.3f, 0.7f, 1.f}) {
    INFO("d = " << d);
    check_derivatives([d](float a, float b) { return operators::gradient_blend_2013(a, b, d); }, 13, 0.85);
  }
  test::Rng rng(6);
  for (int i = 0; i < 2000; ++i) {
    const float f1 = float(rng.uniform(0, 1)), f2 = float(rng.uniform(0, 1));
    const float m = std::max(f1, f2);
    // d = 0 is θ = π/4: the union everywhere.
    CHECK(operators::gradient_blend_2013(f1, f2, 0.f).g == Approx(m).margin(1e-5));
    const OpSample s = operators::gradient_blend_2013(f1, f2, 1.f);
    CHECK(s.g >= m - 1e-5f);
    if (m > 0.7f) CHECK(s.g == m);  // union beyond 0.7
    // Continuity across the k_θ branch switch at C = 0.5: small moves give small changes.
    const OpSample t = operators::gradient_blend_2013(f1 + 1e-4f, f2, 1.f);
    CHECK(std::abs(t.g - s.g) < 2e-3f);
  }
  // Full blend of two equal outside values: the circle arc centred at the origin (θ = 0).
  CHECK(operators::gradient_blend_2013(0.3f, 0.3f, 1.f).g == Approx(0.3f * std::sqrt(2.f)).margin(1e-4));
  // Inside, the blend decreases to the union at 0.7 (2013 Appendix A).
  const float g55 = operators::gradient_blend_2013(0.55f, 0.55f, 1.f).g;
  const float g68 = operators::gradient_blend_2013(0.68f, 0.68f, 1.f).g;
  CHECK(g55 - 0.55f > g68 - 0.68f);
  CHECK(g68 - 0.68f > 0.f);
}
