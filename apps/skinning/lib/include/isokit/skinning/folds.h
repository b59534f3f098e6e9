// SPDX-License-Identifier: MIT
/// \file
/// Folds measured on the skin alone (docs/skinning-metrics.md, "Folds"): a triangle is *folded*
/// when its normal has turned by more than 90° from its rest normal carried by the skeleton.
///
/// The carried normal of triangle t is `R_t n_t`, where `n_t` is its rest normal and `R_t` the
/// rotation of the skinning blend at the triangle: the dual-quaternion blend (Kavan et al. 2008)
/// of the rigid parts of the skinning matrices with the triangle's weights, the mean of its three
/// corners' weights (the blend at its centroid), antipodality fixed against the joint of largest
/// weight. Triangle t is folded when `n'_t · R_t n_t < 0` (`n'_t` its normal in the measured pose).
///
/// No field is involved, and the reference is the same for every method (it depends only on the
/// rig and the pose), so every method is measured alike. Properties (tests/skinning/test_folds.cpp):
/// a rigid motion of the whole rig, or of a part that moves rigidly with one bone, folds nothing;
/// the count does not depend on how the rig is turned; a triangle turned over is counted, one only
/// tilted (< 90°) is not. A triangle of zero area (rest or posed) has no normal and is never folded.
/// Stretches (scale keys) are left out of `R_t`: a fold is a turn, not a scale.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "isokit/skinning/rig.h"
#include "isokit/track/mesh.h"

namespace isokit::skinning {

/// Counts folded triangles for many poses of one mesh: the constructor stores each triangle's
/// rest normal and blend weights; `folded()` takes the posed positions and the pose's skinning
/// matrices (`skinning_matrices(rig, pose)`).
class FoldCounter {
 public:
  /// `rest`: `#V by 3`; `triangles`: `#F by 3` (counter-clockwise seen from outside); `weights`:
  /// one entry per vertex (rig.h); `rest_skin`: the skinning matrices at the rest pose (identity
  /// at the bind pose), which give the triangles folded at rest.
  /// \throw InputError for an index out of range, weights of the wrong size or a joint index
  /// outside `rest_skin`.
  FoldCounter(const track::Positions& rest, const track::Triangles& triangles, const SkinWeights& weights,
              const std::vector<Affine>& rest_skin, std::size_t grain = 1024);

  /// Per triangle: 1 when folded in `posed` under the skinning matrices `skin` (one per joint).
  /// \throw InputError for a vertex count or a matrix count that does not match.
  std::vector<std::uint8_t> folded(const track::Positions& posed, const std::vector<Affine>& skin) const;

  /// The triangles folded at rest (the rest mesh under `rest_skin`), per triangle.
  const std::vector<std::uint8_t>& rest_folded() const { return rest_folded_; }

  /// Folded triangles, and those of them not folded at rest (`folded_new`).
  struct Count {
    int folded{0};
    int folded_new{0};
  };
  Count count(const std::vector<std::uint8_t>& flags) const;

 private:
  track::Triangles triangles_;
  std::vector<Eigen::Vector3d> rest_normals_;  ///< unit, or zero for a degenerate triangle
  SkinWeights blend_;                          ///< per triangle: the mean of its corners' weights
  std::vector<int> pivot_;                     ///< per triangle: its joint of largest weight
  std::size_t joints_{0};
  std::size_t grain_{1024};
  std::vector<std::uint8_t> rest_folded_;
};

}  // namespace isokit::skinning
