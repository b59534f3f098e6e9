// SPDX-License-Identifier: MIT
/// \file
/// The 2014 iso-surface tracker (Robust Iso-Surface Tracking, §5) over a triangle mesh.
///
/// Stages of one `track()` call, starting from the caller's initial positions (2014 §5 stage 1:
/// the previous result moved by the bones' rigid deltas); docs/tracking.md has the equations,
/// every deviation from the papers and the file of each stage ("Code map"):
/// 1. **Projection** (2014 §5 stage 2): up to `initial_newton_steps` Newton steps
///    `p <- p + σ (iso - f(p)) ∇f / |∇f|²` (2013 eq. 4, sign for inward gradients), clamped to
///    `max_step`.
/// 2. **Relaxation** (2014 §5 stage 3, eq. 3 – 4, §5.2): iterations of one step of the ARAP
///    energy `E = Σi Σj wij ||(p̂i - p̂j) - Ri (pi - pj)||²` (cotangent weights at rest,
///    prescribed Ri) restricted to the tangent plane of the last evaluated gradient and scaled by
///    the relaxation mask — a Jacobi sweep (Chebyshev-accelerated, Wang 2015) or a CG solve
///    (`relaxation`) — each followed by one Newton step, until the largest move is below
///    `tolerance` or `max_iterations`. Only the vertices near the last moves are updated (the
///    active set); with `lazy_evaluation`, short Newton steps use the field linearised at the
///    vertex's last evaluation.
/// 3. **Contacts** (2013 §5): flagged by the field, or (`angle_contacts`) the gradient turned by
///    more than `contact_angle_deg` between two evaluations — which also halves the vertex's
///    steps (floor `min_contact_damping`) and frees its Jacobi step from the tangent plane — or
///    (`fold_contacts`) a vertex of a triangle left inverted by the relaxation.
/// 4. **Contact smoothing** (2013 §5 eq. 7): Laplacian smoothing with diffused β.
/// 5. **Fold repair** (`fold_repair`, not in the papers): more smoothing around the triangles
///    still inverted. Then the **statistics** (TrackStats: residuals, contacts, inverted
///    triangles), which step 6 updates for the vertices it moves.
/// 6. **Orientation repair** (`orientation_repair`, not in the papers): single-vertex moves that
///    turn the last inverted triangles the right way, never through another triangle.
/// With `relaxation = Relaxation::kGlobal`, steps 1 and 2 are one solve instead: the exact
/// tangent-plane problem per iteration (factorised once per tracker, the factor kept between
/// calls), a line search on the ARAP energy, bracketed projections, until the convergence test of
/// TrackerOptions::tolerance (docs/tracking.md, "The global solve (option)").
/// All updates are double-buffered (Jacobi); results do not depend on `grain`.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "isokit/track/field.h"
#include "isokit/track/mesh.h"
#include "isokit/track/tracker_options.h"

namespace isokit::track {

namespace detail {
struct TrackerModel;
}

/// Stateful tracker: precomputes weights and adjacency, then tracks many times.
class IsoSurfaceTracker {
 public:
  /// \param rest `#V by 3` rest positions; \param triangles `#F by 3`;
  /// \param iso `#V` target iso-values (e.g. `sample_iso_values` at rest).
  /// \throw InputError naming the item for mismatched sizes, non-finite values, bad indices,
  /// or invalid options.
  IsoSurfaceTracker(const Positions& rest, const Triangles& triangles, std::vector<float> iso,
                    TrackerOptions options = {});
  IsoSurfaceTracker(const IsoSurfaceTracker& other);
  IsoSurfaceTracker(IsoSurfaceTracker&& other) noexcept;
  IsoSurfaceTracker& operator=(const IsoSurfaceTracker& other);
  IsoSurfaceTracker& operator=(IsoSurfaceTracker&& other) noexcept;
  ~IsoSurfaceTracker();

  /// Per-vertex relaxation mask in [0, 1] (0 = no tangential move; default all 1).
  /// \throw InputError for a wrong size or a value outside [0, 1], or a value below 1 with
  /// Relaxation::kEnergy (no tangential step there: use `set_anchor_stiffness(1 - mask)`).
  void set_relaxation_mask(std::vector<float> mask);

