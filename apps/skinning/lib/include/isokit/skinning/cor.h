// SPDX-License-Identifier: MIT
/// \file
/// Skinning with optimized centers of rotation (Le & Hodgins 2016, "Real-time Skeletal Skinning
/// with Optimized Centers of Rotation"). A precomputation gives each vertex i a center of rotation
///
///     p*_i = Σ_t s(w_i, w_t) a_t c_t / Σ_t s(w_i, w_t) a_t
///
/// over the rest mesh's triangles t (area a_t, centroid c_t, weights w_t = the mean of its
/// corners' weights: the paper's discretisation of its integral over the surface), with the
/// similarity of two weight vectors
///
///     s(w_p, w_v) = Σ_{j<k} w_pj w_pk w_vj w_vk exp(−(w_pj w_vk − w_pk w_vj)² / σ²).
///
/// Per frame (the paper's run-time step): R_i = the rotation of the normalised quaternion blend
/// Σ_j w_ij q_j (antipodality fixed against the vertex's largest weight), t_i = LBS(p*_i) − R_i p*_i,
/// and u_i = R_i p_i + t_i: no candy-wrapper twist (quaternion rotations) and no DQS bulge (the
/// translation is LBS's at the center), at LBS's cost. Differences from the paper: no subdivision
/// of the rest mesh before the integral (the paper subdivides until the weights vary little over
/// a triangle); vertices with one influence, which the similarity ignores, are rigid with their
/// bone whatever p* is.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "isokit/skinning/rig.h"
#include "isokit/track/mesh.h"

namespace isokit::skinning {

/// What a vertex with no similar triangle (Σ_t s a_t = 0: e.g. every triangle that shares two of
/// its bones lost one of them to weight pruning) does.
enum class CorFallback {
  kLbs,  ///< linear blend skinning (default; the brief's reading of the paper)
  kDqs,  ///< dual-quaternion skinning
};

/// Options of the center-of-rotation precomputation. Changing them means precomputing anew.
struct CorOptions {
  /// σ, the width of the similarity kernel (dimensionless: weights are in [0, 1]), > 0 and ≤ 10.
  /// Default 0.1 (the paper's value). Setup key `cor.sigma`.
  double sigma{0.1};
  /// The rule for vertices with no similar triangle. Setup key `cor.fallback`: "lbs" (default) or "dqs".
  CorFallback fallback{CorFallback::kLbs};
};

/// \throw InputError naming `where` + the key.
void check_cor_options(const CorOptions& o, const std::string& where);
CorFallback cor_fallback_from_string(const std::string& s, const std::string& where);
const char* to_string(CorFallback f);

/// The precomputed centers and the per-frame deformation.
class CorSkinning {
 public:
  /// Precomputes p*_i (both cores). \throw InputError for bad options or sizes.
  CorSkinning(const track::Positions& rest, const track::Triangles& triangles, const SkinWeights& weights,
              const CorOptions& options = {}, std::size_t grain = 64);
  ~CorSkinning();

  /// `out` (#V × 3) = the CoR skin for the skinning matrices `skin` (their rigid parts rotate,
  /// the full matrices move the centers). parallel_for(grain); grain 0 = serial, same result.
  void deform(const std::vector<Affine>& skin, track::Positions& out, std::size_t grain = 1024) const;

  /// The center of vertex i; NaN-free. `has_center(i)` false: the vertex takes the fallback.
  Eigen::Vector3d center(int vertex) const;
  bool has_center(int vertex) const;
  int fallback_vertices() const;  ///< multi-influence vertices without a similar triangle
  double precompute_seconds() const;
  const CorOptions& options() const;

 private:
  struct Data;
  std::unique_ptr<Data> d_;
};

}  // namespace isokit::skinning
