// SPDX-License-Identifier: MIT
/// \file
/// Property checks of a generated grid operator, slice by slice (used by `isokit-opdesigner
/// inspect` and the tests).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "isokit/operators/grid_operator.h"
#include "isokit/operators/profile.h"

namespace isokit::operators {

struct SliceReport {
  int slice{0};
  double d{0};
  double boundary_error{0};         ///< max |g - eq. 1| over the four edges
  double axis_slope{0};             ///< max |∂g/∂n| on the axes (one-sided difference), origin excluded
  double iso_to_profile{0};         ///< max distance from a 0.5 crossing on a grid edge to the profile
  double profile_to_iso{0};         ///< max distance from a boundary-curve sample to a 0.5 crossing
  double contact_error{0};          ///< max |g - 0.5| along the contact curves (grid interpolation)
  double contact_length{0};         ///< contact_length(grid, k, 1e-3)
  int monotonicity_violations{0};   ///< node pairs with g decreasing in f1 or f2 (by > 1e-6)
  double monotonicity_max_drop{0};  ///< largest such decrease between neighbouring nodes
  double cell{0};                   ///< grid spacing h
};

/// Checks slice `k` of `grid` against the profile of `spec` at that slice's d.
SliceReport inspect_slice(const OperatorSpec& spec, const GridOperator& grid, int k);

/// A failed check: which one, by how much, and what the designer can do about it.
struct CheckFailure {
  int slice{0};
  double d{0};
  std::string check;   ///< e.g. "boundary conditions (2014 eq. 1)"
  std::string detail;  ///< the measured value against its limit
  std::string fix;     ///< what to change in the spec
  /// One line: "slice K (d = D): CHECK failed: DETAIL; FIX".
  std::string message() const;
};

/// The pass/fail criteria of a slice report (those of `isokit-opdesigner inspect`):
/// boundary error ≤ 1e-5 (2014 eq. 1), and the 0.5 iso-line within one grid cell of the
/// boundary profile both ways (2014 eq. 2: the iso-line *is* the profile). Monotonicity and the
/// contact error are reported by inspect_slice but not judged (the presets' contact valleys have
/// small non-monotone runs; docs/operators.md). Returns the first failed check, or nullopt.
std::optional<CheckFailure> judge_slice(const SliceReport& report);

/// inspect_slice + judge_slice over every slice; the first failure, or nullopt when all pass.
std::optional<CheckFailure> check_operator(const OperatorSpec& spec, const GridOperator& grid);

/// 0.5 crossings of slice k along grid edges (linear interpolation).
std::vector<Point2> iso_crossings(const GridOperator& grid, int k, double level);

/// Length along the diagonal from (.5, .5) of the run where g ≤ 0.5 + tol, g linearly
/// interpolated between the diagonal nodes of slice k (0 when g(.5, .5) > 0.5 + tol).
double contact_length(const GridOperator& grid, int k, double tol = 1e-3);

}  // namespace isokit::operators
