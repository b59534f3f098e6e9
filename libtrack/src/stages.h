// SPDX-License-Identifier: MIT
// The stages of one 2014 tracker call (IsoSurfaceTracker::track), each a function of the call's
// state (track_state.h), each in its own file (docs/tracking.md, "Code map"; not installed).
#pragma once

#include <memory>

#include "track_state.h"

namespace isokit::track::detail {

/// One sweep over the active vertices (sweep.cpp): with `relax`, each takes its tangential move
/// (the Jacobi step, or the CG displacement in `disp`), then one field evaluation — or, with lazy
/// evaluation and unless `evaluate_all`, the field linearised at its last evaluation — and one
/// Newton step. Commits the moves (double-buffered), updates the active set, and returns the
/// largest move.
float sweep(TrackState& s, bool relax, bool evaluate_all = false);

/// 2014 stage 2 (projection.cpp): up to `initial_newton_steps` Newton sweeps, stopping early when
/// the largest move is below the tolerance.
void project(TrackState& s);

/// At the iteration cap, with lazy evaluation (projection.cpp): the vertices last moved on a
/// linearised field take one evaluated Newton step, so that none ends on a linearisation.
void finish_linearised(TrackState& s);

/// How one relaxation iteration moves the active vertices in the tangent plane (2014 §5.2): the
/// strategy of the convergence loop `relax`.
class RelaxationStrategy {
 public:
  virtual ~RelaxationStrategy() = default;
  /// Before the sweep of iteration k (0-based).
  virtual void before_sweep(TrackState& s, int k) = 0;
  /// After that sweep.
  virtual void after_sweep(TrackState& s) = 0;
};

/// Jacobi sweeps, Chebyshev-accelerated (relax_jacobi.cpp; 2014 §5.2, Wang 2015).
std::unique_ptr<RelaxationStrategy> jacobi_relaxation();
/// The active vertices' tangential system solved by CG per iteration (relax_cg.cpp; 2014 §5.2).
std::unique_ptr<RelaxationStrategy> cg_relaxation(TrackState& s);

/// 2014 stage 3 (relaxation.cpp): picks the vertices the relaxation starts on, then iterates
/// `strategy` + one Newton sweep until no vertex moves by more than the tolerance (after the
/// lazily moved ones were evaluated again) or `max_iterations`.
void relax(TrackState& s, RelaxationStrategy& strategy);

/// Contacts (contacts.cpp; 2013 §5, docs/tracking.md step 3): the field's contact flags, and the
/// vertices of the triangles inverted after the relaxation (`fold_contacts`). Sets `inverted`.
void mark_contacts(TrackState& s);

/// β-diffused Laplacian smoothing at the contact vertices (contact_smoothing.cpp; 2013 §5 eq. 7).
void smooth_contacts(TrackState& s);

/// Fold repair (fold_repair.cpp; not in the papers, docs/tracking.md step 5).
void repair_folds(TrackState& s);

/// Final statistics (statistics.cpp): residuals, contact and lost counts, inverted triangles.
void collect_statistics(TrackState& s);

/// Orientation repair (orientation_repair.cpp; not in the papers, docs/tracking.md step 6), and
/// the statistics of the vertices it moved.
void repair_orientation(TrackState& s);

/// The number of vertices with β > 0.
int count_smoothed(const TrackState& s);

}  // namespace isokit::track::detail
