// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include <cmath>

#include "isokit/core/error.h"
#include "isokit/operators/biharmonic.h"
#include "isokit/operators/grid_operator.h"
#include "test_util.h"

using namespace isokit;
using operators::GridOperator;

namespace {

/// A smooth synthetic operator sampled on a grid.
GridOperator sampled(int nd, int nf) {
  std::vector<float> v(static_cast<std::size_t>(nd) * nf * nf);
  for (int k = 0; k < nd; ++k)
    for (int i = 0; i < nf; ++i)
      for (int j = 0; j < nf; ++j) {
        const double f1 = double(i) / (nf - 1), f2 = double(j) / (nf - 1), d = double(k) / (nd - 1);
        v[(static_cast<std::size_t>(k) * nf + i) * nf + j] =
            float(0.3 * std::sin(2 * f1 + d) + f2 * f2 * (1 + 0.5 * d) + 0.2 * f1 * f2);
      }
  return GridOperator(nd, nf, std::move(v));
}

}  // namespace

TEST_CASE("grid operator: interpolates nodes, derivatives = central differences at nodes",
          "[operators][grid]") {
  const GridOperator g = sampled(9, 17);
  const auto v = g.view();
  const int n = g.nf();
  const double h = 1.0 / (n - 1);
  for (int k = 0; k < g.nd(); ++k)
    for (int i = 1; i < n - 1; ++i)
      for (int j = 1; j < n - 1; ++j) {
        const auto s = v.eval(float(i * h), float(j * h), float(g.slice_d(k)));
        CHECK(s.g == Approx(v.node(k, i, j)).margin(1e-5));
        CHECK(s.dg1 == Approx((v.node(k, i + 1, j) - v.node(k, i - 1, j)) / (2 * h)).margin(1e-3));
        CHECK(s.dg2 == Approx((v.node(k, i, j + 1) - v.node(k, i, j - 1)) / (2 * h)).margin(1e-3));
      }
}

TEST_CASE("grid operator: derivatives agree with finite differences and are continuous across cells",
          "[operators][grid]") {
  // On the synthetic grid and on a generated contact operator.
  const GridOperator synth = sampled(9, 17);
  const GridOperator gen = operators::generate_operator(operators::preset_spec("contact", 32));
  for (const GridOperator* g : {&synth, &gen}) {
    const auto v = g->view();
    test::Rng rng(21);
    for (int i = 0; i < 3000; ++i) {
      const float f1 = float(rng.uniform(0.002, 0.998)), f2 = float(rng.uniform(0.002, 0.998));
      const float d = float(rng.uniform(0, 1));
      const auto s = v.eval(f1, f2, d);
      const float e = 1e-3f;
      const double fd1 = (double(v.eval(f1 + e, f2, d).g) - v.eval(f1 - e, f2, d).g) / (2 * e);
      const double fd2 = (double(v.eval(f1, f2 + e, d).g) - v.eval(f1, f2 - e, d).g) / (2 * e);
      // Error of a central difference of a C1 piecewise cubic: e · (jump of g'') / 2 at worst.
      const double tol = g == &synth ? 2e-3 : 0.05;
      CHECK(s.dg1 == Approx(fd1).margin(tol));
      CHECK(s.dg2 == Approx(fd2).margin(tol));
    }
    // C1 across cell boundaries: the derivative just left and right of a node line agree.
    const int n = g->nf();
    for (int i = 1; i < n - 1; ++i) {
      const float x = float(i) / float(n - 1), y = float(rng.uniform(0, 1)), d = float(rng.uniform(0, 1));
      const auto l = v.eval(x - 1e-5f, y, d), r = v.eval(x + 1e-5f, y, d);
      CHECK(l.dg1 == Approx(r.dg1).margin(5e-3));
      CHECK(l.dg2 == Approx(r.dg2).margin(5e-3));
      const auto lo = v.eval(y, x - 1e-5f, d), hi = v.eval(y, x + 1e-5f, d);
      CHECK(lo.dg2 == Approx(hi.dg2).margin(5e-3));
    }
  }
}

TEST_CASE("grid operator: clamps inputs, rejects bad shapes", "[operators][grid]") {
  const GridOperator g = sampled(9, 17);
  CHECK(g.eval(-1.f, 0.5f, 0.5f).g == g.eval(0.f, 0.5f, 0.5f).g);
  CHECK(g.eval(0.5f, 2.f, 3.f).g == g.eval(0.5f, 1.f, 1.f).g);
  CHECK_THROWS_AS(GridOperator(2, 4, std::vector<float>(5)), InputError);
  CHECK_THROWS_AS(GridOperator(1, 1, std::vector<float>(1)), InputError);
}
