// SPDX-License-Identifier: MIT
// The energy tracker's global step: the matrix (2 L + W + K) over the unpinned vertices, factored
// once per stiffness (CHOLMOD when available, else Eigen's simplicial LLᵀ), the right-hand sides
// of the exact minimiser of E for fixed R and P, and E itself (energy_tracker.h).
#include <algorithm>
#include <cmath>
#include <string>

#include "energy_model.h"
#include "isokit/core/error.h"
#include "isokit/core/parallel.h"
#include "sparse_factor.h"

namespace isokit::track::detail {

namespace {

Vec3d mul(const Mat3d& r, const Vec3d& v) {
  return r * v;
}

}  // namespace

struct EnergySystem::Impl {
  SpMat a;
  Factor factor;
};

EnergySystem::EnergySystem() : impl_(std::make_unique<Impl>()) {}
EnergySystem::~EnergySystem() = default;

// Row of unpinned vertex i: Σj (wij + wji) + Wi + Ki on the diagonal, −(wij + wji) toward each
// unpinned neighbour (pinned ones go to the right-hand side).
void EnergySystem::factor(const EnergyData& m) {
  std::vector<Eigen::Triplet<double, int>> trips;
  trips.reserve(m.adj.neighbors.size() + m.moving.size());
  for (int iv : m.moving) {
    const std::size_t i = std::size_t(iv);
    double diag = m.iso_w[i] + m.anchor_w[i];
    for (int k = m.adj.offsets[i]; k < m.adj.offsets[i + 1]; ++k) {
      const double s = m.w[std::size_t(k)] + m.w_rev[std::size_t(k)];
      diag += s;
      const int col = m.unknown[std::size_t(m.adj.neighbors[std::size_t(k)])];
      if (col >= 0) trips.emplace_back(m.unknown[i], col, -s);
    }
    trips.emplace_back(m.unknown[i], m.unknown[i], diag);
  }
  impl_->a.resize(m.unknowns, m.unknowns);
  impl_->a.setFromTriplets(trips.begin(), trips.end());
  impl_->a.makeCompressed();
  if (m.unknowns == 0) return;
  impl_->factor.compute(impl_->a);
  require(impl_->factor.info() == Eigen::Success, "energy tracker matrix",
          "could not be factorised (" + std::to_string(m.unknowns) + " unknowns)",
          "check the rest mesh for non-finite or huge coordinates and the weights for overflow");
}

void EnergySystem::solve(double* rhs, int unknowns) const {
  if (unknowns == 0) return;
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>> b(rhs, unknowns, 3);
  const Eigen::MatrixXd x = impl_->factor.solve(Eigen::MatrixXd(b));
  b = x;
}

// b_i = Σj (wij Ri + wji Rj)(pi − pj) + Wi Pi + Ki ai + Σ_{j pinned} (wij + wji) aj.
double global_step(const EnergyCall& c, std::vector<Vec3d>& next) {
  const EnergyData& m = c.m;
  std::vector<double> rhs(std::size_t(m.unknowns) * 3);
  parallel_for(m.moving.size(), m.options.grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      const std::size_t i = std::size_t(m.moving[a]);
      Vec3d r = c.targets.point[i] * m.iso_w[i] + c.anchor[i] * m.anchor_w[i];
      for (int k = m.adj.offsets[i]; k < m.adj.offsets[i + 1]; ++k) {
        const std::size_t j = std::size_t(m.adj.neighbors[std::size_t(k)]);
        const Vec3d d = m.rest[i] - m.rest[j];
        const double wij = m.w[std::size_t(k)], wji = m.w_rev[std::size_t(k)];
        r += mul(c.rot[i], d) * wij + mul(c.rot[j], d) * wji;
        if (m.pinned(j)) r += c.x[j] * (wij + wji);
      }
      double* out = rhs.data() + 3 * std::size_t(m.unknown[i]);
      out[0] = r.x, out[1] = r.y, out[2] = r.z;
    }
  });
  c.m.system.solve(rhs.data(), m.unknowns);
  next = c.x;
  double max_move = 0;
  for (int iv : m.moving) {
    const std::size_t i = std::size_t(iv);
    const double* s = rhs.data() + 3 * std::size_t(m.unknown[i]);
    next[i] = {s[0], s[1], s[2]};
    max_move = std::max(max_move, norm(next[i] - c.x[i]));
  }
  return max_move;
}

double energy(const EnergyCall& c, const std::vector<Vec3d>& x) {
  const EnergyData& m = c.m;
  std::vector<double> per(m.n, 0.0);
  parallel_for(m.n, m.options.grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      double s = 0;
      for (int k = m.adj.offsets[i]; k < m.adj.offsets[i + 1]; ++k) {
        const std::size_t j = std::size_t(m.adj.neighbors[std::size_t(k)]);
        s += m.w[std::size_t(k)] * squared_norm((x[i] - x[j]) - mul(c.rot[i], m.rest[i] - m.rest[j]));
      }
      s += m.iso_w[i] * squared_norm(x[i] - c.targets.point[i]) +
           m.anchor_w[i] * squared_norm(x[i] - c.anchor[i]);
      per[i] = s;
    }
  });
  double total = 0;
  for (double v : per) total += v;
  return total;
}

}  // namespace isokit::track::detail