  /// Per-vertex anchor stiffness k in [0, 1] (default all 0): the painted mask of 2014 Fig. 11 as a
  /// term of the solve (not in the papers' form; docs/tracking.md, "Anchors"). A vertex with k > 0
  /// is pulled toward its anchor (the `anchors` of `track`): its tangential step becomes (1 − k)
  /// times the ARAP step plus k times the way to the anchor (Jacobi), i.e. the ARAP energy gains
  /// `Σj wij · k / (1 − k) · ||pi − ai||²` (CG and global solves), while the projection keeps it
  /// on its iso-value. k = 1 pins the vertex: it is placed at its anchor and is neither projected,
  /// relaxed, smoothed nor repaired, while its neighbours see it where it is.
  /// \throw InputError for a wrong size or a value outside [0, 1].
  void set_anchor_stiffness(std::vector<float> stiffness);

  /// Changes TrackerOptions::max_iterations for the next calls (count, ≥ 0): a live preview
  /// spends a bounded time per call and continues the solve by calling again at the same pose.
  /// \throw InputError for a negative count.
  void set_max_iterations(int iterations);

  /// A test run before each relaxation iteration of the next calls (empty, the default: none),
  /// for a live preview that bounds its time per call: kStop ends the relaxation as the iteration
  /// cap does (TrackStats::converged false, TrackStats::interrupted true) and the call runs its
  /// closing stages (a frame to show, whose solve another call at the same pose may continue);
  /// kAbandon returns at once with the positions where the relaxation stopped, for a caller that
  /// will track them to a newer pose (TrackStats::abandoned; the flags stay the last finished
  /// call's).
  void set_interrupt(std::function<TrackInterrupt()> interrupt);

  /// Vertices the fold and orientation repairs may move (1) or must leave in place (0); empty (the
  /// default): all.
  /// For callers that know where the mesh under-resolves the field (e.g. limbs of a few dozen
  /// vertices, where smoothing would erase the shape); Relaxation::kEnergy has no repair and
  /// ignores it. \throw InputError for a wrong size.
  void set_fold_repair_mask(std::vector<std::uint8_t> mask);

  /// Records the triangles that are inverted at rest with respect to `rest_field` (the field at
  /// the rest pose: a composed field can disagree with the rest mesh in concave creases). With
  /// `fold_contacts`, those triangles are not treated as folds (their vertices are not smoothed
  /// in every call). \throw InputError for an empty field.
  void mark_rest_inversions(const FieldFunction& rest_field);

  /// Tells the tracker the field at the rest pose: records the rest inversions
  /// (`mark_rest_inversions`) and finds the free vertices, where the field disagrees with the rest
  /// mesh (TrackerOptions::free_vertex_angle_deg: the field's inward direction at the rest
  /// position against the inward area-weighted vertex normal); see `flags().free`. Without this
  /// call every vertex is held to its iso-value. \throw InputError for an empty field.
  void set_rest_field(const FieldFunction& rest_field);

  /// Tracks the field from `positions` (in: initial guess, out: result).
  /// \param rotations `#V` target rotations Ri, or empty for identity.
  /// \throw InputError for wrong sizes or non-finite positions / rotations.
  TrackStats track(const FieldFunction& field, const std::vector<Mat3f>& rotations, Positions& positions);

  /// As above, with this call's anchors (`#V by 3`, e.g. each vertex moved rigidly by its nearest
  /// bone) for the vertices of non-zero anchor stiffness; without them (the overload above) the
  /// anchors are the initial positions. \throw InputError for a wrong size or non-finite anchors.
  TrackStats track(const FieldFunction& field, const std::vector<Mat3f>& rotations, Positions& positions,
                   const Positions& anchors);

  /// Per-vertex flags of the last call, in the caller's vertex order.
  const VertexFlags& flags() const;
  /// One-ring adjacency in the caller's vertex order (built on each call).
  Adjacency adjacency() const;
  /// Cotangent weights aligned with `adjacency().neighbors` (symmetric, ≥ 0; built on each call).
  std::vector<float> weights() const;
  const TrackerOptions& options() const;

 private:
  std::unique_ptr<detail::TrackerModel> model_;  // libtrack/src/track_state.h
};

}  // namespace isokit::track
