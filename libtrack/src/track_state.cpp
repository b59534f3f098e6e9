// SPDX-License-Identifier: MIT
#include "track_state.h"

#include <algorithm>
#include <cmath>

#include "isokit/core/parallel.h"

namespace isokit::track::detail {

namespace {

// Per directed edge (i, j): ½ (Ri + Rj)(pi - pj) at rest (2014 eq. 3 with both ordered pairs).
std::vector<Vec3f> edge_targets(const TrackerModel& m, const std::vector<Mat3f>& rotations) {
  const Adjacency& adj = m.adj;
  const bool has_rot = !rotations.empty();
  std::vector<Vec3f> targets(adj.neighbors.size());
  parallel_for(m.rest.size(), m.options.grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i)
      for (int k = adj.offsets[i]; k < adj.offsets[i + 1]; ++k) {
        const int j = adj.neighbors[k];
        const Vec3f e_ij = m.rest[i] - m.rest[j];
        targets[k] = has_rot
                         ? (rotations[m.caller(i)] * e_ij + rotations[m.caller(std::size_t(j))] * e_ij) * 0.5f
                         : e_ij;
      }
  });
  return targets;
}

}  // namespace

TrackState::TrackState(const TrackerModel& model, const FieldFunction& f, const std::vector<Mat3f>& rotations,
                       std::vector<Vec3f> initial)
    : m(model),
      field(f),
      n(model.iso.size()),
      cg(model.options.relaxation == Relaxation::kConjugateGradient),
      lazy_on(model.options.lazy_evaluation),
      cos_contact(std::cos(model.options.contact_angle_deg * kPiF / 180.f)),
      cos_linear(std::cos(kChebyshevMaxTurnDeg * kPiF / 180.f)),
      min_g2(model.options.min_gradient * model.options.min_gradient),
      tol(model.options.tolerance * model.diagonal),
      tol2(tol * tol),
      rho2(model.options.chebyshev_rho * model.options.chebyshev_rho),
      prev(initial),
      cur(std::move(initial)),
      next(cur),
      targets(edge_targets(model, rotations)),
      normal(n, Vec3f{}),
      values(n),
      moves(n, 0.f),
      damping(n, 1.f),
      last_residual(n, 0.f),
      newton_scale(n, 1.f),
      field_contact(n, 0),
      moved(n, 0),
      touched(n, 0),
      linear(n, 0),
      batch_points(n),
      batch_gradients(n),
      batch_values(n),
      batch_contact(n),
      batch_vertex(n),
      eval_points(lazy_on ? n : 0),
      eval_gradients(lazy_on ? n : 0),
      lazy(n, 0),
      pending(n, 0),
      radius2(lazy_on ? n : 0),
      set(n, model.adj),
      active(set.all()) {
  flags.contact.assign(n, 0);
  flags.lost.assign(n, 0);
  flags.free = model.free;
  for (std::size_t i = 0; i < radius2.size(); ++i) radius2[i] = std::min(4.f * tol2, m.lazy_r2[i]);
}

}  // namespace isokit::track::detail
