// SPDX-License-Identifier: MIT
// The 2014 tracker's data: what it precomputes once (`TrackerModel`) and what one `track()` call
// works on (`TrackState`), in the tracker's internal vertex order (not installed).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "active_set.h"
#include "isokit/core/math.h"
#include "isokit/track/energy_tracker.h"
#include "isokit/track/field.h"
#include "isokit/track/mesh.h"
#include "isokit/track/tracker_options.h"

namespace isokit::track::detail {

// Relaxation iterations before the Chebyshev acceleration starts (Wang 2015 uses 10): the first
// iterations are dominated by the Newton projection of the initial guess, not by the linear part.
constexpr int kChebyshevDelay = 10;
// The Chebyshev extrapolation assumes a linear iteration: a vertex whose gradient turned by more
// than this between its last two evaluations (a crease, a contact valley) takes a plain Jacobi step.
// The lazy evaluation uses the same bound for "a smooth part of the field".
constexpr float kChebyshevMaxTurnDeg = 10.f;
// Fold test: a triangle is tested at its centroid when its normal deviates from the outward
// direction at one of its vertices by more than this (an inverted one deviates by more than 90°).
constexpr float kFoldCandidateDeg = 45.f;

class TangentSolver;  // global_solve.h

/// The global solve's factorisation and tangent bases, kept between calls (TrackerOptions::
/// relaxation = kGlobal): a cache, so a copy starts empty and `reset()` follows a change of the
/// unknowns' layout (relaxation mask, free vertices).
class TangentSolverCache {
 public:
  TangentSolverCache();
  ~TangentSolverCache();
  TangentSolverCache(const TangentSolverCache&);
  TangentSolverCache& operator=(const TangentSolverCache&);
  TangentSolverCache(TangentSolverCache&&) noexcept;
  TangentSolverCache& operator=(TangentSolverCache&&) noexcept;
  void reset();
  TangentSolver& get();  ///< built on first use

 private:
  std::unique_ptr<TangentSolver> solver_;
};

/// What the tracker precomputes at construction (IsoSurfaceTracker's data). Per-vertex arrays are
/// in the internal order: internal vertex k is the caller's vertex `order[k]` (empty: the same
/// order), `rank` the inverse.
struct TrackerModel {
  TrackerOptions options;
  std::vector<int> order, rank;
  Triangles triangles;
  std::vector<Vec3f> rest;
  std::vector<float> iso;
  Adjacency adj;                              // one-ring
  Adjacency vertex_faces;                     // CSR: the triangles around each vertex
  std::vector<float> weights;                 // cotangent weights per directed edge (adj.neighbors)
  std::vector<float> weight_sum;              // per vertex
  std::vector<float> max_step;                // longest Newton step per vertex
  std::vector<float> mask;                    // relaxation mask
  std::vector<float> anchor_k;                // anchor stiffness (empty: all 0)
  std::vector<std::uint8_t> repair_mask;      // fold / orientation repair: may move (empty: all)
  std::vector<float> lazy_r2;                 // squared lazy evaluation radius bound per vertex
  float diagonal{0};                          // rest bounding-box diagonal
  std::vector<std::uint8_t> rest_inverted;    // per triangle (empty: none recorded)
  std::vector<std::uint8_t> free;             // per vertex: free vertex (set_rest_field; all 0 before)
  TangentSolverCache global;                  // kGlobal: factor and bases between calls
  std::function<TrackInterrupt()> interrupt;  // set_interrupt: tested before each iteration
  std::optional<EnergyTracker> energy;        // Relaxation::kEnergy: the whole call, caller's order
  // Outputs of the last call.
  VertexFlags flags;                        // caller's order
  std::vector<std::uint8_t> last_inverted;  // per triangle, at the end of the last call

  /// The caller's index of internal vertex i.
  std::size_t caller(std::size_t i) const { return order.empty() ? i : std::size_t(order[i]); }
};

/// Everything one `track()` call reads and writes, passed to every stage (stages.h).
struct TrackState {
  /// Sets up the call: `initial` (internal order) becomes every position buffer, the per-edge
  /// ARAP targets are computed from `rotations` (empty: identity), every vertex is active.
  TrackState(const TrackerModel& model, const FieldFunction& field, const std::vector<Mat3f>& rotations,
             std::vector<Vec3f> initial);

