// SPDX-License-Identifier: MIT
// The energy tracker's local step: the field at the current positions, the per-vertex ARAP
// rotations (Sorkine & Alexa 2007), the target search and the monotone guard (energy_tracker.h).
#include <algorithm>
#include <cmath>

#include <Eigen/Core>

#include "energy_model.h"
#include "field_eval.h"
#include "isokit/core/parallel.h"
#include "isokit/core/rotation_fit.h"

namespace isokit::track::detail {

namespace {

// Resets per vertex and call (see `replaces`).
constexpr std::uint8_t kMaxResets = 2;

Mat3d to_mat3(const Eigen::Matrix3d& r) {
  Mat3d out;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) out(a, b) = r(a, b);
  return out;
}

// A candidate replaces the target if there is none yet; or if it is not farther from xi by the
// target term's distance and misses its iso-value by no more than iso_tolerance or than the old
// target (a closer target that misses by more would let the ARAP term drag the vertex away from
// where the search still finds its iso-value, and back: a 2-cycle); or (a reset) if the old
// target is off — it misses its iso-value by more than iso_tolerance, or (plane targets) its plane
// no longer locates the iso-surface near xi, the candidate lying farther beyond it than
// iso_tolerance / |∇f(xi)| — and the candidate misses by less. Only resets can raise E, and a
// vertex is reset at most kMaxResets times per call: where the field's gradient turns quickly
// two targets can each make the other's plane look stale, and without a budget the vertex
// would cycle between them.
bool replaces(const EnergyCall& c, const TargetSet& t, const TargetSet& cand, std::size_t i, bool& reset) {
  const EnergyData& m = c.m;
  if (t.kind[i] == TargetKind::kNone) return true;
  const float tol = m.options.iso_tolerance;
  const double dn = m.target_distance2(c.x[i], cand.point[i], cand.normal[i]),
               dold = m.target_distance2(c.x[i], t.point[i], t.normal[i]);
  if (dn <= dold && (cand.res[i] <= tol || cand.res[i] <= t.res[i])) return true;
  float miss = t.res[i];
  if (m.planes() && cand.kind[i] == TargetKind::kIso && dn > dold)
    miss = std::max(miss, float((std::sqrt(dn) - std::sqrt(dold)) * double(norm(c.grad[i]))));
  reset = miss > tol && cand.res[i] < miss && c.reset_count[i] < kMaxResets;
  return reset;
}

void accept_targets(EnergyCall& c, const TargetSet& cand) {
  const EnergyData& m = c.m;
  TargetSet& t = c.targets;
  std::vector<std::uint8_t> reset(m.n, 0);
  parallel_for(m.moving.size(), m.options.grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      const std::size_t i = std::size_t(m.moving[a]);
      bool r = false;
      if (!replaces(c, t, cand, i, r)) continue;
      reset[i] = r;
      c.reset_count[i] = std::uint8_t(c.reset_count[i] + r);
      t.point[i] = cand.point[i];
      t.normal[i] = cand.normal[i];
      t.res[i] = cand.res[i];
      t.kind[i] = cand.kind[i];
    }
  });
  c.resets = 0;
  for (std::uint8_t r : reset) c.resets += r;
}

}  // namespace

void fit_rotations(EnergyCall& c) {
  const EnergyData& m = c.m;
  // A pinned vertex whose neighbours are all pinned keeps its rotation through the call (its
  // one-ring does not move): fitted at the call's first local step only.
  const bool all = !c.frozen_rotations_fitted;
  const std::size_t count = all ? m.n : m.rotating.size();
  parallel_for(count, m.options.grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      const std::size_t i = all ? a : std::size_t(m.rotating[a]);
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();  // Σj wij (xi − xj)(pi − pj)ᵀ
      for (int k = m.adj.offsets[i]; k < m.adj.offsets[i + 1]; ++k) {
        const std::size_t j = std::size_t(m.adj.neighbors[std::size_t(k)]);
        const Vec3d d = m.rest[i] - m.rest[j], x = c.x[i] - c.x[j];
        cov += m.w[std::size_t(k)] * Eigen::Vector3d(x.x, x.y, x.z) * Eigen::RowVector3d(d.x, d.y, d.z);
      }
      c.rot[i] = to_mat3(procrustes_rotation(cov));
    }
  });
  c.frozen_rotations_fitted = true;
}

void local_step(EnergyCall& c) {
  const EnergyData& m = c.m;
  const std::size_t nm = m.moving.size();
  std::vector<Vec3f> pts(nm), grads(nm);
  std::vector<float> values(nm);
  std::vector<std::uint8_t> contact(nm);
  for (std::size_t a = 0; a < nm; ++a) {
    const Vec3d& p = c.x[std::size_t(m.moving[a])];
    pts[a] = {float(p.x), float(p.y), float(p.z)};
  }
  eval_field(c.field, pts.data(), nm, values.data(), grads.data(), contact.data(), m.options.grain);
  c.stats.field_evaluations += long(nm);
  for (std::size_t a = 0; a < nm; ++a) {
    const std::size_t i = std::size_t(m.moving[a]);
    c.value[i] = values[a];
    c.grad[i] = grads[a];
    c.field_contact[i] = contact[a];
  }
  fit_rotations(c);
  TargetSet cand;
  search_targets(c, cand);
  accept_targets(c, cand);
}

}  // namespace isokit::track::detail
