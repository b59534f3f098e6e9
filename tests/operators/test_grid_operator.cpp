// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include <cmath>
#include <utility>
#include <vector>

#include "isokit/core/error.h"
#include "isokit/operators/analytic.h"
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
        const double f1 = double(i) / (nf - 1), f2 = double(j) / (nf - 1),
                     d = nd > 1 ? double(k) / (nd - 1) : 0.0;
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

namespace {

/// A random input in [-0.1, 1.1]: often exactly on a node, on 0 or 1, or just beside them.
float random_input(test::Rng& rng, int nodes) {
  switch (rng.integer(0, 4)) {
    case 0:
      return float(rng.integer(0, nodes - 1)) / float(nodes - 1);  // a node (0 and 1 included)
    case 1:
      return float(rng.integer(0, 1)) + float(rng.uniform(-1e-3, 1e-3));  // near an edge
    case 2:
      return float(rng.uniform(-0.1, 1.1));  // clamped when outside
    default:
      return float(rng.uniform(0, 1));
  }
}

}  // namespace

TEST_CASE("grid operator: the direct and padded stencil paths equal the ghosted path bit for bit",
          "[operators][grid]") {
  // Interior stencils are read directly, edge stencils through ghost(); with a padded copy every
  // stencil is read from it. All must give eval_ghosted's bits (also at the edges, on nodes and
  // outside [0, 1]), for small grids where every stencil touches an edge.
  test::Rng rng(22);
  for (const auto& [nd, nf] : {std::pair{9, 17}, std::pair{1, 9}, std::pair{2, 2}, std::pair{3, 3},
                               std::pair{4, 4}, std::pair{16, 128}}) {
    const GridOperator g = sampled(nd, nf);
    const auto v = g.view();
    std::vector<float> padded(v.padded_size());
    v.fill_padded(padded.data());
    auto pv = v;
    pv.padded = padded.data();
    for (int i = 0; i < 20000; ++i) {
      const float f1 = random_input(rng, nf), f2 = random_input(rng, nf), d = random_input(rng, nd);
      const auto ref = v.eval_ghosted(f1, f2, d);
      for (const auto& s : {v.eval(f1, f2, d), pv.eval(f1, f2, d)}) {
        INFO("nd " << nd << " nf " << nf << " f1 " << f1 << " f2 " << f2 << " d " << d);
        REQUIRE(s.g == ref.g);
        REQUIRE(s.dg1 == ref.dg1);
        REQUIRE(s.dg2 == ref.dg2);
      }
    }
    // The padded copy holds ghost() around the grid and the nodes inside.
    for (int k = 0; k < nd; ++k)
      for (int i1 = -1; i1 <= nf; ++i1)
        for (int i2 = -1; i2 <= nf; ++i2)
          REQUIRE(
              padded[(std::size_t(k) * (nf + 2) + std::size_t(i1 + 1)) * (nf + 2) + std::size_t(i2 + 1)] ==
              v.ghost(k, i1, i2));
  }
}

TEST_CASE("grid operator: vectorised and scalar bicubic agree bit for bit, weights", "[operators][grid]") {
  // bicubic (SSE2 on x86 hosts) against bicubic_scalar (the device code) on random stencils,
  // with and without a blend towards a second slice.
  test::Rng rng(23);
  float rows[2][4][6];
  for (int i = 0; i < 20000; ++i) {
    for (auto& slice : rows)
      for (auto& row : slice)
        for (float& x : row) x = float(rng.uniform(-2, 2));
    const float w = rng.integer(0, 1) ? 0.f : float(rng.uniform(0, 1));
    const float t1 = float(rng.uniform(0, 1)), t2 = i % 7 == 0 ? 0.f : float(rng.uniform(0, 1));
    const auto a = operators::bicubic(&rows[0][0][1], 6, 24, w, t1, t2, 127.f);
    const auto b = operators::bicubic_scalar(&rows[0][0][1], 6, 24, w, t1, t2, 127.f);
    REQUIRE(a.g == b.g);
    REQUIRE(a.dg1 == b.dg1);
    REQUIRE(a.dg2 == b.dg2);
  }
  // Catmull-Rom weights: a partition of unity, exact at the cell ends.
  for (int i = 0; i <= 1000; ++i) {
    const float t = float(i) / 1000.f;
    float w[4], dw[4];
    operators::catmull_rom(t, w, dw);
    CHECK(w[0] + w[1] + w[2] + w[3] == Approx(1.0).margin(1e-6));
    CHECK(dw[0] + dw[1] + dw[2] + dw[3] == Approx(0.0).margin(1e-6));
    if (i == 0 || i == 1000) {
      CHECK(w[i == 0 ? 1 : 2] == 1.f);
      CHECK(w[0] == 0.f);
      CHECK(w[3] == 0.f);
    }
  }
}

