// SPDX-License-Identifier: MIT
// The energy tracker's local step: the field at the current positions, the per-vertex ARAP
// rotations (Sorkine & Alexa 2007), the target search and the monotone guard (energy_tracker.h).
#include <cmath>

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SVD>

#include "energy_model.h"
#include "field_eval.h"
#include "isokit/core/parallel.h"

namespace isokit::track::detail {

namespace {

// Rotation minimising Σj wij ‖ej − R dj‖² for S = Σj wij dj ejᵀ: R = V Uᵀ (S = U Σ Vᵀ), with the
// sign of the singular vector of the smallest singular value flipped if that is a reflection.
Mat3d procrustes(const Eigen::Matrix3d& s) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(s, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  Eigen::Matrix3d r = svd.matrixV() * u.transpose();
  if (r.determinant() < 0) {
    u.col(2) = -u.col(2);  // JacobiSVD sorts the singular values in decreasing order
    r = svd.matrixV() * u.transpose();
  }
  Mat3d out;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) out(a, b) = r(a, b);
  return out;
}

// A candidate replaces the target if it is not farther from xi, or if there is none yet, or if
// the old one misses its iso-value by more than iso_tolerance and the candidate by less (a reset).
void accept_targets(EnergyCall& c, const TargetSet& cand) {
  const EnergyData& m = c.m;
  const float tol = m.options.iso_tolerance;
  TargetSet& t = c.targets;
  std::vector<std::uint8_t> reset(m.n, 0);
  parallel_for(m.moving.size(), m.options.grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      const std::size_t i = std::size_t(m.moving[a]);
      bool take = t.kind[i] == TargetKind::kNone;
      if (!take) {
        const double dn = squared_norm(cand.point[i] - c.x[i]), dold = squared_norm(t.point[i] - c.x[i]);
        take = dn <= dold;
        if (!take && t.res[i] > tol && cand.res[i] < t.res[i]) take = true, reset[i] = 1;
      }
      if (!take) continue;
      t.point[i] = cand.point[i];
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
  parallel_for(m.n, m.options.grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
      for (int k = m.adj.offsets[i]; k < m.adj.offsets[i + 1]; ++k) {
        const std::size_t j = std::size_t(m.adj.neighbors[std::size_t(k)]);
        const Vec3d d = m.rest[i] - m.rest[j], x = c.x[i] - c.x[j];
        s += m.w[std::size_t(k)] * Eigen::Vector3d(d.x, d.y, d.z) * Eigen::RowVector3d(x.x, x.y, x.z);
      }
      c.rot[i] = procrustes(s);
    }
  });
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
