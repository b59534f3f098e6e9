// SPDX-License-Identifier: MIT
// One sweep of the tracker over its active vertices: tangential step, field evaluation, Newton
// step (2014 §5.2: "one Jacobi iteration ... interleaved with one Newton projection"), then the
// double-buffered commit and the next active set.
#include <algorithm>
#include <cmath>

#include "field_eval.h"
#include "isokit/core/parallel.h"
#include "jacobi_step.h"
#include "newton_step.h"
#include "stages.h"

namespace isokit::track::detail {

namespace {

// The active vertices [b, e) of `active` (every vertex when `dense`): optional tangential step
// (the Jacobi step, reading `cur` and `prev`, or the CG displacement), written to `next`; then one
// Newton step in place on `next`, on the field evaluated there or — lazy evaluation, unless
// `evaluate_all` — linearised at the vertex's last evaluation. The points to evaluate are gathered
// into the compact buffers (positions [b, b + count) of the task's range) and evaluated in one call.
void sweep_range(TrackState& s, bool relax, bool dense, bool evaluate_all, std::size_t b, std::size_t e) {
  const Vec3f* cu = s.cur.data();
  const Vec3f* pv = s.prev.data();
  Vec3f* nx = s.next.data();
  const int* act = s.active.data();
  Vec3f* in = s.batch_points.data();
  float* val = s.batch_values.data();
  Vec3f* grd = s.batch_gradients.data();
  std::uint8_t* fcv = s.batch_contact.data();
  int* idx = s.batch_vertex.data();
  const JacobiTerms t = jacobi_terms(s);
  std::size_t count = b;
  for (std::size_t a = b; a < e; ++a) {
    const std::size_t i = dense ? a : static_cast<std::size_t>(act[a]);
    const Vec3f p = cu[i];
    Vec3f q = p;
    if (relax && !s.disp.empty())
      q = p + s.disp[i];
    else if (relax && relaxes(s, t, i))
      q = jacobi_target(s, t, cu, pv, i, p);
    nx[i] = q;
    if (!evaluate_all && s.lazy[i] && linearised_newton(s, i, p, q, nx)) continue;
    in[count] = q;
    idx[count++] = static_cast<int>(i);
  }
  eval_field(s.field, in + b, count - b, val + b, grd + b, fcv + b, 0);
  for (std::size_t a = b; a < count; ++a)
    newton_update(s, static_cast<std::size_t>(idx[a]), val[a], grd[a], fcv[a], cu, nx);
  s.evaluations += static_cast<long>(count - b);
}

// Commits x_{k+1} after every vertex has read its neighbours, flags the vertices that moved by
// more than the tolerance, and returns the largest squared move.
float commit(TrackState& s, bool dense) {
  float mx = 0.f;
  if (dense) {
    // Every vertex was written: rotate the buffers (Jacobi: x_{k+1} from x_k only).
    s.prev.swap(s.cur);  // prev <- x_k
    s.cur.swap(s.next);  // cur <- x_{k+1}; `next` is scratch
    for (std::size_t i = 0; i < s.n; ++i) {
      mx = std::max(mx, s.moves[i]);
      s.moved[i] = s.moves[i] > s.tol2 ? 1 : 0;
    }
    if (!s.first) std::fill(s.touched.begin(), s.touched.end(), std::uint8_t{1});
    return mx;
  }
  // For the inactive vertices prev = cur already (up to their last move, below the tolerance).
  // (Serial: a copy per vertex costs less than waking the other threads.)
  for (int i : s.active) {
    s.prev[i] = s.cur[i];  // prev <- x_k
    s.cur[i] = s.next[i];  // cur <- x_{k+1}
    mx = std::max(mx, s.moves[i]);
    s.moved[i] = s.moves[i] > s.tol2 ? 1 : 0;
    if (!s.first) s.touched[i] = 1;
  }
  return mx;
}

}  // namespace

float sweep(TrackState& s, bool relax, bool evaluate_all) {
  const bool dense = s.active.size() == s.n;
  // Active sets are often a few thousand vertices: smaller tasks keep both cores busy (the grain
  // changes no result).
  const std::size_t max_grain = s.m.options.grain;
  const std::size_t grain = max_grain == 0 ? 0 : std::clamp<std::size_t>(s.active.size() / 16, 64, max_grain);
  parallel_for(s.active.size(), grain,
               [&](std::size_t b, std::size_t e) { sweep_range(s, relax, dense, evaluate_all, b, e); });
  const float mx = commit(s, dense);
  s.first = false;
  s.set.update(s.active, s.moved);
  // Without the active set (2014): every vertex in the next sweep while any moved.
  if (!s.m.options.active_set && !s.active.empty()) s.active = s.set.all();
  return std::sqrt(mx);
}

}  // namespace isokit::track::detail
