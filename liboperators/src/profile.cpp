// SPDX-License-Identifier: MIT
#include "isokit/operators/profile.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace isokit::operators {
namespace {

double cross(const Point2& a, const Point2& b, const Point2& c) {  // (b - a) x (c - a)
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

double seg_param(const Point2& a, const Point2& b, const Point2& p) {
  const double ex = b[0] - a[0], ey = b[1] - a[1];
  const double l2 = ex * ex + ey * ey;
  if (l2 <= 0) return 0;
  return std::clamp(((p[0] - a[0]) * ex + (p[1] - a[1]) * ey) / l2, 0.0, 1.0);
}

double dist2_at(const Point2& a, const Point2& b, double t, const Point2& p) {
  const double x = a[0] + (b[0] - a[0]) * t - p[0], y = a[1] + (b[1] - a[1]) * t - p[1];
  return x * x + y * y;
}

/// Closed-segment intersection test (touching counts).
bool segments_intersect(const Point2& a, const Point2& b, const Point2& c, const Point2& d) {
  const double d1 = cross(c, d, a), d2 = cross(c, d, b), d3 = cross(a, b, c), d4 = cross(a, b, d);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
  auto on = [](const Point2& p, const Point2& q, const Point2& r, double cr) {
    return cr == 0 && std::min(p[0], q[0]) <= r[0] && r[0] <= std::max(p[0], q[0]) &&
           std::min(p[1], q[1]) <= r[1] && r[1] <= std::max(p[1], q[1]);
  };
  return on(c, d, a, d1) || on(c, d, b, d2) || on(a, b, c, d3) || on(a, b, d, d4);
}

std::vector<Point2> dedup(const std::vector<Point2>& in) {
  std::vector<Point2> out;
  for (const auto& p : in)
    if (out.empty() || std::hypot(p[0] - out.back()[0], p[1] - out.back()[1]) > 1e-12) out.push_back(p);
  return out;
}

}  // namespace

double signed_distance(const std::vector<Point2>& pl, const Point2& p) {
  double best = std::numeric_limits<double>::infinity(), best_t = 0;
  std::size_t best_s = 0;
  for (std::size_t s = 0; s + 1 < pl.size(); ++s) {
    const double t = seg_param(pl[s], pl[s + 1], p);
    const double d2 = dist2_at(pl[s], pl[s + 1], t, p);
    if (d2 < best) best = d2, best_s = s, best_t = t;
  }
  const double dist = std::sqrt(best);
  if (dist == 0) return 0;
  // Side: the segment's left normal, or the vertex pseudo-normal at a shared vertex.
  auto left_normal = [&](std::size_t s) {
    const double ex = pl[s + 1][0] - pl[s][0], ey = pl[s + 1][1] - pl[s][1];
    const double l = std::hypot(ex, ey);
    return Point2{-ey / l, ex / l};
  };
  std::size_t vertex = pl.size();
  if (best_t <= 0 && best_s > 0) vertex = best_s;
  if (best_t >= 1 && best_s + 2 < pl.size()) vertex = best_s + 1;
  double side;
  if (vertex < pl.size()) {
    const Point2 n0 = left_normal(vertex - 1), n1 = left_normal(vertex);
    side = (p[0] - pl[vertex][0]) * (n0[0] + n1[0]) + (p[1] - pl[vertex][1]) * (n0[1] + n1[1]);
  } else {
    side = cross(pl[best_s], pl[best_s + 1], p);
  }
  return side >= 0 ? dist : -dist;
}

bool self_intersects(const std::vector<Point2>& raw) {
  const std::vector<Point2> pl = dedup(raw);
  const std::size_t n = pl.size();
  for (std::size_t i = 0; i + 1 < n; ++i)
    for (std::size_t j = i + 2; j + 1 < n; ++j)
      if (segments_intersect(pl[i], pl[i + 1], pl[j], pl[j + 1])) return true;
  // Adjacent segments folding back onto each other (overlap beyond the shared vertex).
  for (std::size_t i = 0; i + 2 < n; ++i) {
    const Point2 &a = pl[i], &b = pl[i + 1], &c = pl[i + 2];
    if (cross(a, b, c) == 0 && (c[0] - b[0]) * (a[0] - b[0]) + (c[1] - b[1]) * (a[1] - b[1]) > 0) return true;
  }
  return false;
}

SliceProfile::SliceProfile(const OperatorSpec& spec, double d) {
  for (const auto& curve : spec.curves) {
    ProfilePolyline pl{curve.kind, dedup(curve.polyline(d)), 1.0};
    if (pl.points.size() < 2) continue;  // zero length (e.g. the contact line at d = 0)
    if (pl.kind == CurveKind::kBoundary && signed_distance(pl.points, {1.0, 1.0}) < 0) pl.side = -1.0;
    polylines_.push_back(std::move(pl));
  }
}

double SliceProfile::constraint_distance(const Point2& p) const {
  double best = std::numeric_limits<double>::infinity(), value = best;
  for (const auto& pl : polylines_) {
    const double sd = signed_distance(pl.points, p);
    if (std::abs(sd) < best) {
      best = std::abs(sd);
      value = pl.kind == CurveKind::kBoundary ? pl.side * sd : std::abs(sd);
    }
  }
  return value;
}

double SliceProfile::distance(const Point2& p) const {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& pl : polylines_)
    for (std::size_t s = 0; s + 1 < pl.points.size(); ++s) {
      const double t = seg_param(pl.points[s], pl.points[s + 1], p);
      best = std::min(best, dist2_at(pl.points[s], pl.points[s + 1], t, p));
    }
  return std::sqrt(best);
}

std::vector<Point2> SliceProfile::samples(double step, bool boundary_only) const {
  std::vector<Point2> out;
  for (const auto& pl : polylines_) {
    if (boundary_only && pl.kind != CurveKind::kBoundary) continue;
    for (std::size_t s = 0; s + 1 < pl.points.size(); ++s) {
      const Point2 &a = pl.points[s], &b = pl.points[s + 1];
      const int n = std::max(1, static_cast<int>(std::ceil(std::hypot(b[0] - a[0], b[1] - a[1]) / step)));
      for (int i = 0; i < n; ++i) out.push_back({a[0] + (b[0] - a[0]) * i / n, a[1] + (b[1] - a[1]) * i / n});
    }
    out.push_back(pl.points.back());
  }
  return out;
}

}  // namespace isokit::operators
