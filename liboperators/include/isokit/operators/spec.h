// SPDX-License-Identifier: MIT
/// \file
/// Operator specs (2014 §4.2): the profile curves along which `g = 0.5`, their control points
/// keyframed over `d`, the grid resolution and the controller. Stored as versioned JSON
/// (format "isokit-operator-spec", version 1; see docs/operators.md for the schema).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "isokit/operators/controller.h"

namespace isokit::operators {

/// A point of the operator domain `(f1, f2) ∈ [0, 1]²`.
using Point2 = std::array<double, 2>;

/// What `g = 0.5` on the curve separates. Numbers are fixed (file format); strings in JSON.
enum class CurveKind : int {
  /// "boundary": the outer 0.5 iso-line; `g < 0.5` on the side of (0, 0), `> 0.5` toward (1, 1).
  kBoundary = 0,
  /// "contact": a contact line (2014 Fig. 5, green); `g > 0.5` on both sides.
  kContact = 1,
};

/// How control points define the curve: "polyline" (through the points) or "bspline" (clamped
/// uniform cubic B-spline: passes through the first and last points; ≥ 4 points).
enum class CurveType : int { kPolyline = 0, kBSpline = 1 };

/// Control points of a curve at one value of `d`.
struct Keyframe {
  double d{0};
  std::vector<Point2> points;
};

/// A profile curve: control points linearly interpolated between keyframes (constant beyond the
/// first and last). All keyframes have the same number of points.
struct ProfileCurve {
  CurveKind kind{CurveKind::kBoundary};
  CurveType type{CurveType::kPolyline};
  std::vector<Keyframe> keyframes;

  std::vector<Point2> control_points(double d) const;
  /// The curve at `d` as a polyline (B-splines sampled with 32 points per span).
  std::vector<Point2> polyline(double d) const;
};

/// Most cells (slices × resolution²) an operator grid may have: 2^27, 512 MiB of floats (e.g.
/// 512³, or 1024² × 128). A spec or setup file declares the grid's size in a few bytes; the bound
/// keeps the grid a command derives from it within a documented size (docs/fuzzing.md).
constexpr long long kMaxOperatorCells = 1LL << 27;

/// What the biharmonic generator builds (2014 §4.2). `validate` checks the ranges below.
struct OperatorSpec {
  /// Name stored in the file and shown by the tools. Default "custom".
  std::string name{"custom"};
  /// Grid nodes per f axis, in [8, 1024]. Default 128 (2014 §6.1).
  int resolution{128};
  /// Number of d slices, in [8, 1024]. Default 128 (2014 §6.1).
  int slices{128};
  /// slices × resolution² is at most `kMaxOperatorCells` (see there).
  /// Slope of the constraint values across the profile, > 0 (g per unit of distance in the
  /// (f1, f2) square): nodes of crossed cells get `0.5 + distance_slope * signed distance`
  /// (2014 §4.2, eq. 2). Default 1, which matches `g(f, 0) = f`.
  double distance_slope{1.0};
  /// Controller `d(α)` (2014 §4.1): a preset name (Controller::preset), used unless
  /// `controller_knots` is non-empty. Default "contact".
  std::string controller{"contact"};
  /// A custom controller (angles in radians, values in [0, 1]). Default empty: the preset.
  std::vector<ControllerKnot> controller_knots;
  /// The profile curves along which `g = 0.5` (2014 §4.2, Fig. 5). Default empty
  /// (`preset_spec` fills them).
  std::vector<ProfileCurve> curves;

  Controller make_controller() const;
  bool operator==(const OperatorSpec& o) const;
};

bool operator==(const ProfileCurve& a, const ProfileCurve& b);

/// Presets (2014 §4.2):
/// - "contact" (`g_dc`): boundary polyline (0, .5)-(.5, .5)-(.5, 0) for all d, and the contact
///   line from (.5, .5) along the diagonal to (.5 + 0.4 d, .5 + 0.4 d) (see docs: the paper's
///   end point (.5 + d/√2, .5 + d/√2) leaves the square for d > 0.707).
/// - "bulge" (`g_db`): boundary B-spline inflating toward the origin with d (meeting point on
///   the diagonal from (.5, .5) at d = 0 to (.36, .36) at d = 1) plus the contact line from the
///   meeting point to (.5 + 0.4 d, .5 + 0.4 d).
/// - "clean-union": the boundary polyline only, the same for all d.
/// \throw isokit::InputError for an unknown name or resolution.
OperatorSpec preset_spec(const std::string& name, int resolution = 128);
std::vector<std::string> preset_spec_names();

/// Checks every field; `source` (a file name) prefixes the messages.
/// \throw isokit::InputError naming the source and the field.
void validate(const OperatorSpec& spec, const std::string& source);

/// JSON text <-> spec (validated). \throw isokit::InputError naming `source` and the field.
OperatorSpec spec_from_json(const std::string& text, const std::string& source);
std::string spec_to_json(const OperatorSpec& spec);
/// Files; save writes atomically (temporary name, then rename). \throw isokit::InputError naming
/// the file if it cannot be read or written.
OperatorSpec load_spec(const std::string& path);
void save_spec(const OperatorSpec& spec, const std::string& path);

}  // namespace isokit::operators
