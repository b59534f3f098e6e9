// SPDX-License-Identifier: MIT
// The global per-frame solve of the 2014 tracker (TrackerOptions::relaxation = kGlobal;
// docs/tracking.md, "The global solve"; docs/decisions/global-tangent-solve.md): the tangent-plane
// ARAP problem of 2014 eq. 3 – 4 solved exactly at each iteration, alternated with safeguarded
// Newton projections (not installed).
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "isokit/core/math.h"
#include "track_state.h"

namespace isokit::track::detail {

/// Any unit vector perpendicular to the unit vector n.
Vec3f perpendicular(const Vec3f& n);

/// A symmetric 3 × 3 tensor: xx, yy, zz, xy, xz, yz.
using Sym3 = std::array<float, 6>;

/// The reduced tangent-plane system `Tᵀ (L + D) T u = Tᵀ g` of one iteration and its solver, kept
/// between calls: L is the cotangent Laplacian of the rest mesh (⊗ I3), D the diagonal of the
/// regularisation and the relaxation mask, T the per-vertex tangent bases (3 × 2; 3 × 3 for a
/// free vertex; none for a vertex with mask 0), g the ARAP residual `Σj wij ((pj - pi) + tij)`.
/// The pattern is analysed once; the numeric factor is reused across iterations and calls as
/// the preconditioner of a conjugate-gradient solve, and refactored when that solve slows down.
class TangentSolver {
 public:
  TangentSolver();
  ~TangentSolver();
  TangentSolver(const TangentSolver&) = delete;
  TangentSolver& operator=(const TangentSolver&) = delete;

  /// Solves for the tangential displacements `d` (one per vertex, 0 for fixed ones) at the
  /// call's positions `s.cur`; `normals[i]` is the plane normal of vertex i (unit; 0 = hold the
  /// vertex in place this iteration); `curvature[i]` is the constraint's curvature term of the
  /// Lagrangian's Hessian at vertex i (`μi ∇²f`, 3 × 3, restricted to the tangent plane here;
  /// its 2 × 2 eigenvalues are clamped to ≥ -½ Σj wij, and to ≥ 0 if the matrix is then not
  /// positive definite). Adds the CG iterations and factorisations to the stats.
  void solve(TrackState& s, const std::vector<Vec3f>& normals, const std::vector<Sym3>& curvature,
             std::vector<Vec3f>& d);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// 2014 stages 2 and 3 as one convergent solve (global_solve.cpp): Newton projection of the
/// initial guess, then iterations of (tangent-plane ARAP solve, Newton projection) until the
/// convergence test of TrackerOptions::relaxation holds, the iterations stagnate, or the cap.
void solve_frame(TrackState& s, TangentSolver& solver);

}  // namespace isokit::track::detail
