// SPDX-License-Identifier: MIT
// The per-vertex Newton projection `p <- p + σ (iso - f(p)) ∇f / |∇f|²` (2014 §5 stage 2; 2013
// eq. 4 with the sign fixed, docs/tracking.md "Deviations"), its contact detection and damping,
// and the lazy evaluation's linearised step: inline, for the sweep's hot loop (not installed).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "points.h"
#include "track_state.h"

namespace isokit::track::detail {

/// The Newton step of vertex i for the gradient g (|g|² = g2) and the residual r = iso - f,
/// scaled by its contact damping and overshoot scale, at most `max_step` long; none for a free
/// vertex (TrackerOptions::free_vertex_angle_deg: not held to its iso-value).
inline Vec3f newton_step(const TrackState& s, std::size_t i, const Vec3f& g, float g2, float r) {
  if (s.flags.free[i]) return Vec3f{};
  Vec3f step = g * (s.m.options.sigma * s.damping[i] * s.newton_scale[i] * r / g2);
  const float len2 = squared_norm(step);
  const float max_step = s.m.max_step[i];
  if (len2 > max_step * max_step) step = step * (max_step / std::sqrt(len2));
  return step;
}

/// Lazy evaluation: if `q` (where vertex i moved from `p`, written at nx[i]) lies within the trust
/// radius of its last evaluation, takes the Newton step on the field linearised there and returns
/// true; false (nothing changed) otherwise.
inline bool linearised_newton(TrackState& s, std::size_t i, const Vec3f& p, const Vec3f& q, Vec3f* nx) {
  if (s.pinned(i)) {  // held at its anchor
    s.moves[i] = 0.f;
    return true;
  }
  const Vec3f d = q - s.eval_points[i];
  if (!(squared_norm(d) <= s.radius2[i])) return false;
  const Vec3f g = s.eval_gradients[i];
  nx[i] += newton_step(s, i, g, squared_norm(g), s.m.iso[i] - (s.values[i] + dot(g, d)));
  s.moves[i] = squared_norm(nx[i] - p);
  s.pending[i] = 1;
  return true;
}

/// Trust region of the linearisation: the error it made at nx[i] (evaluated: f), per unit of
/// displacement, sets how far the vertex may move on the next one (the composed gradient is not
/// the exact gradient of the composed value: see docs/tracking.md).
inline void update_trust_radius(TrackState& s, std::size_t i, float f, const Vec3f& at) {
  const Vec3f d = at - s.eval_points[i];
  const Vec3f ge = s.eval_gradients[i];
  const float err = std::abs(f - s.values[i] - dot(ge, d)) / std::sqrt(squared_norm(ge));
  const float dl = std::sqrt(squared_norm(d));
  const float r = 0.5f * s.tol * dl;
  const float bound = s.m.lazy_r2[i];
  s.radius2[i] = err * err * bound > r * r ? r * r / (err * err) : bound;
}

/// Vertex i was evaluated at nx[i] (from cu[i]): value f, gradient g, the field's contact flag
/// fc. Marks it lost (back to cu[i]) without a usable gradient; flags a turn of the gradient by
/// more than the contact angle (2013 §5) and halves its steps from then on, so that it settles on
/// the contact surface instead of oscillating across; then takes the Newton step.
inline void newton_update(TrackState& s, std::size_t i, float f, const Vec3f& g, std::uint8_t fc,
                          const Vec3f* cu, Vec3f* nx) {
  const TrackerOptions& o = s.m.options;
  const float g2 = squared_norm(g);
  if (s.pending[i] && finite(g) && std::isfinite(f)) update_trust_radius(s, i, f, nx[i]);
  s.values[i] = f, s.field_contact[i] = fc;
  s.pending[i] = 0;
  s.lazy[i] = 0;
  if (s.pinned(i)) {  // held at its anchor (its value is kept for the statistics)
    nx[i] = cu[i];
    s.moves[i] = 0.f;
    return;
  }
  if (s.flags.lost[i] || !std::isfinite(f) || !finite(g) || !(g2 > s.min_g2)) {
    s.flags.lost[i] = 1;
    nx[i] = cu[i];  // left in place
    s.moves[i] = 0.f;
    return;
  }
  const Vec3f nrm = g / std::sqrt(g2);
  const bool seen = s.normal[i] != Vec3f{};
  const float turn = dot(nrm, s.normal[i]);  // cosine of the turn since the last evaluation
  s.linear[i] = seen && turn >= s.cos_linear ? 1 : 0;
  if (seen && turn < s.cos_contact && !s.flags.free[i]) {  // a free vertex's gradient says nothing
    if (o.angle_contacts) s.flags.contact[i] = 1;
    s.damping[i] = std::max(s.damping[i] * 0.5f, o.min_contact_damping);
  }
  const float r = s.m.iso[i] - f;
  if (s.cg && seen && r * s.last_residual[i] < 0.f && std::abs(r) > 0.5f * std::abs(s.last_residual[i]))
    s.newton_scale[i] = std::max(s.newton_scale[i] * 0.5f, 1.f / 16.f);
  s.last_residual[i] = r;
  const Vec3f step = newton_step(s, i, g, g2, r);
  if (s.lazy_on && s.linear[i] && !s.flags.contact[i] && !s.field_contact[i] &&
      squared_norm(step) <= s.radius2[i]) {
    s.lazy[i] = 1;
    s.eval_points[i] = nx[i];
    s.eval_gradients[i] = g;
  }
  nx[i] += step;
  s.normal[i] = nrm;
  s.moves[i] = squared_norm(nx[i] - cu[i]);  // squared: one square root per iteration
}

}  // namespace isokit::track::detail
