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

/// Distance from `p` to the triangle `a b c` (degenerate triangles: to their edges).
double point_triangle_distance(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c);

}  // namespace isokit::implicit
