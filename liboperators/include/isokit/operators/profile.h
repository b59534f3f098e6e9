// SPDX-License-Identifier: MIT
/// \file
/// The profile of one slice `d`: the spec's curves as polylines, with the distances the
/// biharmonic generator constrains grid nodes from (2014 §4.2).
#pragma once

#include <vector>

#include "isokit/operators/spec.h"

namespace isokit::operators {

struct ProfilePolyline {
  CurveKind kind{CurveKind::kBoundary};
  std::vector<Point2> points;  ///< consecutive duplicates removed; ≥ 2 points
  /// +1 when the left side (of the point order) faces (1, 1), -1 otherwise (boundary curves).
  double side{1.0};
};

class SliceProfile {
 public:
  /// The curves of `spec` at `d`; curves of zero length (e.g. the contact line at d = 0) are
  /// dropped.
  SliceProfile(const OperatorSpec& spec, double d);

  const std::vector<ProfilePolyline>& polylines() const { return polylines_; }
  /// Distance used for constraints: that of the nearest curve, signed for boundary curves
  /// (positive toward (1, 1)) and non-negative for contact curves.
  double constraint_distance(const Point2& p) const;
  /// Unsigned distance to the nearest curve (infinity without curves).
  double distance(const Point2& p) const;
  /// Points along the curves, at most `step` apart.
  std::vector<Point2> samples(double step, bool boundary_only = false) const;

 private:
  std::vector<ProfilePolyline> polylines_;
};

/// Signed distance to an open polyline, positive on the left of the point order (vertex
/// pseudo-normals at interior vertices).
double signed_distance(const std::vector<Point2>& polyline, const Point2& p);

/// True if two non-adjacent segments of the polyline intersect or touch.
bool self_intersects(const std::vector<Point2>& polyline);

}  // namespace isokit::operators
