// SPDX-License-Identifier: MIT
/// \file
/// Fit quality of a fitted rig, per joint with a primitive (docs/skinning.md, "Fit quality"):
/// the distances both ways between each part's mesh and its primitive's 0.5 iso-surface
/// (libimplicit fit_quality.h), and the rest vertices of other joints inside the primitive.
#pragma once

#include <vector>

#include "isokit/implicit/fit_quality.h"
#include "isokit/skinning/fitted_rig.h"

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

/// Measures every primitive of `fitted` (about 0.05 s per part on one core at the default
/// resolution). \throw InputError for options out of range (fit_quality.h).
FitQuality fit_quality(const FittedRig& fitted, const implicit::FitDistanceOptions& options = {});

}  // namespace isokit::skinning
