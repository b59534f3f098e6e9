// SPDX-License-Identifier: MIT
/// \file
/// Pure spec edits of the studio (no grid, no history): each returns the edited spec, or throws
/// isokit::InputError saying why the edit does not apply. The model validates the result.
#pragma once

#include <vector>

#include "isokit/studio/model.h"

namespace isokit::studio::detail {

/// Index of the keyframe of `curve` within `tolerance` of `d`, or -1.
int keyframe_near(const operators::ProfileCurve& curve, double d, double tolerance);
/// Index of the keyframe of `curve` at `d`: the one within `tolerance`, else a keyframe inserted
/// at `d` with the interpolated points.
int ensure_keyframe(operators::ProfileCurve& curve, double d, double tolerance);

/// Control point `p` moved to `to` at `d` (keyframe semantics of model.h).
OperatorSpec move_point(OperatorSpec spec, const CurvePoint& p, double d, double tolerance, const Point2& to);
/// Point inserted after `segment` at parameter `t` of that segment, in every keyframe.
OperatorSpec insert_point(OperatorSpec spec, int curve, int segment, double t);
/// Point removed from every keyframe (refused below the curve type's minimum).
OperatorSpec remove_point(OperatorSpec spec, const CurvePoint& p);
OperatorSpec insert_keyframe(OperatorSpec spec, int curve, double d, double tolerance);
OperatorSpec remove_keyframe(OperatorSpec spec, int curve, int keyframe);

/// The effective controller knots (the preset's when spec.controller_knots is empty).
std::vector<ControllerKnot> effective_knots(const OperatorSpec& spec);
OperatorSpec insert_knot(OperatorSpec spec, double alpha, double d);
OperatorSpec set_knot(OperatorSpec spec, int i, double alpha, double d);
OperatorSpec remove_knot(OperatorSpec spec, int i);

OperatorSpec append_curve(OperatorSpec spec, CurveKind kind, CurveType type, std::vector<Point2> points);
OperatorSpec remove_curve(OperatorSpec spec, int curve);

/// Slices whose profile differs between `a` and `b` (each curve's kind, type and
/// control_points at the slice's d; all slices when the grid shape or slope differ).
std::vector<int> changed_slices(const OperatorSpec& a, const OperatorSpec& b);

/// Nearest control point of any curve at `d` within `radius`. Points at the same distance (up
/// to 1e-9; e.g. the contact line's ends on the boundary corner at d = 0) are ranked: the
/// `selected` point, then other points of its curve, then boundary curves, then the rest; then
/// the first in curve and point order.
std::optional<CurvePoint> nearest_point(const OperatorSpec& spec, double d, const Point2& p, double radius,
                                        const std::optional<CurvePoint>& selected = std::nullopt);
/// Nearest control-polygon point of any curve at `d` within `radius`.
std::optional<SegmentPick> nearest_segment(const OperatorSpec& spec, double d, const Point2& p,
                                           double radius);

}  // namespace isokit::studio::detail
