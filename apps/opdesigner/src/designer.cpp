// SPDX-License-Identifier: MIT
#include "isokit/opdesigner/designer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "isokit/core/error.h"
#include "isokit/core/math.h"
#include "isokit/operators/profile.h"
#include "isokit/plot/figure.h"

namespace isokit::opdesigner {

using operators::StoredOperator;
using plot::Point2;

namespace {

std::string fmt(double v, int digits = 3) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}

struct Field2 {
  double value{0};
  double gx{0}, gy{0};
};

/// Capsule field around segment a-b: (1 - (r/R)²)³ for r < R, with 0.5 at r = radius.
Field2 capsule(const Point2& p, const Point2& a, const Point2& b, double radius) {
  const double R = radius / std::sqrt(1.0 - std::cbrt(0.5));
  const double ex = b[0] - a[0], ey = b[1] - a[1];
  const double t = std::clamp(((p[0] - a[0]) * ex + (p[1] - a[1]) * ey) / (ex * ex + ey * ey), 0.0, 1.0);
  const double dx = p[0] - (a[0] + t * ex), dy = p[1] - (a[1] + t * ey);
  const double r = std::hypot(dx, dy);
  if (r >= R) return {};
  const double x2 = (r / R) * (r / R), w = 1 - x2;
  Field2 f{w * w * w, 0, 0};
  if (r > 0) {
    const double dfdr = 3 * w * w * (-2 * r / (R * R));
    f.gx = dfdr * dx / r;
    f.gy = dfdr * dy / r;
  }
  return f;
}

}  // namespace