TEST_CASE("grid operator: the 2013 blend sampled as the paper stores it (128³) follows the analytic blend",
          "[operators][grid]") {
  const GridOperator g = operators::sampled_gradient_blend_2013(128, 128);
  REQUIRE(g.nf() == 128);
  REQUIRE(g.nd() == 128);
  // At the nodes the grid is the analytic value.
  for (int k : {0, 37, 127})
    for (int i : {0, 20, 64, 127})
      for (int j : {0, 51, 100, 127}) {
        const float f1 = float(i) / 127.f, f2 = float(j) / 127.f, d = float(k) / 127.f;
        CHECK(g.view().node(k, i, j) == operators::gradient_blend_2013(f1, f2, d).g);
      }
  // Between the nodes: the blend's derivatives jump where its straight (union) part meets the
  // arc and along the level 0.5 (docs/operators.md); within a cell of those kinks the C¹
  // interpolant rounds them off. Measured 2026-12-02 over 20,000 points: value error at most
  // 1.2e-3, derivative error at most 0.7 (at a kink), above 0.02 at 2.1 % of the points.
  test::Rng rng(11);
  double worst_value = 0, worst_slope = 0;
  int slope_off = 0;
  const int n = 20000;
  for (int s = 0; s < n; ++s) {
    const float f1 = float(rng.uniform(0, 1)), f2 = float(rng.uniform(0, 1)), d = float(rng.uniform(0, 1));
    const operators::OpSample a = operators::gradient_blend_2013(f1, f2, d), b = g.eval(f1, f2, d);
    worst_value = std::max(worst_value, double(std::abs(a.g - b.g)));
    const double slope = std::max(std::abs(a.dg1 - b.dg1), std::abs(a.dg2 - b.dg2));
    worst_slope = std::max(worst_slope, slope);
    slope_off += slope > 0.02 ? 1 : 0;
  }
  INFO("worst value error " << worst_value << ", worst slope error " << worst_slope
                            << ", slopes off by > 0.02: " << slope_off);
  CHECK(worst_value < 2e-3);
  CHECK(worst_slope < 1.0);
  CHECK(slope_off < n * 3 / 100);
  CHECK(g.eval(0.f, 0.f, 0.5f).g == 0.f);  // composable: g(0, 0; d) = 0
}

TEST_CASE("grid operator: sample_operator lays out slices like the generator and refuses bad input",
          "[operators][grid]") {
  const GridOperator g =
      operators::sample_operator([](float f1, float f2, float d) { return f1 + 2 * f2 + 4 * d; }, 3, 2);
  CHECK(g.view().node(0, 1, 2) == Approx(0.5 + 2.0));
  CHECK(g.view().node(1, 2, 0) == Approx(1.0 + 4.0));
  CHECK_THROWS_WITH(operators::sample_operator([](float, float, float) { return 0.f; }, 1, 2),
                    Catch::Contains("nf >= 2"));
  CHECK_THROWS_WITH(
      operators::sample_operator([](float f1, float, float) { return f1 > 0.5f ? NAN : 0.f; }, 4, 2),
      Catch::Contains("not finite"));
}
