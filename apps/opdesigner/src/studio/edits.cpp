// SPDX-License-Identifier: MIT
#include "studio/edits.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "isokit/core/error.h"

namespace isokit::studio::detail {

using operators::Keyframe;
using operators::ProfileCurve;

namespace {

Point2 lerp(const Point2& a, const Point2& b, double t) {
  return {a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t};
}

double distance(const Point2& a, const Point2& b) {
  return std::hypot(a[0] - b[0], a[1] - b[1]);
}

ProfileCurve& curve_at(OperatorSpec& spec, int c) {
  require(c >= 0 && c < int(spec.curves.size()), "curve " + std::to_string(c), "does not exist",
          "pick a curve of the spec");
  return spec.curves[static_cast<std::size_t>(c)];
}

void check_point(const ProfileCurve& curve, const CurvePoint& p) {
  const int n = curve.keyframes.empty() ? 0 : int(curve.keyframes[0].points.size());
  require(p.point >= 0 && p.point < n,
          "point " + std::to_string(p.point) + " of curve " + std::to_string(p.curve), "does not exist",
          "pick a control point");
}

std::size_t min_points(CurveType type) {
  return type == CurveType::kBSpline ? 4 : 2;
}

}  // namespace

int keyframe_near(const ProfileCurve& curve, double d, double tolerance) {
  for (std::size_t k = 0; k < curve.keyframes.size(); ++k)
    if (std::abs(curve.keyframes[k].d - d) <= tolerance) return int(k);
  return -1;
}

int ensure_keyframe(ProfileCurve& curve, double d, double tolerance) {
  const int near = keyframe_near(curve, d, tolerance);
  if (near >= 0) return near;
  Keyframe kf{d, curve.control_points(d)};
  const auto at = std::find_if(curve.keyframes.begin(), curve.keyframes.end(),
                               [&](const Keyframe& k) { return k.d > d; });
  const auto index = at - curve.keyframes.begin();
  curve.keyframes.insert(at, std::move(kf));
  return int(index);
}

OperatorSpec move_point(OperatorSpec spec, const CurvePoint& p, double d, double tolerance,
                        const Point2& to) {
  ProfileCurve& curve = curve_at(spec, p.curve);
  check_point(curve, p);
  const int k = ensure_keyframe(curve, d, tolerance);
  curve.keyframes[static_cast<std::size_t>(k)].points[static_cast<std::size_t>(p.point)] = to;
  return spec;
}

OperatorSpec insert_point(OperatorSpec spec, int c, int segment, double t) {
  ProfileCurve& curve = curve_at(spec, c);
  const int n = curve.keyframes.empty() ? 0 : int(curve.keyframes[0].points.size());
  require(segment >= 0 && segment + 1 < n,
          "segment " + std::to_string(segment) + " of curve " + std::to_string(c), "does not exist",
          "pick a segment between two control points");
  require(std::isfinite(t) && t >= 0 && t <= 1, "segment parameter", "must be in [0, 1]",
          "pick a point on the segment");
  for (Keyframe& kf : curve.keyframes) {
    const auto s = static_cast<std::size_t>(segment);
    kf.points.insert(kf.points.begin() + segment + 1, lerp(kf.points[s], kf.points[s + 1], t));
  }
  return spec;
}

OperatorSpec remove_point(OperatorSpec spec, const CurvePoint& p) {
  ProfileCurve& curve = curve_at(spec, p.curve);
  check_point(curve, p);
  const std::size_t minimum = min_points(curve.type);
  require(curve.keyframes[0].points.size() > minimum, "curve " + std::to_string(p.curve),
          "has only " + std::to_string(minimum) + " control points, the minimum for its type",
          "add a point before deleting one, or delete the curve");
  for (Keyframe& kf : curve.keyframes) kf.points.erase(kf.points.begin() + p.point);
  return spec;
}

OperatorSpec insert_keyframe(OperatorSpec spec, int c, double d, double tolerance) {
  ProfileCurve& curve = curve_at(spec, c);
  require(keyframe_near(curve, d, tolerance) < 0, "keyframe at d = " + format_number(d),
          "curve " + std::to_string(c) + " already has a keyframe at this slice", "edit its points instead");
  ensure_keyframe(curve, d, tolerance);
  return spec;
}

OperatorSpec remove_keyframe(OperatorSpec spec, int c, int k) {
  ProfileCurve& curve = curve_at(spec, c);
  require(k >= 0 && k < int(curve.keyframes.size()), "keyframe " + std::to_string(k), "does not exist",
          "pick a keyframe of the curve");
  require(curve.keyframes.size() > 1, "curve " + std::to_string(c), "has a single keyframe",
          "a curve needs at least one keyframe; delete the curve instead");
  curve.keyframes.erase(curve.keyframes.begin() + k);
  return spec;
}

std::vector<ControllerKnot> effective_knots(const OperatorSpec& spec) {
  if (!spec.controller_knots.empty()) return spec.controller_knots;
  return spec.make_controller().knots();
}

OperatorSpec insert_knot(OperatorSpec spec, double alpha, double d) {
  std::vector<ControllerKnot> knots = effective_knots(spec);
  require(std::isfinite(alpha) && alpha > knots.front().alpha && alpha < knots.back().alpha,
          "knot angle " + format_number(alpha), "must lie strictly between 0 and pi",
          "the end knots are fixed; move them instead");
  const auto at =
      std::find_if(knots.begin(), knots.end(), [&](const ControllerKnot& k) { return k.alpha >= alpha; });
  require(at->alpha != alpha, "knot angle " + format_number(alpha), "is already used",
          "move that knot instead");
  knots.insert(at, ControllerKnot{alpha, d});
  spec.controller_knots = std::move(knots);
  return spec;
}

OperatorSpec set_knot(OperatorSpec spec, int i, double alpha, double d) {
  std::vector<ControllerKnot> knots = effective_knots(spec);
  const int n = int(knots.size());
  require(i >= 0 && i < n, "knot " + std::to_string(i), "does not exist", "pick a knot of the controller");
  auto& knot = knots[static_cast<std::size_t>(i)];
  if (i > 0 && i < n - 1) {
    require(std::isfinite(alpha) && alpha > knots[static_cast<std::size_t>(i) - 1].alpha &&
                alpha < knots[static_cast<std::size_t>(i) + 1].alpha,
            "knot " + std::to_string(i) + " angle " + format_number(alpha), "would pass a neighbouring knot",
            "keep knots in angle order");
    knot.alpha = alpha;
  }
  knot.d = d;
  spec.controller_knots = std::move(knots);
  return spec;
}

OperatorSpec remove_knot(OperatorSpec spec, int i) {
  std::vector<ControllerKnot> knots = effective_knots(spec);
  require(i > 0 && i < int(knots.size()) - 1, "knot " + std::to_string(i), "is an end knot or does not exist",
          "the knots at alpha = 0 and pi stay; move them instead");
  knots.erase(knots.begin() + i);
  spec.controller_knots = std::move(knots);
  return spec;
}

OperatorSpec append_curve(OperatorSpec spec, CurveKind kind, CurveType type, std::vector<Point2> points) {
  ProfileCurve curve;
  curve.kind = kind;
  curve.type = type;
  curve.keyframes.push_back(Keyframe{0.0, std::move(points)});
  spec.curves.push_back(std::move(curve));
  return spec;
}

OperatorSpec remove_curve(OperatorSpec spec, int c) {
  curve_at(spec, c);
  spec.curves.erase(spec.curves.begin() + c);
  return spec;
}

std::vector<int> changed_slices(const OperatorSpec& a, const OperatorSpec& b) {
  std::vector<int> out;
  const bool all = a.slices != b.slices || a.resolution != b.resolution ||
                   a.distance_slope != b.distance_slope || a.curves.size() != b.curves.size();
  for (int k = 0; k < b.slices; ++k) {
    const double d = b.slices == 1 ? 0.0 : double(k) / (b.slices - 1);
    bool changed = all;
    for (std::size_t c = 0; c < b.curves.size() && !changed; ++c) {
      const ProfileCurve &x = a.curves[c], &y = b.curves[c];
      changed = x.kind != y.kind || x.type != y.type || x.control_points(d) != y.control_points(d);
    }
    if (changed) out.push_back(k);
  }
  return out;
}

std::optional<CurvePoint> nearest_point(const OperatorSpec& spec, double d, const Point2& p, double radius,
                                        const std::optional<CurvePoint>& selected) {
  constexpr double kTie = 1e-9;
  auto rank = [&](int c, int i) {
    if (selected && selected->curve == c) return selected->point == i ? 0 : 1;
    return spec.curves[static_cast<std::size_t>(c)].kind == CurveKind::kBoundary ? 2 : 3;
  };
  std::optional<CurvePoint> best;
  double best_distance = 0;
  int best_rank = 0;
  for (std::size_t c = 0; c < spec.curves.size(); ++c) {
    const std::vector<Point2> points = spec.curves[c].control_points(d);
    for (std::size_t i = 0; i < points.size(); ++i) {
      const double e = distance(points[i], p);
      if (e > radius) continue;
      const int r = rank(int(c), int(i));
      if (best && !(e < best_distance - kTie) && !(e <= best_distance + kTie && r < best_rank)) continue;
      best = CurvePoint{int(c), int(i)};
      best_distance = e;
      best_rank = r;
    }
  }
  return best;
}

std::optional<SegmentPick> nearest_segment(const OperatorSpec& spec, double d, const Point2& p,
                                           double radius) {
  std::optional<SegmentPick> best;
  double best_distance = radius;
  for (std::size_t c = 0; c < spec.curves.size(); ++c) {
    const std::vector<Point2> points = spec.curves[c].control_points(d);
    for (std::size_t s = 0; s + 1 < points.size(); ++s) {
      const Point2 &a = points[s], &b = points[s + 1];
      const double len2 = (b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]);
      const double t =
          len2 > 0
              ? std::clamp(((p[0] - a[0]) * (b[0] - a[0]) + (p[1] - a[1]) * (b[1] - a[1])) / len2, 0.0, 1.0)
              : 0.0;
      const Point2 q = lerp(a, b, t);
      if (const double e = distance(q, p); e <= best_distance) {
        best_distance = e;
        best = SegmentPick{int(c), int(s), t, q};
      }
    }
  }
  return best;
}

}  // namespace isokit::studio::detail