  const TrackerModel& m;
  const FieldFunction& field;
  const std::size_t n;

  // Constants of the call.
  const bool cg;       // Relaxation::kConjugateGradient
  const bool lazy_on;  // TrackerOptions::lazy_evaluation
  const float cos_contact, cos_linear, min_g2, tol, tol2, rho2;

  // Three position buffers: x_{k-1} (`prev`, for the Chebyshev step), x_k (`cur`), x_{k+1}.
  // Only the active vertices are written; for the others next = cur = prev.
  std::vector<Vec3f> prev, cur, next;
  // Per directed edge (i, j), constant during the call: ½ (Ri + Rj)(pi - pj) at rest (= pi - pj
  // exactly for identity rotations, so the rest pose gives δ = 0 bit for bit).
  std::vector<Vec3f> targets;
  std::vector<Vec3f> normal;   // ∇f/|∇f| at the last evaluation (0: none yet)
  std::vector<float> values;   // f at the last evaluation
  std::vector<float> moves;    // squared length of the last move
  std::vector<float> damping;  // contact damping of the Newton and tangential steps
  // CG relaxation: a vertex whose Newton steps overshoot (the residual changes sign without
  // halving: a 2-cycle across a kink of the field) has its Newton steps halved for the rest of the
  // call, down to 1/16; the Jacobi relaxation keeps the paper's plain Newton steps.
  std::vector<float> last_residual, newton_scale;
  std::vector<std::uint8_t> field_contact;  // the field's contact flag at the last evaluation
  std::vector<std::uint8_t> moved;          // moved by more than the tolerance (active set input)
  std::vector<std::uint8_t> touched;        // moved after the first evaluation, or smoothed
  std::vector<std::uint8_t> linear;         // gradient turned by < kChebyshevMaxTurnDeg last time
  VertexFlags flags;                        // contact, lost, β (internal order)
  std::vector<Vec3f> anchors;               // the call's anchors (empty: no anchor stiffness)

  /// Anchor stiffness of vertex i (set_anchor_stiffness), 0 without.
  float stiffness(std::size_t i) const { return m.anchor_k.empty() ? 0.f : m.anchor_k[i]; }
  /// Vertex i is pinned to its anchor (stiffness 1): no move of any stage.
  bool pinned(std::size_t i) const { return !m.anchor_k.empty() && m.anchor_k[i] >= 1.f; }

  // Compact per-iteration buffers of the evaluated vertices (field input and output, vertex).
  std::vector<Vec3f> batch_points, batch_gradients;
  std::vector<float> batch_values;
  std::vector<std::uint8_t> batch_contact;
  std::vector<int> batch_vertex;

  // Lazy evaluation: where the field was last evaluated and its gradient there, whether the vertex
  // may take linearised Newton steps (`lazy`), whether it moved since its last evaluation
  // (`pending`), and its squared trust radius (starts at twice the tolerance, then follows the
  // error measured at each evaluation after lazy steps; at most lazy_r2).
  std::vector<Vec3f> eval_points, eval_gradients;
  std::vector<std::uint8_t> lazy, pending;
  std::vector<float> radius2;
  std::atomic<long> evaluations{0};

  ActiveSet set;
  std::vector<int> active;  // the vertices the next sweep updates, ascending
  bool first{true};         // the first evaluation covers every vertex and does not mark it touched
  bool force{false};        // the next sweep evaluates every active vertex (no lazy step)
  float omega{1.f};         // Chebyshev weight of the current iteration (1: plain Jacobi)
  std::vector<Vec3f> disp;  // CG: per-vertex tangential displacement (empty: Jacobi)

  // After the relaxation: inverted flags per triangle, and those the fold repair tested at the
  // final positions (empty: none).
  std::vector<std::uint8_t> inverted, fresh;
  TrackStats stats;
};

/// The caller's interrupt (IsoSurfaceTracker::set_interrupt) asks the relaxation to stop or to
/// abandon the call: noted in the call's statistics.
inline bool interrupted(TrackState& s) {
  const TrackInterrupt q = s.m.interrupt ? s.m.interrupt() : TrackInterrupt::kContinue;
  if (q == TrackInterrupt::kContinue) return false;
  s.stats.interrupted = true;
  s.stats.abandoned = q == TrackInterrupt::kAbandon;
  return true;
}

}  // namespace isokit::track::detail
