// SPDX-License-Identifier: MIT
#include "isokit/operators/checks.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace isokit::operators {

std::vector<Point2> iso_crossings(const GridOperator& grid, int k, double level) {
  const int n = grid.nf();
  const double h = 1.0 / (n - 1);
  const float* s = grid.slice(k);
  auto g = [&](int i1, int i2) { return double(s[static_cast<std::size_t>(i1) * n + i2]); };
  std::vector<Point2> out;
  auto edge = [&](int a1, int a2, int b1, int b2) {
    const double va = g(a1, a2), vb = g(b1, b2);
    if ((va < level) == (vb < level)) return;
    const double t = (level - va) / (vb - va);
    out.push_back({(a1 + (b1 - a1) * t) * h, (a2 + (b2 - a2) * t) * h});
  };
  for (int i1 = 0; i1 < n; ++i1)
    for (int i2 = 0; i2 < n; ++i2) {
      if (i1 + 1 < n) edge(i1, i2, i1 + 1, i2);
      if (i2 + 1 < n) edge(i1, i2, i1, i2 + 1);
    }
  return out;
}

double contact_length(const GridOperator& grid, int k, double tol) {
  // Diagonal nodes (i, i), linearly interpolated along the diagonal: sub-cell resolution of the
  // contact line's end without the bicubic's overshoot across the V-shaped valley.
  const int n = grid.nf();
  const double h = 1.0 / (n - 1);
  const float* s = grid.slice(k);
  auto diag = [&](double t) {
    const double x = std::clamp(t / h, 0.0, double(n - 1));
    const int i = std::min(int(x), n - 2);
    const double w = x - i;
    const double a = s[static_cast<std::size_t>(i) * n + i],
                 b = s[static_cast<std::size_t>(i + 1) * n + i + 1];
    return a + w * (b - a);
  };
  const double level = 0.5 + tol;
  if (diag(0.5) > level) return 0.0;
  // Walk node by node, then locate the crossing inside the first cell that leaves the run.
  double t = 0.5;
  int i = int(std::floor(0.5 / h)) + 1;
  for (; i < n; ++i) {
    const double ti = i * h;
    if (diag(ti) > level) {
      const double a = diag(t), b = diag(ti);
      return (t + (ti - t) * (level - a) / (b - a) - 0.5) * std::sqrt(2.0);
    }
    t = ti;
  }
  return (1.0 - 0.5) * std::sqrt(2.0);
}

SliceReport inspect_slice(const OperatorSpec& spec, const GridOperator& grid, int k) {
  SliceReport r;
  const int n = grid.nf();
  const double h = 1.0 / (n - 1);
  r.slice = k;
  r.d = grid.slice_d(k);
  r.cell = h;
  const float* s = grid.slice(k);
  auto g = [&](int i1, int i2) { return double(s[static_cast<std::size_t>(i1) * n + i2]); };
  for (int i = 0; i < n; ++i) {
    r.boundary_error = std::max({r.boundary_error, std::abs(g(i, 0) - i * h), std::abs(g(0, i) - i * h),
                                 std::abs(g(i, n - 1) - 1.0), std::abs(g(n - 1, i) - 1.0)});
    // The origin is excluded: there g(f1, 0) = f1 (slope 1 along f1) meets ∂g/∂f1 = 0 on f1 = 0.
    if (i > 0)
      r.axis_slope =
          std::max({r.axis_slope, std::abs(g(1, i) - g(0, i)) / h, std::abs(g(i, 1) - g(i, 0)) / h});
  }
  for (int i1 = 0; i1 < n; ++i1)
    for (int i2 = 0; i2 < n; ++i2) {
      for (const double drop :
           {i1 + 1 < n ? g(i1, i2) - g(i1 + 1, i2) : 0.0, i2 + 1 < n ? g(i1, i2) - g(i1, i2 + 1) : 0.0})
        if (drop > 1e-6) {
          ++r.monotonicity_violations;
          r.monotonicity_max_drop = std::max(r.monotonicity_max_drop, drop);
        }
    }
  const SliceProfile profile(spec, r.d);
  const std::vector<Point2> iso = iso_crossings(grid, k, 0.5);
  for (const auto& p : iso) r.iso_to_profile = std::max(r.iso_to_profile, profile.distance(p));
  for (const auto& q : profile.samples(0.5 * h, true)) {
    double best = std::numeric_limits<double>::infinity();
    for (const auto& p : iso) best = std::min(best, std::hypot(p[0] - q[0], p[1] - q[1]));
    r.profile_to_iso = std::max(r.profile_to_iso, best);
  }
  const GridOperatorView v{grid.slice(k), 1, n};
  for (const auto& pl : profile.polylines()) {
    if (pl.kind != CurveKind::kContact) continue;
    for (std::size_t sidx = 0; sidx + 1 < pl.points.size(); ++sidx) {
      const Point2 &a = pl.points[sidx], &b = pl.points[sidx + 1];
      const int m = std::max(1, int(std::ceil(std::hypot(b[0] - a[0], b[1] - a[1]) / (0.25 * h))));
      for (int j = 0; j <= m; ++j) {
        const double x = a[0] + (b[0] - a[0]) * j / m, y = a[1] + (b[1] - a[1]) * j / m;
        r.contact_error =
            std::max(r.contact_error, std::abs(double(v.eval_slice(0, float(x), float(y)).g) - 0.5));
      }
    }
  }
  r.contact_length = contact_length(grid, k);
  return r;
}

std::string CheckFailure::message() const {
  char head[64];
  std::snprintf(head, sizeof head, "slice %d (d = %.3f): ", slice, d);
  return head + check + " failed: " + detail + "; " + fix;
}

std::optional<CheckFailure> judge_slice(const SliceReport& r) {
  auto fail = [&](std::string check, double value, double limit, std::string unit, std::string fix) {
    char detail[96];
    std::snprintf(detail, sizeof detail, "%.3g %s (limit %.3g)", value, unit.c_str(), limit);
    return CheckFailure{r.slice, r.d, std::move(check), detail, std::move(fix)};
  };
  if (r.boundary_error > 1e-5)
    return fail("boundary conditions (2014 eq. 1)", r.boundary_error, 1e-5, "max |g - eq. 1| on the edges",
                "keep every profile curve off the square's edges (f1, f2 in (0, 1))");
  if (r.iso_to_profile > r.cell)
    return fail(
        "0.5 iso-line against the profile", r.iso_to_profile / r.cell, 1.0,
        "cells from a 0.5 crossing to the profile",
        "the operator has a 0.5 iso-line the profile does not ask for: make the boundary curve run from the "
        "f1 = 0 side to the f2 = 0 side without folding, or raise the resolution");
  if (r.profile_to_iso > r.cell)
    return fail("profile against the 0.5 iso-line", r.profile_to_iso / r.cell, 1.0,
                "cells from the boundary profile to the nearest 0.5 crossing",
                "the boundary curve is not reproduced: separate curves closer than two cells, or raise the "
                "resolution");
  return std::nullopt;
}

std::optional<CheckFailure> check_operator(const OperatorSpec& spec, const GridOperator& grid) {
  for (int k = 0; k < grid.nd(); ++k)
    if (auto f = judge_slice(inspect_slice(spec, grid, k))) return f;
  return std::nullopt;
}

}  // namespace isokit::operators
