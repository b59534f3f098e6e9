// SPDX-License-Identifier: MIT
// 2014 stage 3: the relaxation's convergence loop, over a relaxation strategy (Jacobi or CG),
// each iteration one tangential move and one Newton projection (docs/tracking.md, step 2).
#include <algorithm>
#include <utility>

#include "isokit/core/parallel.h"
#include "jacobi_step.h"
#include "stages.h"

namespace isokit::track::detail {

namespace {

// The relaxation starts on the vertices whose first tangential step is longer than the
// tolerance, or that are still settling after the Newton steps: a vertex with a shorter step
// would move by less than the tolerance and is left until a neighbour moves (no field
// evaluation needed to find them). Without Newton steps nothing was evaluated: every vertex;
// without the active set (TrackerOptions::active_set), every vertex too.
void select_start(TrackState& s) {
  const TrackerOptions& o = s.m.options;
  if (o.max_iterations <= 0) return;
  if (o.initial_newton_steps == 0 || !o.active_set) {
    s.active = s.set.all();
    return;
  }
  std::vector<std::uint8_t> start(s.n, 0);
  for (int i : s.active) start[i] = 1;
  const JacobiTerms t = jacobi_terms(s);
  parallel_for(s.n, o.grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      if (start[i] || !relaxes(s, t, i) || s.normal[i] == Vec3f{}) continue;
      const float scale = s.m.mask[i] * s.damping[i];
      if (squared_norm(jacobi_delta(t, s.cur.data(), i, s.cur[i])) * scale * scale > s.tol2) start[i] = 1;
    }
  });
  s.active.clear();
  for (std::size_t i = 0; i < s.n; ++i)
    if (start[i]) s.active.push_back(static_cast<int>(i));
}

// Called when no vertex moved by more than the tolerance: true if the call has converged. With
// lazy evaluation, the vertices moved on a linearised field since their last evaluation are
// evaluated once more first (they become the active set of a `force`d iteration), unless the
// last iteration was that one (`verified`).
bool settle(TrackState& s, bool verified) {
  if (verified || !s.lazy_on) return true;
  s.active.clear();
  for (std::size_t i = 0; i < s.n; ++i)
    if (s.pending[i]) s.active.push_back(static_cast<int>(i));
  return s.active.empty();
}

// One iteration k: the strategy's tangential move and one Newton sweep. True when converged.
bool iterate(TrackState& s, RelaxationStrategy& strategy, int k) {
  if (s.active.empty()) {
    if (settle(s, s.force)) return true;
    s.force = true;
  }
  strategy.before_sweep(s, k);
  s.stats.vertex_updates += static_cast<long>(s.active.size());
  s.stats.max_move = sweep(s, true, s.force);
  strategy.after_sweep(s);
  s.stats.iterations = k + 1;
  const bool verified = std::exchange(s.force, false);
  if (s.stats.max_move <= s.tol) {
    if (settle(s, verified)) return true;
    s.force = true;
  }
  return false;
}

}  // namespace

void relax(TrackState& s, RelaxationStrategy& strategy) {
  select_start(s);
  for (int k = 0; k < s.m.options.max_iterations; ++k) {
    if (interrupted(s)) break;
    if (iterate(s, strategy, k)) {
      s.stats.converged = true;
      break;
    }
  }
  if (s.m.options.max_iterations == 0) s.stats.converged = true;
  // Stopped by the iteration cap: the vertices last moved on a linearised field take one
  // evaluated Newton step (no tangential step), so that none ends on a linearisation.
  // (Not when abandoned: the positions are a starting guess for the caller's next call.)
  if (!s.stats.converged && !s.stats.abandoned && s.lazy_on && !settle(s, false)) sweep(s, false, true);
  s.stats.field_evaluations = s.evaluations;
  if (s.first) std::fill(s.touched.begin(), s.touched.end(), std::uint8_t{1});  // nothing evaluated yet
}

}  // namespace isokit::track::detail
