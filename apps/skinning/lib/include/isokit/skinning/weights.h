// SPDX-License-Identifier: MIT
/// \file
/// Automatic skin weights by heat diffusion (Baran & Popović 2007, "Automatic rigging and
/// animation of 3D characters", §4): for each joint j solve `(−Δ + H) w_j = H p_j` on the mesh,
/// with one sparse Cholesky factorisation shared by all joints.
///
/// Pipeline of `heat_weights`:
///  1. `d_i` = distance from vertex i to the nearest bone segment (all non-excluded joints);
///     `p_j(i) = 1/k` when j is one of the k joints at that nearest distance (ties shared, relative
///     tolerance 1e-9), else 0; `H_ii = c / max(d_i, ε)²`, ε = 1e-4 × bounding-box diagonal.
///  2. Δ = M⁻¹L: L the cotangent Laplacian, M the lumped (barycentric, area/3) mass. Every corner
///     cotangent is clamped to [0, 1e3] before use, so L is an M-matrix: the solve obeys a discrete
///     maximum principle (each w_j in [0,1], Σ_j w_j = 1 up to round-off) even on obtuse
///     triangles. The symmetric system solved is `(−L + M H) w_j = M H p_j`; masses are floored
///     at 1e-6 × the mean so vertices of zero-area triangles keep the matrix definite.
///  3. Weights are clamped to ≥ 0, those below `min_weight` (relative to the vertex's sum) are
///     dropped (the largest is always kept) and the rest renormalised to sum 1.
///
/// Deviation from the paper: no visibility test (Baran & Popović set H_ii = 0 when the nearest
/// bone is hidden from the vertex by the mesh), so a vertex closer to a foreign bone than to its
/// own takes some of that bone's weight (docs/skinning-procedural.md).
///
/// Vertices used by no triangle get their weights straight from p (the nearest bone).
/// The solver is CHOLMOD (LLᵀ) when isokit_skinning is built with it (ISOKIT_HAVE_CHOLMOD),
/// else Eigen's SimplicialLDLT (the matrix is symmetric positive definite).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "isokit/skinning/rig.h"
#include "isokit/track/mesh.h"

namespace isokit::skinning {

/// A bone segment `a → b` in mesh space; `a == b` is allowed (a point bone).
struct Segment {
  Eigen::Vector3d a{Eigen::Vector3d::Zero()};
  Eigen::Vector3d b{Eigen::Vector3d::Zero()};
};

/// The rest-pose bone segments of every joint, used for weights. Rule:
///  - a joint with children gets one segment from its position to each child's position; a
///    child at the joint's own position (distance ≤ 1e-9 × the skeleton's extent) adds none;
///  - a joint left without a segment (a leaf, or all children on top of it) gets one segment of
///    `leaf_fraction` (default 0.5) × its parent bone's length, along the parent bone's direction
///    (parent position → joint); when the parent coincides with the joint the nearest ancestor at
///    a distinct position defines the bone; a lone root gets a point segment `a == b`.
/// \return `#joints` lists (each non-empty).
std::vector<std::vector<Segment>> joint_segments(const Rig& rig, double leaf_fraction = 0.5);

struct HeatWeightOptions {
  double heat_constant{1.0};  ///< c > 0 in `H_ii = c / d_i²` (Baran & Popović: 1)
  float min_weight{0.01f};    ///< in [0, 1): weights below this fraction of the vertex's sum are dropped
  std::vector<int> excluded_joints;  ///< joints that get no weight (e.g. a root with no geometry)
  /// Called after each block of solves with the joints solved so far and the joints to solve.
  std::function<void(int done, int total)> progress;
  std::string name{"mesh"};  ///< names the mesh in error messages
};

/// Heat-diffusion weights of the mesh `rest` (`#V by 3`), `tris` (`#F by 3`) for the joints whose
/// bones are `segments_per_joint` (one list per joint; an empty list = excluded joint).
/// \return normalised CSR weights (`validate`-ready), joints sorted ascending per vertex.
/// \throw InputError for no triangles, bad indices, non-finite positions (naming the vertex) or
/// segments, or when no joint has a bone.
SkinWeights heat_weights(const track::Positions& rest, const track::Triangles& tris,
                         const std::vector<std::vector<Segment>>& segments_per_joint,
                         const HeatWeightOptions& options = {});

/// `heat_weights` on a rig's rest mesh with `joint_segments(rig)`; error messages name the rig.
SkinWeights heat_weights(const Rig& rig, HeatWeightOptions options = {});

/// Distance from `p` to the segment `s` (a point segment is handled).
double segment_distance(const Eigen::Vector3d& p, const Segment& s);

}  // namespace isokit::skinning
