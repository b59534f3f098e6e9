// SPDX-License-Identifier: MIT
/// \file
/// How well a fitted primitive matches its mesh part, measured both ways (docs/skinning.md,
/// "Fit quality"):
/// - vertex → surface: for each part vertex, the distance to the primitive's 0.5 iso-surface
///   (the nearer of the point a few Newton steps on `f − 0.5` reach from the vertex and the
///   nearest iso-surface point of the lattice below);
/// - surface → vertices: the 0.5 iso-surface is sampled where it crosses the edges of a lattice
///   over the field's support (linear interpolation along the edge); each such point's distance
///   to the nearest part triangle. Points a caller marks as excluded (e.g. the caps a primitive
///   pushes into its neighbours by design) are left out.
///
/// Both are upper bounds of the true distances up to the lattice spacing (support box /
/// `resolution`). A field with no 0.5 level near a vertex gives an infinite distance, never NaN.
///
/// \note Field convention: values in [0, 1], inside > 0.5, gradients inward, compact support.
#pragma once

#include <array>
#include <functional>
#include <vector>

#include "isokit/core/math.h"
#include "isokit/implicit/field.h"

namespace isokit::implicit {

struct FitDistanceOptions {
  /// Lattice nodes per axis over the field's support box for the iso-surface points, in
  /// [8, 256] (not in the papers; 40 puts the spacing at about r / 10 on a limb).
  int resolution = 40;
  /// Newton steps on `f − 0.5` from each vertex, in [0, 100]; a step longer than two lattice
  /// spacings is shortened to that (not in the papers).
  int newton_steps = 10;
};

/// Distances in the units of the vertices (world). p95: the 95th percentile (nearest rank).
struct FitDistances {
  int vertices{0};                                  ///< part vertices measured
  int surface_points{0};                            ///< iso-surface points measured (after the exclusions)
  double to_surface_p95{0}, to_surface_max{0};      ///< vertex → 0.5 iso-surface
  double from_surface_p95{0}, from_surface_max{0};  ///< iso-surface point → nearest part triangle
};

/// Fit distances of `field` (in its local frame; `local_to_world` places it) against the part
/// `vertices` / `triangles` (world; `triangles` index `vertices`). `exclude(world point)` true
/// leaves an iso-surface point out of the surface → vertices distances.
/// \throw InputError for options out of range or triangle indices out of range.
FitDistances fit_distances(const Field& field, const Rigid3d& local_to_world,
                           const std::vector<Vec3d>& vertices,
                           const std::vector<std::array<int, 3>>& triangles,
                           const std::function<bool(const Vec3d&)>& exclude = {},
                           const FitDistanceOptions& options = {});

/// What the tracker needs from a field at rest (2014 §4: gradients pointing towards the closest
/// point of the surface), measured at mesh vertices: the angle between the field's outward
/// direction −∇f and the vertex's outward normal, and the distance from the vertex to the field's
/// `iso` level along the field (Newton steps). Not in the papers.
struct AgreementOptions {
  double angle_limit_deg = 60;  ///< angles above this are counted (`FieldAgreement::over_limit`); (0, 180]
  int newton_steps = 8;         ///< Newton steps towards the level, in [1, 100]
  double tolerance = 1e-4;      ///< a point is on the level when |f − iso| is below this; > 0
};

/// Percentiles are nearest rank. A point without a usable gradient has the angle 180° and an
/// infinite distance, never NaN; a point without a normal is not counted.
struct FieldAgreement {
  int points{0};
  double angle_p50{0}, angle_p95{0}, angle_max{0};           ///< degrees
  int over_limit{0};                                         ///< points whose angle exceeds the limit
  double distance_p50{0}, distance_p95{0}, distance_max{0};  ///< world units
};

/// Agreement of `field` (in its local frame; `local_to_world` places it) with the points
/// `points` (world) and their outward normals `normals` (world, any length; same count).
/// \throw InputError when the counts differ or the options are out of range.
FieldAgreement field_agreement(const Field& field, const Rigid3d& local_to_world,
                               const std::vector<Vec3d>& points, const std::vector<Vec3d>& normals,
                               float iso = 0.5f, const AgreementOptions& options = {});

/// Area-weighted vertex normals (the sum of the incident triangles' cross products, not
/// normalised) of `vertices` / `triangles`.
std::vector<Vec3d> area_weighted_normals(const std::vector<Vec3d>& vertices,
                                         const std::vector<std::array<int, 3>>& triangles);

/// Distance from `p` to the triangle `a b c` (degenerate triangles: to their edges).
double point_triangle_distance(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c);

}  // namespace isokit::implicit
