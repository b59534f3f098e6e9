// SPDX-License-Identifier: MIT
// Properties of the 2013 compact-support remap t_r (Implicit Skinning §4.1).
#include <catch2/catch.hpp>

#include "isokit/implicit/field_math.h"
#include "test_util.h"

using namespace isokit;
using implicit::remap_tr;

namespace {
double tr(double x, double r) {
  double d;
  return remap_tr(x, r, &d);
}
double dtr(double x, double r) {
  double d;
  remap_tr(x, r, &d);
  return d;
}
}  // namespace

TEST_CASE("t_r hits its end and mid values with zero end slopes", "[implicit][remap]") {
  for (double r : {1e-3, 0.05, 0.3, 1.0, 7.5, 250.0}) {
    CHECK(tr(-r, r) == 1.0);
    CHECK(tr(r, r) == 0.0);
    CHECK(tr(0.0, r) == 0.5);
    CHECK(dtr(-r, r) == 0.0);
    CHECK(dtr(r, r) == 0.0);
    CHECK(tr(-2 * r, r) == 1.0);
    CHECK(tr(3 * r, r) == 0.0);
    // Continuity of value and slope across the support border, from inside the interval.
    const double e = 1e-6 * r;
    CHECK(tr(-r + e, r) == Approx(1.0).margin(1e-12));
    CHECK(tr(r - e, r) == Approx(0.0).margin(1e-12));
    CHECK(std::abs(dtr(r - e, r)) < 1e-9 / r);
    CHECK(std::abs(dtr(-r + e, r)) < 1e-9 / r);
    // Mid-slope: -15 / (16 r).
    CHECK(dtr(0.0, r) == Approx(-15.0 / (16.0 * r)).epsilon(1e-14));
  }
}

TEST_CASE("t_r' agrees with central differences, t_r is decreasing and in [0, 1]", "[implicit][remap]") {
  test::Rng rng(11);
  for (int i = 0; i < 5000; ++i) {
    const double r = rng.uniform(0.01, 10.0);
    const double x = rng.uniform(-1.5 * r, 1.5 * r);
    const double h = 1e-6 * r;
    const double fd = (tr(x + h, r) - tr(x - h, r)) / (2 * h);
    CHECK(dtr(x, r) == Approx(fd).margin(1e-7 / r));
    CHECK(dtr(x, r) <= 0.0);
    CHECK(tr(x, r) >= 0.0);
    CHECK(tr(x, r) <= 1.0);
    // Symmetry: t_r(-x) = 1 - t_r(x).
    CHECK(tr(-x, r) == Approx(1.0 - tr(x, r)).margin(1e-14));
  }
}

TEST_CASE("float t_r matches double t_r", "[implicit][remap]") {
  test::Rng rng(12);
  for (int i = 0; i < 5000; ++i) {
    const double r = rng.uniform(0.01, 10.0), x = rng.uniform(-1.2 * r, 1.2 * r);
    float df;
    const float vf = remap_tr(float(x), float(r), &df);
    CHECK(vf == Approx(tr(x, r)).margin(2e-6));
    CHECK(df == Approx(dtr(x, r)).margin(2e-6 / r));
  }
}
