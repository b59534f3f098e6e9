// SPDX-License-Identifier: MIT
/// \file
/// Property checks of a generated grid operator, slice by slice (used by `isokit-opdesigner
/// inspect` and the tests).
#pragma once

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

/// 0.5 crossings of slice k along grid edges (linear interpolation).
std::vector<Point2> iso_crossings(const GridOperator& grid, int k, double level);

/// Length along the diagonal from (.5, .5) of the run where g ≤ 0.5 + tol, g linearly
/// interpolated between the diagonal nodes of slice k (0 when g(.5, .5) > 0.5 + tol).
double contact_length(const GridOperator& grid, int k, double tol = 1e-3);

}  // namespace isokit::operators
