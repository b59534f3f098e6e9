// SPDX-License-Identifier: MIT
// The tangential ARAP system of one relaxation iteration and its conjugate-gradient solver
// (2014 §5.2; TrackerOptions::relaxation = kConjugateGradient; not installed).
#pragma once

#include <cstdint>
#include <vector>

#include "isokit/core/math.h"
#include "isokit/track/mesh.h"

namespace isokit::track::detail {

/// The tangential ARAP system of one relaxation step (2014 §5.2, solved instead of one Jacobi
/// sweep): unknown displacements d_i of the listed vertices, the others held in place,
/// `(Σj wij / s_i) d_i - Σ_{j unknown} wij dj = Σj wij ((pj - pi) + tij)`, each row and d_i
/// restricted to the tangent plane of `normals[i]` unless `free3d[i]` (a contact vertex) or
/// `free_vertices[i]` (not held to its iso-value; may be null). Per-vertex arrays are
/// indexed by vertex, `weights` and `targets` by directed edge.
struct TangentProblem {
  const Adjacency* adj{nullptr};
  const float* weights{nullptr};
  const float* weight_sums{nullptr};
  const Vec3f* targets{nullptr};
  const Vec3f* positions{nullptr};
  const Vec3f* normals{nullptr};
  const std::uint8_t* free3d{nullptr};
  const std::uint8_t* free_vertices{nullptr};
  const float* scale{nullptr};  ///< s_i in (0, 1]: mask × damping
  /// Anchor stiffness k_i in [0, 1) and anchors a_i (null: none): row i gains
  /// `Σj wij k_i / (1 − k_i) (a_i − p_i − d_i)` (IsoSurfaceTracker::set_anchor_stiffness).
  const float* anchor_k{nullptr};
  const Vec3f* anchors{nullptr};
  float tolerance{0};  ///< stop when every |r_i| / diag_i is below this (a Jacobi step)
  int max_iterations{100};
};

/// Jacobi-preconditioned conjugate gradient on `p` (filtered PCG). `local` has one entry per
/// vertex, all -1 (restored on return); `d` receives one displacement per unknown. Serial and
/// deterministic. Returns the CG iterations run.
int solve_tangential_cg(const TangentProblem& p, const std::vector<int>& unknowns, std::vector<int>& local,
                        std::vector<Vec3f>& d);

}  // namespace isokit::track::detail
