// SPDX-License-Identifier: MIT
#include "isokit/operators/spec.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>

#include <nlohmann/json.hpp>

#include "isokit/core/atomic_file.h"
#include "isokit/core/error.h"
#include "isokit/operators/profile.h"

namespace isokit::operators {
namespace {

constexpr const char* kFormat = "isokit-operator-spec";
constexpr int kVersion = 1;

Point2 lerp(const Point2& a, const Point2& b, double t) {
  return {a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t};
}

/// Clamped uniform cubic B-spline, de Boor evaluation at u ∈ [0, m - 3].
Point2 bspline_point(const std::vector<Point2>& p, double u) {
  const int m = static_cast<int>(p.size());
  const int spans = m - 3;
  auto knot = [&](int i) { return static_cast<double>(std::min(std::max(i - 3, 0), spans)); };
  int s = std::min(static_cast<int>(std::floor(u)), spans - 1) + 3;  // knot span index
  Point2 d[4];
  for (int j = 0; j < 4; ++j) d[j] = p[s - 3 + j];
  for (int r = 1; r <= 3; ++r)
    for (int j = 3; j >= r; --j) {
      const int i = s - 3 + j;
      const double den = knot(i + 4 - r) - knot(i);
      const double a = den > 0 ? (u - knot(i)) / den : 0.0;
      d[j] = lerp(d[j - 1], d[j], a);
    }
  return d[3];
}

std::string point_text(const Point2& p) {
  return "(" + format_number(p[0]) + ", " + format_number(p[1]) + ")";
}

}  // namespace

std::vector<Point2> ProfileCurve::control_points(double d) const {
  if (keyframes.empty()) return {};
  if (d <= keyframes.front().d) return keyframes.front().points;
  if (d >= keyframes.back().d) return keyframes.back().points;
  std::size_t i = 1;
  while (keyframes[i].d < d) ++i;
  const auto& a = keyframes[i - 1];
  const auto& b = keyframes[i];
  const double t = (d - a.d) / (b.d - a.d);
  std::vector<Point2> out(a.points.size());
  for (std::size_t j = 0; j < out.size(); ++j) out[j] = lerp(a.points[j], b.points[j], t);
  return out;
}

std::vector<Point2> ProfileCurve::polyline(double d) const {
  std::vector<Point2> cp = control_points(d);
  if (type == CurveType::kPolyline || cp.size() < 4) return cp;
  const int spans = static_cast<int>(cp.size()) - 3;
  constexpr int kPerSpan = 32;
  std::vector<Point2> out;
  out.reserve(static_cast<std::size_t>(spans) * kPerSpan + 1);
  for (int i = 0; i <= spans * kPerSpan; ++i) out.push_back(bspline_point(cp, double(i) / kPerSpan));
  return out;
}

bool operator==(const ProfileCurve& a, const ProfileCurve& b) {
  if (a.kind != b.kind || a.type != b.type || a.keyframes.size() != b.keyframes.size()) return false;
  for (std::size_t i = 0; i < a.keyframes.size(); ++i)
    if (a.keyframes[i].d != b.keyframes[i].d || a.keyframes[i].points != b.keyframes[i].points) return false;
  return true;
}

bool OperatorSpec::operator==(const OperatorSpec& o) const {
  if (name != o.name || resolution != o.resolution || slices != o.slices ||
      distance_slope != o.distance_slope || controller != o.controller ||
      controller_knots.size() != o.controller_knots.size() || curves.size() != o.curves.size())
    return false;
  for (std::size_t i = 0; i < controller_knots.size(); ++i)
    if (controller_knots[i].alpha != o.controller_knots[i].alpha ||
        controller_knots[i].d != o.controller_knots[i].d)
      return false;
  for (std::size_t i = 0; i < curves.size(); ++i)
    if (!(curves[i] == o.curves[i])) return false;
  return true;
}

Controller OperatorSpec::make_controller() const {
  if (!controller_knots.empty()) return Controller(controller_knots, controller);
  return Controller::preset(controller);
}

std::vector<std::string> preset_spec_names() {
  return {"contact", "bulge", "clean-union"};
}

OperatorSpec preset_spec(const std::string& name, int resolution) {
  OperatorSpec s;
  s.name = name;
  s.resolution = resolution;
  s.slices = resolution;
  // Contact line end: (.5, .5) + 0.4 d (1, 1): reaches (.9, .9) at d = 1, keeping 0.1 (12.8 cells
  // at 128) from the g(1, 1) = 1 corner (docs/operators.md, "contact-line end point").
  const double reach = 0.4;
  ProfileCurve contact{CurveKind::kContact, CurveType::kPolyline, {}};
  if (name == "contact" || name == "clean-union") {
    s.controller = name == "contact" ? "contact" : "constant0";
    s.curves.push_back(
        {CurveKind::kBoundary, CurveType::kPolyline, {{0.0, {{0, 0.5}, {0.5, 0.5}, {0.5, 0}}}}});
    if (name == "contact") {
      contact.keyframes = {{0.0, {{0.5, 0.5}, {0.5, 0.5}}}, {1.0, {{0.5, 0.5}, {0.5 + reach, 0.5 + reach}}}};
      s.curves.push_back(contact);
    }
  } else if (name == "bulge") {
    s.controller = "bulge";
    const double m = 0.36;  // meeting point on the diagonal at maximal bulge
    ProfileCurve b{CurveKind::kBoundary, CurveType::kBSpline, {}};
    b.keyframes = {{0.0, {{0, 0.5}, {0.25, 0.5}, {0.5, 0.5}, {0.5, 0.5}, {0.5, 0.5}, {0.5, 0.25}, {0.5, 0}}},
                   {1.0, {{0, 0.5}, {0.2, 0.5}, {m, m}, {m, m}, {m, m}, {0.5, 0.2}, {0.5, 0}}}};
    s.curves.push_back(b);
    contact.keyframes = {{0.0, {{0.5, 0.5}, {0.5, 0.5}}}, {1.0, {{m, m}, {0.5 + reach, 0.5 + reach}}}};
    s.curves.push_back(contact);
  } else {
    std::string list;
    for (const auto& n : preset_spec_names()) list += (list.empty() ? "" : ", ") + n;
    throw InputError("preset '" + name + "': unknown; use one of " + list);
  }
  validate(s, "preset '" + name + "'");
  return s;
}

void validate(const OperatorSpec& s, const std::string& source) {
  const std::string at = source + ": ";
  require(s.resolution >= 8 && s.resolution <= 1024, at + "resolution",
          "must be in [8, 1024] (got " + std::to_string(s.resolution) + ")",
          "use e.g. 128 (the paper's grid)");
  require(s.slices >= 8 && s.slices <= 1024, at + "slices",
          "must be in [8, 1024] (got " + std::to_string(s.slices) + ")", "use e.g. 128");
  const long long cells = static_cast<long long>(s.slices) * s.resolution * s.resolution;
  require(cells <= kMaxOperatorCells, at + "slices x resolution^2",
          "is " + std::to_string(cells) + " cells, more than the " + std::to_string(kMaxOperatorCells) +
              " an operator grid may have (512 MiB)",
          "lower the resolution or the slices (the paper uses 128 x 128 x 128)");
  require(std::isfinite(s.distance_slope) && s.distance_slope > 0, at + "distance_slope",
          "must be positive (got " + format_number(s.distance_slope) + ")", "use 1");
  try {
    (void)s.make_controller();
  } catch (const InputError& e) {
    throw InputError(at + "controller: " + e.what());
  }
  require(!s.curves.empty(), at + "curves", "the profile is empty",
          "give at least one boundary curve (see docs/operators.md)");
  bool has_boundary = false;
  for (std::size_t c = 0; c < s.curves.size(); ++c) {
    const auto& curve = s.curves[c];
    const std::string cn = at + "curves[" + std::to_string(c) + "]";
    has_boundary |= curve.kind == CurveKind::kBoundary;
    require(!curve.keyframes.empty(), cn + ".keyframes", "empty", "give at least one keyframe");
    const std::size_t min_points = curve.type == CurveType::kBSpline ? 4 : 2;
    for (std::size_t k = 0; k < curve.keyframes.size(); ++k) {
      const auto& kf = curve.keyframes[k];
      const std::string kn = cn + ".keyframes[" + std::to_string(k) + "]";
      require(std::isfinite(kf.d) && kf.d >= 0 && kf.d <= 1, kn + ".d",
              "must be in [0, 1] (got " + format_number(kf.d) + ")",
              "keyframe d values are slice parameters");
      if (k > 0)
        require(kf.d > curve.keyframes[k - 1].d, kn + ".d", "keyframes must have increasing d",
                "sort the keyframes");
      require(kf.points.size() >= min_points, kn + ".points",
              "needs at least " + std::to_string(min_points) + " points (got " +
                  std::to_string(kf.points.size()) + ")",
              "add control points");
      require(kf.points.size() == curve.keyframes[0].points.size(), kn + ".points",
              "every keyframe of a curve needs the same number of points", "match keyframe 0");
      for (std::size_t p = 0; p < kf.points.size(); ++p) {
        const Point2& q = kf.points[p];
        require(
            std::isfinite(q[0]) && std::isfinite(q[1]) && q[0] >= 0 && q[0] <= 1 && q[1] >= 0 && q[1] <= 1,
            kn + ".points[" + std::to_string(p) + "]", "outside the unit square (got " + point_text(q) + ")",
            "operator inputs are field values in [0, 1]");
        // g = 0.5 on the profile must agree with the Dirichlet boundary (2014 eq. 1).
        require(q[0] < 1 && q[1] < 1, kn + ".points[" + std::to_string(p) + "]",
                "lies on the edge f1 = 1 or f2 = 1 where g = 1 (got " + point_text(q) + ")",
                "keep profile curves inside the square, away from the g = 1 edges");
        require((q[0] > 0 || q[1] == 0.5) && (q[1] > 0 || q[0] == 0.5),
                kn + ".points[" + std::to_string(p) + "]",
                "lies on an axis away from (0, 0.5) / (0.5, 0), where g(0, f2) = f2 and g(f1, 0) = f1 "
                "are not 0.5 (got " +
                    point_text(q) + ")",
                "start and end boundary curves at (0, 0.5) and (0.5, 0)");
      }
    }
    // Self-intersection at the keyframes and half-way between them.
    std::vector<double> ds;
    for (std::size_t k = 0; k < curve.keyframes.size(); ++k) {
      ds.push_back(curve.keyframes[k].d);
      if (k > 0) ds.push_back(0.5 * (curve.keyframes[k - 1].d + curve.keyframes[k].d));
    }
    for (double d : ds)
      require(!self_intersects(curve.polyline(d)), cn, "self-intersects at d = " + format_number(d),
              "a profile curve must be a simple curve; move its control points");
  }
  require(has_boundary, at + "curves", "no curve of kind \"boundary\"",
          "the outer 0.5 iso-line must be given (see docs/operators.md)");
}

// ---- JSON ----

namespace {

using nlohmann::json;

const json& field(const json& j, const char* key, const std::string& where) {
  require(j.is_object() && j.contains(key), where + "." + key, "missing",
          "see docs/operators.md for the schema");
  return j.at(key);
}

double number(const json& j, const std::string& where) {
  require(j.is_number(), where, "must be a number", "see docs/operators.md for the schema");
  return j.get<double>();
}

int integer(const json& j, const std::string& where) {
  require(j.is_number_integer(), where, "must be an integer", "see docs/operators.md for the schema");
  // get<int> would wrap a larger integer silently (4294967424 -> 128).
  const bool fits = j.is_number_unsigned() ? j.get<std::uint64_t>() <=
                                                 static_cast<std::uint64_t>(std::numeric_limits<int>::max())
                                           : j.get<std::int64_t>() >= std::numeric_limits<int>::min() &&
                                                 j.get<std::int64_t>() <= std::numeric_limits<int>::max();
  require(fits, where, "out of range (got " + j.dump() + ")", "see docs/operators.md for the schema");
  return static_cast<int>(j.get<std::int64_t>());
}

Point2 point(const json& j, const std::string& where) {
  require(j.is_array() && j.size() == 2, where, "must be a pair [f1, f2]", "write points as [x, y]");
  return {number(j[0], where + "[0]"), number(j[1], where + "[1]")};
}

}  // namespace

OperatorSpec spec_from_json(const std::string& text, const std::string& source) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for a number like 1e999
    throw InputError(source + ": not valid JSON (" + e.what() + "); fix the syntax");
  }
  const std::string r = source + ": ";
  require(j.is_object(), r + "top level", "must be a JSON object", "see docs/operators.md");
  const json& fmt = field(j, "format", r + "spec");
  require(fmt.is_string() && fmt.get<std::string>() == kFormat, r + "format",
          "must be \"" + std::string(kFormat) + "\"", "this is not an isokit operator spec");
  const int version = integer(field(j, "version", r + "spec"), r + "version");
  require(version == kVersion, r + "version",
          "unsupported version " + std::to_string(version) + " (this build reads version " +
              std::to_string(kVersion) + ")",
          "regenerate the spec with this isokit version");
  OperatorSpec s;
  if (j.contains("name")) {
    require(j["name"].is_string(), r + "name", "must be a string", "quote it");
    s.name = j["name"].get<std::string>();
  }
  s.resolution = integer(field(j, "resolution", r + "spec"), r + "resolution");
  s.slices = j.contains("slices") ? integer(j["slices"], r + "slices") : s.resolution;
  if (j.contains("distance_slope")) s.distance_slope = number(j["distance_slope"], r + "distance_slope");
  if (j.contains("controller")) {
    const json& c = j["controller"];
    const std::string cw = r + "controller";
    require(c.is_object(), cw, "must be an object {\"preset\": name} or {\"knots\": [[alpha, d], ...]}",
            "see docs/operators.md");
    if (c.contains("preset")) {
      require(c["preset"].is_string(), cw + ".preset", "must be a string", "quote it");
      s.controller = c["preset"].get<std::string>();
    }
    if (c.contains("knots")) {
      const json& ks = c["knots"];
      require(ks.is_array(), cw + ".knots", "must be an array of [alpha, d]", "see docs/operators.md");
      if (c.contains("name") && c["name"].is_string())
        s.controller = c["name"].get<std::string>();
      else if (!c.contains("preset"))
        s.controller = "custom";
      for (std::size_t i = 0; i < ks.size(); ++i) {
        const Point2 p = point(ks[i], cw + ".knots[" + std::to_string(i) + "]");
        s.controller_knots.push_back({p[0], p[1]});
      }
    }
  }
  const json& curves = field(j, "curves", r + "spec");
  require(curves.is_array(), r + "curves", "must be an array", "see docs/operators.md");
  for (std::size_t c = 0; c < curves.size(); ++c) {
    const std::string cw = r + "curves[" + std::to_string(c) + "]";
    const json& cj = curves[c];
    ProfileCurve curve;
    const json& kind = field(cj, "kind", cw);
    require(kind.is_string() && (kind == "boundary" || kind == "contact"), cw + ".kind",
            "must be \"boundary\" or \"contact\"", "see docs/operators.md");
    curve.kind = kind == "boundary" ? CurveKind::kBoundary : CurveKind::kContact;
    const json& type = cj.contains("type") ? cj["type"] : json("polyline");
    require(type.is_string() && (type == "polyline" || type == "bspline"), cw + ".type",
            "must be \"polyline\" or \"bspline\"", "see docs/operators.md");
    curve.type = type == "polyline" ? CurveType::kPolyline : CurveType::kBSpline;
    const json& kfs = field(cj, "keyframes", cw);
    require(kfs.is_array(), cw + ".keyframes", "must be an array", "see docs/operators.md");
    for (std::size_t k = 0; k < kfs.size(); ++k) {
      const std::string kw = cw + ".keyframes[" + std::to_string(k) + "]";
      Keyframe kf;
      kf.d = number(field(kfs[k], "d", kw), kw + ".d");
      const json& pts = field(kfs[k], "points", kw);
      require(pts.is_array(), kw + ".points", "must be an array of [f1, f2]", "see docs/operators.md");
      for (std::size_t p = 0; p < pts.size(); ++p)
        kf.points.push_back(point(pts[p], kw + ".points[" + std::to_string(p) + "]"));
      curve.keyframes.push_back(std::move(kf));
    }
    s.curves.push_back(std::move(curve));
  }
  validate(s, source);
  return s;
}

