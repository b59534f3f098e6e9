// SPDX-License-Identifier: MIT
/// \file
/// Direct Delta Mush (Le & Lewis 2019, "Direct Delta Mush Skinning and Variants"): Delta Mush's
/// smooth deformation in closed form. A precomputation gives, for each vertex i and bone j, the
/// symmetric 4×4 matrix
///
///     Ω_ij = Σ_k B_ik w_kj p̃_k p̃_kᵀ          (p̃_k = [p_k; 1], the rest vertex k)
///
/// with B the Laplacian smoothing matrix (below); per frame, with the skinning matrices M_j,
///
///     Q_i = Σ_j M_j Ω_ij = [ Q̂  q ]        R_i = polar(Q̂ − q p̄ᵀ / s)    t_i = q / s − R_i p̄ / s
///                         [ p̄ᵀ s ]        u_i = R_i p_i + t_i
///
/// i.e. the rigid transform that best maps the rest neighbourhood of i, weighted by B_ik w_kj, to
/// its LBS images (a weighted Procrustes fit; the paper's derivation). `s` is 1 when the weights
/// sum to one; it is kept so that pruning (below) changes nothing at rest or under rigid motion.
///
/// Smoothing: each of `smoothing_steps` steps solves `(I + λ L) y = x` with L = I − D⁻¹A the
/// uniform (umbrella) Laplacian of the mesh graph: an implicit Laplacian smoothing step, so B is
/// row-stochastic and non-negative. It is factored once (SPD form `D + λ(D − A)`, CHOLMOD when
/// isokit_skinning has it, else SimplicialLDLT) and applied to the 10 distinct entries of
/// w_kj p̃_k p̃_kᵀ of every bone.
///
/// Storage is sparse: per vertex, the bones whose smoothed weight Σ_k B_ik w_kj is at least
/// `prune` times the vertex's largest; no #V × #B matrix is kept (the solve runs over blocks of
/// bones). Rotations (max tr(Rᵀ A)) are extracted with the iteration of Müller et al. 2016,
/// started from the vertex's dominant bone (exact in zero steps at rest and under a rigid motion
/// of the whole skeleton), and with the SVD where it has not converged in 8 steps.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "isokit/core/math.h"
#include "isokit/skinning/rig.h"
#include "isokit/track/mesh.h"

namespace isokit::skinning {

/// Which closed form (docs/skinning.md, "Direct Delta Mush").
enum class DdmVariant {
  /// The paper's full form: rotation and translation from the same λ-smoothed Ω (default).
  kV0,
  /// Rotation from the λ-smoothed Ω, translation from centroids smoothed with κ instead: κ < λ
  /// keeps the skin's position closer to the vertex's own LBS (less shrinkage), κ = λ is v0.
  kV1,
};

/// Options of Direct Delta Mush. Changing them means precomputing anew.
struct DdmOptions {
  /// Implicit smoothing steps p (count, ≥ 0; 0 = no smoothing: Ω_ij = w_ij p̃_i p̃_iᵀ and the
  /// result is LBS). Default 3. Setup key `ddm.smoothing_steps`.
  int smoothing_steps{3};
  /// λ, the amount of each smoothing step (dimensionless, in [0, 1000]; a step spreads a vertex's
  /// weight over about √(2λ) rings of the mesh graph). Default 3. Setup key `ddm.lambda`.
  double lambda{3.0};
  /// κ, the smoothing amount of the translation's centroids (variant v1 only; same unit and
  /// range as λ; κ = λ gives v0). Default 1. Setup key `ddm.kappa`.
  double kappa{1.0};
  /// α, the weight of the vertex's own LBS transform in its fit, in [0, 1]:
  /// Ω_ij ← (1 − α) Ω_ij + α w_ij p̃_i p̃_iᵀ (0 = the pure smoothed fit, 1 = LBS). Default 0.
  /// Setup key `ddm.alpha`.
  double alpha{0.0};
  DdmVariant variant{DdmVariant::kV0};  ///< setup key `ddm.variant`: "v0" (default) or "v1"
  /// Relative smoothed weight below which a bone is dropped from a vertex's Ω, in [0, 0.5)
  /// (0 = keep every bone). Not in the paper (sparse storage). Default 1e-3. Key `ddm.prune`.
  double prune{1e-3};
};

/// \throw InputError naming `where` + the key for an option out of range.
void check_ddm_options(const DdmOptions& o, const std::string& where);
DdmVariant ddm_variant_from_string(const std::string& s, const std::string& where);
const char* to_string(DdmVariant v);

/// The precomputed Ω of a mesh, and the per-frame deformation.
class DirectDeltaMush {
 public:
  /// Precomputes Ω (sparse, see the file comment). `joints` = number of skinning matrices.
  /// \throw InputError for bad options (naming the `ddm.` key) or sizes.
  DirectDeltaMush(const track::Positions& rest, const track::Triangles& triangles, const SkinWeights& weights,
                  int joints, const DdmOptions& options = {});
  ~DirectDeltaMush();

  /// `out` (resized to #V × 3) = the DDM skin for the skinning matrices `skin` (rigid parts
  /// used for nothing special: affine matrices are fitted as they are). Both cores via
  /// parallel_for(grain); grain 0 = serial, same result.
  void deform(const std::vector<Affine>& skin, track::Positions& out, std::size_t grain = 1024) const;

  /// Ω_ij as stored (zero when pruned). For tests and inspection.
  Eigen::Matrix4d omega(int vertex, int joint) const;
  std::size_t stored_pairs() const;   ///< (vertex, bone) pairs kept
  double precompute_seconds() const;  ///< wall time of the precomputation
  const DdmOptions& options() const;

 private:
  struct Data;
  std::unique_ptr<Data> d_;
};

}  // namespace isokit::skinning
