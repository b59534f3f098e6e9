// SPDX-License-Identifier: MIT
/// \file
/// Fit quality of a fitted rig, per joint with a primitive (docs/skinning.md, "Fit quality"):
/// the distances both ways between each part's mesh and its primitive's 0.5 iso-surface
/// (libimplicit fit_quality.h), and the rest vertices of other joints inside the primitive.
#pragma once

#include <cstdint>
#include <vector>

#include "isokit/implicit/fit_quality.h"
#include "isokit/skinning/fitted_rig.h"
#include "isokit/skinning/skin_field.h"

namespace isokit::skinning {

/// One joint's primitive against its part. The part's mesh is what the fit sees: the triangles
/// of the joint (a triangle belongs to the joint of two of its vertices) and their vertices.
/// Iso-surface points inside a primitive next to it in the tree (parent, children: the caps
/// closing a joint reach into them by design, 2013 §4.1) are left out of surface → vertices.
struct PartQuality {
  int joint{-1};
  double r{0};                       ///< the primitive's t_r width (bone to farthest sample)
  implicit::FitDistances distances;  ///< world units (the rig's)
  PrimitiveCoverage coverage;        ///< rest vertices inside it: own, related, unrelated
  /// Its own field at its partition's rest vertices, against their normals in the whole mesh
  /// (area-weighted): angle of −∇f to the normal, distance to the 0.5 level.
  implicit::FieldAgreement agreement;
};

struct FitQuality {
  double diagonal{0};              ///< the rest mesh's bounding-box diagonal
  int vertices_without_field{0};   ///< rest vertices whose partition joint has no primitive
  std::vector<PartQuality> parts;  ///< one per joint with a primitive, in joint order
  /// Worst part values, relative to the diagonal (infinite when a part has no 0.5 level).
  double worst_to_surface_p95() const;
  double worst_to_surface_max() const;
  double worst_from_surface_p95() const;
  double worst_from_surface_max() const;
  int unrelated_inside() const;  ///< sum over the primitives
};

/// What the tracker follows at rest: the composed field (a 2014 tree) against the rest mesh
/// (issue "Fields that agree with the mesh"; docs/skinning.md, "Checking a fit").
struct RestAgreement {
  /// At every rest vertex outside open panels: angle of −∇f to the area-weighted vertex normal
  /// and distance to the 0.5 level (the 60° limit of TrackerOptions::free_vertex_angle_deg).
  implicit::FieldAgreement composed;
  /// The same over the visible vertices: those also not inside another connected component of
  /// the mesh (an eyeball in its socket, a robot's limb sunk into its torso: no field whose
  /// surface is the skin passes through them).
  implicit::FieldAgreement visible;
  int hidden_vertices{0};  ///< vertices inside another component (`hidden_vertices`), outside open panels
  int triangles{0};
  int inverted_triangles{
      0};                 ///< rest triangles outside open panels whose normal points along +∇f (QUALITY.md)
  int open_panels{0};     ///< components that are open sheets (`open_panel_vertices`)
  int panel_vertices{0};  ///< their vertices, left out of the counts above
  int unrelated_inside{0};  ///< rest vertices inside a primitive of an unrelated joint (FitQuality)
};

/// Per vertex: 1 on an open panel, a connected component with a border whose triangles' vector
/// area (which equals its border loops' vector area) is at least 0.3 of its area — a sheet with
/// no inside (an armour plate, a robot's panel), unlike a tube open at its ends (vector area
/// near 0) or a body open at the neck (a small share).
std::vector<std::uint8_t> open_panel_vertices(const Rig& rig, int* panels = nullptr);

/// Per vertex: 1 when it lies inside another connected component of the mesh (generalized
/// winding number of that component's triangles above 0.5, Jacobson et al. 2013), so it is not
/// on the visible skin.
std::vector<std::uint8_t> hidden_vertices(const Rig& rig);

/// The composed field `field` (at its rest pose) against the rest mesh of `fitted`.
RestAgreement rest_agreement(const FittedRig& fitted, const SkinField& field);

/// Measures every primitive of `fitted` (about 0.05 s per part on one core at the default
/// resolution). \throw InputError for options out of range (fit_quality.h).
FitQuality fit_quality(const FittedRig& fitted, const implicit::FitDistanceOptions& options = {});

}  // namespace isokit::skinning
