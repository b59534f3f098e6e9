// SPDX-License-Identifier: MIT
/// \file
/// The fitted parts of a rig (2013 §4.1): the mesh partitioned by dominant joint and one HRBF
/// primitive fitted per joint with vertices (bone-local frame, 32³ grid). The composed field
/// built on them is in skin_field.h.
///
/// Bone segments (the fit's culling planes and closure points, see docs/skinning.md):
/// - a joint with exactly one child joint: from the joint to the child, closure points at both
///   ends (the start one only when the parent has a primitive);
/// - any other joint (leaf, or several children such as hips, chest, hand): from the joint along
///   the direction to its vertices' centroid (or their principal axis when the centroid lies on
///   the joint), long enough that no vertex is culled at the far end, no closure at the far end.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "isokit/implicit/fit.h"
#include "isokit/skinning/rig.h"
#include "isokit/skinning/setup.h"
#include "isokit/track/mesh.h"

namespace isokit::skinning {

/// Progress of long work: `(stage, done, total)`.
using Progress = std::function<void(const std::string&, int, int)>;

/// Which rule gave a joint's vertices a field (docs/skinning.md, "No vertex without a field").
enum class FitRule {
  no_vertices,  ///< no vertex in its partition: nothing to cover
  hrbf,         ///< its HRBF, first try (triangles facing the bone with cosine < −0.2 dropped)
  hrbf_strict,  ///< its HRBF, second try (cosine > 0.3 kept)
  hrbf_open,    ///< its HRBF, third try (cosine > 0.3, no closure points)
  distance,     ///< the distance field of its closed part (SkinSetup::fit.field = distance)
  shared,       ///< no fit: its vertices share the primitive of `merged_into`
  capsule,      ///< no HRBF fit: a capsule that matches its part, or no touching neighbour to share with
  none,         ///< no fit and no fitted neighbour: its vertices have no field
};
const char* to_string(FitRule rule);

/// One joint's primitive.
struct BonePart {
  int joint{-1};
  int vertices{0};          ///< vertices in the joint's partition
  Eigen::Vector3d start{};  ///< bone segment at rest, mesh space: start (fit frame origin)
  Eigen::Vector3d end{};    ///< and end (the fit frame's +z points from start to end)
  bool fitted{false};
  std::string error;            ///< why the joint has no primitive (no vertices, failed fit)
  int merged_into{-1};          ///< the joint that took this joint's vertices after a failed fit
  FitRule rule{FitRule::none};  ///< the rule applied (a refitted merge target keeps its own try's)
  implicit::FittedPart fit;     ///< valid when `fitted`
};

/// Partition, bone segments and fitted primitives of a rig (the part shared by all methods).
class FittedRig {
 public:
  /// \param rig a validated rig with weights. \throw InputError if no joint gets a primitive.
  FittedRig(const Rig& rig, const SkinSetup& setup, const Progress& progress = {});

  const Rig& rig() const { return *rig_; }
  /// Joint of each vertex: dominant weight, stray islands merged into their neighbours.
  const std::vector<int>& partition() const { return partition_; }
  const std::vector<BonePart>& bones() const { return bones_; }  ///< one per joint
  int fitted_count() const;
  /// The nearest ancestor of `joint` that has a primitive (-1: none): its parent in the tree.
  int primitive_parent(int joint) const;
  double fit_seconds() const { return fit_seconds_; }

 private:
  std::shared_ptr<const Rig> rig_;
  std::vector<int> partition_;
  std::vector<BonePart> bones_;
  double fit_seconds_{0};
};

/// How far a primitive's inside reaches at rest, counted over the rest vertices with a field
/// value above 0.5 by their joint in the partition: a primitive holding many vertices of
/// unrelated joints reaches where it should not (docs/skinning.md, "Checking a fit").
struct PrimitiveCoverage {
  int joint{-1};
  int own{0};        ///< vertices of its partition (inside or not)
  int related{0};    ///< vertices inside it of the primitives next to it in the tree (parent, children)
  int unrelated{0};  ///< vertices inside it of every other joint
};

/// One entry per fitted joint, in joint order. "Next in the tree": the nearest ancestor with a
/// primitive, and the joints whose nearest ancestor with a primitive this joint is.
std::vector<PrimitiveCoverage> primitive_coverage(const FittedRig& fitted);

/// Guard against vertices that crossed their own bone's axis, which past what the field can fold
/// would flatten the limb for good (not in the papers; docs/skinning.md, "Decision: the axis
/// guard"). A vertex at least half its primitive's `r` from the bone axis at rest whose radial
/// direction in its primitive's frame now makes more than 90° with its rest radial direction is
/// put back on its own side: the radial component along the rest one is set to `offset` times
/// the rest one (the rest is kept).
class AxisGuard {
 public:
  /// \param offset fraction of the rest radial vector a crossed vertex is put back at (0.2).
  explicit AxisGuard(const FittedRig& fitted, double offset = 0.2);
  /// Moves the crossed vertices of `positions` (welded, posed by `skin`); returns how many.
  int apply(const std::vector<Affine>& skin, track::Positions& positions) const;

 private:
  const FittedRig* fitted_;
  double offset_;
  std::vector<int> own_;                 // primitive joint per vertex (-1: none, or too close to the axis)
  std::vector<Eigen::Vector2d> radial_;  // rest radial vector in the primitive's frame
};

/// Stray islands: connected components of a joint's vertex set other than its largest go to the
/// joint most of their boundary neighbours belong to (repeated until stable).
std::vector<int> clean_partition(const std::vector<int>& labels, const track::Triangles& triangles,
                                 int num_vertices);

}  // namespace isokit::skinning