std::string spec_to_json(const OperatorSpec& s) {
  json j;
  j["format"] = kFormat;
  j["version"] = kVersion;
  j["name"] = s.name;
  j["resolution"] = s.resolution;
  j["slices"] = s.slices;
  j["distance_slope"] = s.distance_slope;
  json c;
  if (s.controller_knots.empty()) {
    c["preset"] = s.controller;
  } else {
    c["name"] = s.controller;
    c["knots"] = json::array();
    for (const auto& k : s.controller_knots) c["knots"].push_back({k.alpha, k.d});
  }
  j["controller"] = c;
  j["curves"] = json::array();
  for (const auto& curve : s.curves) {
    json cj;
    cj["kind"] = curve.kind == CurveKind::kBoundary ? "boundary" : "contact";
    cj["type"] = curve.type == CurveType::kPolyline ? "polyline" : "bspline";
    cj["keyframes"] = json::array();
    for (const auto& kf : curve.keyframes) {
      json pts = json::array();
      for (const auto& p : kf.points) pts.push_back({p[0], p[1]});
      cj["keyframes"].push_back({{"d", kf.d}, {"points", pts}});
    }
    j["curves"].push_back(cj);
  }
  return j.dump(2) + "\n";
}

OperatorSpec load_spec(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  require(bool(in), path, "cannot be opened", "check the path");
  std::stringstream ss;
  ss << in.rdbuf();
  return spec_from_json(ss.str(), path);
}

void save_spec(const OperatorSpec& spec, const std::string& path) {
  const std::string text = spec_to_json(spec);
  write_text_file_atomically(path, text);
}

}  // namespace isokit::operators
