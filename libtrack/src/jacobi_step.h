// SPDX-License-Identifier: MIT
// The per-vertex Jacobi step of the tangential ARAP energy (2014 eq. 3 and 4, §5.2) with its
// Chebyshev extrapolation (Wang 2015): inline, for the sweep's hot loop (not installed).
#pragma once

#include <cstdint>

#include "track_state.h"

namespace isokit::track::detail {

/// Raw pointers into the state for the hot loops: lets the compiler keep them in registers
/// across the stores to the position buffers.
struct JacobiTerms {
  const int* off;
  const int* nb;
  const float* w;
  const Vec3f* tg;
  const float* wsum;
  const Vec3f* nrms;
  const std::uint8_t* contact;
  const std::uint8_t* free;  // free vertices: 3D steps (TrackerOptions::free_vertex_angle_deg)
  const float* anchor_k;     // anchor stiffness (null: none)
  const Vec3f* anchors;      // the call's anchors (null: none)
};

inline JacobiTerms jacobi_terms(const TrackState& s) {
  JacobiTerms t;
  t.off = s.m.adj.offsets.data();
  t.nb = s.m.adj.neighbors.data();
  t.w = s.m.weights.data();
  t.tg = s.targets.data();
  t.wsum = s.m.weight_sum.data();
  t.nrms = s.normal.data();
  t.contact = s.flags.contact.data();
  t.free = s.flags.free.data();
  t.anchor_k = s.m.anchor_k.empty() ? nullptr : s.m.anchor_k.data();
  t.anchors = s.anchors.empty() ? nullptr : s.anchors.data();
  return t;
}

/// Tangential ARAP displacement of vertex i at `p` (Jacobi, neighbours fixed at `cu`), before the
/// mask: δ = Σ wij ((p̂j - p̂i) + ½ (Ri + Rj)(pi - pj)) / Σ wij, restricted to the current tangent
/// plane except at contact vertices, whose gradient direction is meaningless on the contact
/// valley (full 3D step, damped), and at free vertices, which the field does not locate (full 3D
/// step). Summed per edge, so that p̂ = p with Ri = I gives exactly δ = 0. With an anchor of
/// stiffness k (set_anchor_stiffness) the step is (1 − k) δ + k (ai − p): the Jacobi step of the
/// energy with the pull term k / (1 − k) Σj wij ||pi − ai||².
inline Vec3f jacobi_delta(const JacobiTerms& t, const Vec3f* cu, std::size_t i, const Vec3f& p) {
  Vec3f acc{};
  for (int k = t.off[i]; k < t.off[i + 1]; ++k) acc += ((cu[t.nb[k]] - p) + t.tg[k]) * t.w[k];
  Vec3f d = acc / t.wsum[i];
  if (t.anchor_k && t.anchor_k[i] > 0.f) d = d * (1.f - t.anchor_k[i]) + (t.anchors[i] - p) * t.anchor_k[i];
  const Vec3f nrm = t.nrms[i];
  if (!t.contact[i] && !t.free[i]) d = d - nrm * dot(d, nrm);
  return d;
}

/// Whether vertex i takes tangential steps: mask > 0, not lost, not isolated, not pinned.
inline bool relaxes(const TrackState& s, const JacobiTerms& t, std::size_t i) {
  return s.m.mask[i] > 0.f && !s.flags.lost[i] && t.off[i] < t.off[i + 1] && !s.pinned(i);
}

/// The Jacobi target of vertex i at `p` = x_k (`pv`: x_{k-1}), its step scaled by mask ×
/// damping. Chebyshev semi-iteration (omega != 1, on a smooth part of the field):
/// x_{k+1} = x_{k-1} + ω (x̂_{k+1} - x_{k-1}), i.e. the Jacobi target plus (ω - 1) times its
/// distance to x_{k-1}; that momentum is kept in the tangent plane (the Newton step handles the
/// normal direction) and scaled like the step. A free vertex, without Newton steps to damp the
/// momentum's normal part, takes the plain Jacobi step (with it, spikes of 3 – 4 edges grew on
/// the ninja's Attack2: docs/tracking.md, "Free vertices").
inline Vec3f jacobi_target(const TrackState& s, const JacobiTerms& t, const Vec3f* cu, const Vec3f* pv,
                           std::size_t i, const Vec3f& p) {
  const Vec3f nrm = t.nrms[i];
  const float scale = s.m.mask[i] * s.damping[i];
  Vec3f q = p + jacobi_delta(t, cu, i, p) * scale;
  if (s.omega != 1.f && s.linear[i] && !t.free[i]) {
    const Vec3f mom = q - pv[i];
    q += (mom - nrm * dot(mom, nrm)) * ((s.omega - 1.f) * scale);
  }
  return q;
}

}  // namespace isokit::track::detail
