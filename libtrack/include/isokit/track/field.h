// SPDX-License-Identifier: MIT
/// \file
/// The field the tracker follows: any callable that evaluates value and gradient for a batch of
/// points (libtrack knows nothing about skeletons, HRBFs or libimplicit), plus the statistics
/// every tracking call returns.
///
/// \note Field convention: values in [0, 1], surface 0.5, inside > 0.5, gradients point inward,
/// compact support (0 value and 0 gradient outside). Triangles are counter-clockwise seen from
/// outside, so a correct triangle's normal points along `-∇f`.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "isokit/core/math.h"
#include "isokit/track/mesh.h"

namespace isokit::track {

/// Evaluates `n` points: writes `values[k]`, `gradients[k]`, and may set `contact[k] = 1` when
/// the point lies on a contact part of the field (`contact` arrives zero-filled; leave it alone
/// if the field knows nothing about contacts). Called concurrently from several threads on
/// disjoint ranges when the tracker's grain is > 0: it must be thread-safe.
using FieldFunction = std::function<void(const Vec3f* points, std::size_t n, float* values, Vec3f* gradients,
                                         std::uint8_t* contact)>;

/// `iso[v] = f(positions[v])` (per-vertex target iso-values sampled at rest, 2013 §5).
/// \throw InputError if a position is not finite or the field returns a non-finite value.
std::vector<float> sample_iso_values(const FieldFunction& field, const Positions& positions);

/// What IsoSurfaceTracker::set_interrupt's test asks of the call in progress.
enum class TrackInterrupt { kContinue, kStop, kAbandon };

/// What a tracking or projection call did.
struct TrackStats {
  int iterations{0};  ///< relaxation iterations (2014: Jacobi + Newton; 2013: Newton steps)
  /// Vertex updates of the relaxation (2014 tracker: the sum of the active-set sizes over its
  /// iterations, at most `iterations * #V`; 2013 projector: the Newton steps taken, summed over
  /// the vertices still moving).
  long vertex_updates{0};
  /// Field evaluations of the Newton and relaxation iterations (fewer than the vertex updates with
  /// the 2014 tracker's lazy evaluation; the final statistics' evaluations are not counted).
  long field_evaluations{0};
  /// CG iterations summed over the relaxation (kConjugateGradient; kGlobal: the preconditioned CG
  /// iterations of its tangential solves, 0 for a solve by a fresh factorisation; kEnergy with
  /// plane targets: the preconditioned CG iterations of its global steps)
  long solver_iterations{0};
  /// kGlobal: numeric factorisations of the tangential system in the call; kEnergy: of its global
  /// step's matrix `2 L + W + K`, taken at construction and after a stiffness change, never in a call
  int factorizations{0};
  int backtracks{0};  ///< kGlobal: line-search step halvings in the call
  /// kGlobal: the tangential residual of TrackerOptions::tolerance at the end of the call (the
  /// smaller of the largest move the last solve asked for and the last iteration's largest move;
  /// 0 for the other solvers)
  float tangential_residual{0};
  bool converged{false};  ///< the convergence test of TrackerOptions::tolerance held before the cap
  /// The relaxation stopped early at the caller's request (IsoSurfaceTracker::set_interrupt).
  bool interrupted{false};
  /// The call was abandoned (TrackInterrupt::kAbandon): the positions are where the relaxation
  /// stopped, the closing stages did not run, flags and residual statistics are not this call's.
  bool abandoned{false};
  float max_move{0};       ///< largest vertex move in the last iteration
  float max_residual{0};   ///< max |f(v) - iso_v| over vertices outside the smoothed contact region, not free
  float mean_residual{0};  ///< mean of the same
  int contact_vertices{0};   ///< vertices flagged by the field or stopped by the gradient-angle rule
  int smoothed_vertices{0};  ///< vertices with diffused beta > 0 (moved by contact smoothing)
  int oriented_vertices{0};  ///< vertices moved by the orientation repair (2014 tracker)
  int lost_vertices{0};      ///< zero / non-finite gradient: left in place (e.g. outside the support)
  /// 2013 projector: vertices stopped for making no progress (ProjectorOptions::stall_steps)
  int stalled_vertices{0};
  int free_vertices{0};  ///< not held to their iso-value (VertexFlags::free; 2014 tracker)
  /// triangles whose normal points along +∇f at their centroid (2013 projector: 0 unless
  /// ProjectorOptions::count_inverted)
  int inverted_triangles{0};
  double seconds{0};  ///< wall time of the call
};

/// Per-vertex outputs of the last call (same order as the mesh vertices).
struct VertexFlags {
  std::vector<std::uint8_t> contact;  ///< 1 = contact vertex
  std::vector<std::uint8_t> lost;     ///< 1 = no usable gradient, left in place
  std::vector<float> beta;            ///< diffused smoothing weight in [0, 1]
  /// 1 = free vertex: the field at rest does not locate it (TrackerOptions::free_vertex_angle_deg),
  /// so it is not held to its iso-value (2014 tracker; empty for the 2013 projector).
  std::vector<std::uint8_t> free;
};

/// Counts triangles whose normal `(b - a) x (c - a)` points along `+∇f` at the centroid
/// (`dot > 0`); triangles where the field has a zero gradient are not counted.
int count_inverted_triangles(const FieldFunction& field, const Positions& positions,
                             const Triangles& triangles);

}  // namespace isokit::track