void plot_slice(const StoredOperator& op, double d, const std::string& out_path) {
  require(std::isfinite(d) && d >= 0 && d <= 1, "--d", "must be in [0, 1] (got " + format_number(d) + ")",
          "d is the operator parameter");
  const auto& g = op.grid;
  const int n = std::max(g.nf(), 129);
  plot::ScalarGrid grid;
  grid.nx = grid.ny = n;
  grid.values.resize(static_cast<std::size_t>(n) * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      grid.values[static_cast<std::size_t>(j) * n + i] =
          g.eval(float(grid.x(i)), float(grid.y(j)), float(d)).g;
  plot::FigureOptions fo;
  fo.title = "operator '" + op.spec.name + "' at d = " + fmt(d, 3) + "  (x: f1, y: f2)";
  plot::Figure fig(grid, fo);
  for (int l = 1; l <= 9; ++l)
    if (l != 5) fig.add_iso_lines(0.1f * l, {0.15, 0.15, 0.15}, 0.8);
  fig.add_iso_lines(0.5f, {1, 1, 1}, 2.5);
  const operators::SliceProfile profile(op.spec, d);
  for (const auto& pl : profile.polylines()) {
    std::vector<Point2> pts(pl.points.begin(), pl.points.end());
    if (pl.kind == operators::CurveKind::kContact)
      fig.add_polyline(pts, {0.1, 0.85, 0.2}, 3.0);
    else
      fig.add_polyline(pts, {0.9, 0.2, 0.6}, 1.5, true);
  }
  fig.add_caption("heat map: g(f1, f2; d); black: iso-lines every 0.1; white: g = 0.5");
  fig.add_caption("dashed magenta: boundary profile curve; green: contact line (g = 0.5, inside both)");
  fig.save(out_path);
}

ComposedField compose_field(const operators::GridOperator& op, const operators::ControllerTable& controller,
                            const ComposeOptions& o) {
  require(std::isfinite(o.angle_deg) && o.angle_deg >= 0 && o.angle_deg <= 180, "--angle",
          "must be in [0, 180] degrees (got " + format_number(o.angle_deg) + ")", "0 = straight joint");
  if (o.d)
    require(std::isfinite(*o.d) && *o.d >= 0 && *o.d <= 1, "--d",
            "must be in [0, 1] (got " + format_number(*o.d) + ")", "omit --d to use the spec's controller");
  require(o.samples >= 16 && o.samples <= 4096, "samples", "must be in [16, 4096]", "use e.g. 361");
  const double phi = o.angle_deg * kPi / 180.0;
  ComposedField out;
  out.bones = {Point2{-1.2, 0}, Point2{0, 0}, Point2{1.2 * std::cos(phi), 1.2 * std::sin(phi)}};
  const Point2 a = out.bones[0], j = out.bones[1], b = out.bones[2];
  plot::ScalarGrid& grid = out.grid;
  grid.nx = grid.ny = o.samples;
  grid.x0 = grid.y0 = -1.6;
  grid.x1 = grid.y1 = 1.6;
  grid.values.resize(static_cast<std::size_t>(o.samples) * o.samples);
  for (int y = 0; y < o.samples; ++y)
    for (int x = 0; x < o.samples; ++x) {
      const Point2 p{grid.x(x), grid.y(y)};
      const Field2 u = capsule(p, a, j, o.radius), v = capsule(p, j, b, o.radius);
      double d = 0;
      if (o.d) {
        d = *o.d;
      } else {
        const double nu = std::hypot(u.gx, u.gy), nv = std::hypot(v.gx, v.gy);
        const double c =
            (nu > 0 && nv > 0) ? std::clamp((u.gx * v.gx + u.gy * v.gy) / (nu * nv), -1.0, 1.0) : 1.0;
        d = controller(float(std::acos(c)));
      }
      out.stats.max_d = std::max(out.stats.max_d, d);
      grid.values[static_cast<std::size_t>(y) * o.samples + x] =
          op.eval(float(u.value), float(v.value), float(d)).g;
    }
  // The contact surface is a valley where g touches 0.5 with g > 0.5 on both sides: take the
  // iso-line just above 0.5 inside both fields; it runs around the contact line (count it once).
  const float eps = 0.01f;
  for (const auto& s : plot::iso_segments(grid, 0.5f + eps)) {
    const Point2 m{0.5 * (s[0][0] + s[1][0]), 0.5 * (s[0][1] + s[1][1])};
    // Inside both operands by a margin, evaluated exactly at the segment (not at a sample): the
    // clean union's own 0.5 + eps line where f1 = f2 (around a joint) stays below this margin.
    if (capsule(m, a, j, o.radius).value > 0.5 + 2 * eps && capsule(m, j, b, o.radius).value > 0.5 + 2 * eps)
      out.contact.push_back(s);
  }
  out.stats.contact_length = 0.5 * plot::total_length(out.contact);
  return out;
}

ComposeStats compose(const StoredOperator& op, const ComposeOptions& o, const std::string& out_path) {
  const ComposedField field = compose_field(op.grid, op.spec.make_controller().table(), o);
  const ComposeStats& st = field.stats;
  const Point2 a = field.bones[0], j = field.bones[1], b = field.bones[2];
  if (out_path.empty()) return st;
  plot::FigureOptions fo;
  fo.pixel_size = o.pixels;
  fo.title = "'" + op.spec.name + "', bend " + fmt(o.angle_deg, 0) + " deg, " +
             (o.d ? "d = " + fmt(*o.d, 2) : "d = " + op.spec.controller + "(alpha)");
  plot::Figure fig(field.grid, fo);
  for (int l = 1; l <= 9; ++l)
    if (l != 5) fig.add_iso_lines(0.1f * l, {0.15, 0.15, 0.15}, 0.7);
  fig.add_iso_lines(0.5f, {1, 1, 1}, 2.5);
  fig.add_segments(field.contact, {0.1, 0.85, 0.2}, 3.0);
  fig.add_polyline({a, j, b}, {0.9, 0.2, 0.6}, 1.5, true);
  fig.add_caption("white: composed 0.5 iso-line; green: contact part (inside both capsules); dashed: bones");
  fig.add_caption("contact length " + fmt(st.contact_length, 3) + " (capsule radius " + fmt(o.radius, 2) +
                  ")");
  fig.save(out_path);
  return st;
}

}  // namespace isokit::opdesigner
