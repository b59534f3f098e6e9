// SPDX-License-Identifier: MIT
// The energy tracker's global step (energy_tracker.h): the matrix (2 L + W + K) over the unpinned
// vertices, factored once per stiffness (CHOLMOD when available, else Eigen's simplicial LLᵀ);
// with point targets its solve is the step, with plane targets (2 L + B + K) couples the 3
// coordinates and is solved by conjugate gradients preconditioned by that same factor; the
// right-hand sides of the minimiser of E for fixed R, P and n, and E itself.
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

// A plane solve stops when the residual fell to kPlaneStepTolerance of the step's own (the
// residual at xk), or to kPlaneTolerance of ‖b‖, or at the cap; the iterate is used whichever
// ends it, as every one lowers E. The step's error is then a small fraction of the step, so the
// convergence test still sees the move (measured on CesiumMan's walk: 1e-2 instead of solving to
// 1e-10 of ‖b‖ takes 189 → 118 ms per frame with the same quality metrics).
constexpr double kPlaneStepTolerance = 1e-2;
constexpr double kPlaneTolerance = 1e-10;
constexpr int kPlaneMaxIterations = 100;

struct EnergySystem::Impl {
  SpMat a;  // 2 L + W + K
  Factor factor;

  int conjugate_gradients(const EnergyData& m, const std::vector<Vec3d>& normals,
                          const std::vector<double>& rhs, std::vector<double>& x) const;
  void multiply(const EnergyData& m, const std::vector<Vec3d>& normals, Eigen::Ref<const Eigen::VectorXd> p,
                Eigen::Ref<Eigen::VectorXd> out) const;
  Eigen::VectorXd precondition(const Eigen::VectorXd& r) const;
  // (2 L + W + K) x = rhs for the 3 coordinates, `rhs` unknowns × 3 row-major, overwritten.
  void solve_rows(double* rhs, Eigen::Index unknowns) const;
};

using Rows = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;  // 3 coordinates per unknown

// The preconditioner (2 L + W + K)⁻¹ per coordinate: it holds every target at full weight in
// every direction, so it bounds the plane matrix from above, (2 L + εW + K) ≤ (2 L + B + K) ≤
// (2 L + W + K), and it is the same matrix at every normal: factored once per stiffness instead
// of at each call (measured in docs/decisions/tracker-one-energy.md, "A constant preconditioner").
Eigen::VectorXd EnergySystem::Impl::precondition(const Eigen::VectorXd& r) const {
  Eigen::VectorXd out = r;
  solve_rows(out.data(), Eigen::Index(r.size() / 3));
  return out;
}

void EnergySystem::Impl::solve_rows(double* rhs, Eigen::Index unknowns) const {
  Eigen::Map<Rows> b(rhs, unknowns, 3);
  const Eigen::MatrixXd x = factor.solve(Eigen::MatrixXd(b));
  b = x;
}

// out = (2 L + B + K) p = (2 L + W + K) p − Σi Wi (1 − ε) (I − ni niᵀ) pi, row by row (`a` is
// symmetric: column u holds row u).
void EnergySystem::Impl::multiply(const EnergyData& m, const std::vector<Vec3d>& normals,
                                  Eigen::Ref<const Eigen::VectorXd> p,
                                  Eigen::Ref<Eigen::VectorXd> out) const {
  const double eps = double(m.options.tangent_weight);
  parallel_for(m.moving.size(), m.options.grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t u = b; u < e; ++u) {
      Vec3d sum{};
      for (SpMat::InnerIterator it(a, Eigen::Index(u)); it; ++it) {
        const std::size_t j = 3 * std::size_t(it.row());
        sum += Vec3d{p[j], p[j + 1], p[j + 2]} * it.value();
      }
      const std::size_t i = std::size_t(m.moving[u]);
      if (!EnergyData::point_target(normals[i])) {
        const Vec3d pu{p[3 * u], p[3 * u + 1], p[3 * u + 2]};
        sum = sum - (pu - normals[i] * dot(normals[i], pu)) * (m.iso_w[i] * (1.0 - eps));
      }
      out[3 * u] = sum.x, out[3 * u + 1] = sum.y, out[3 * u + 2] = sum.z;
    }
  });
}

int EnergySystem::Impl::conjugate_gradients(const EnergyData& m, const std::vector<Vec3d>& normals,
                                            const std::vector<double>& rhs, std::vector<double>& xv) const {
  using Vec = Eigen::VectorXd;
  const Eigen::Map<const Vec> b(rhs.data(), Eigen::Index(rhs.size()));
  Eigen::Map<Vec> x(xv.data(), Eigen::Index(xv.size()));
  Vec r(b.size()), ap(x.size());
  multiply(m, normals, x, r);
  r = b - r;
  const double stop = std::max(kPlaneStepTolerance * r.norm(), kPlaneTolerance * b.norm());
  if (r.norm() <= kPlaneTolerance * b.norm()) return 0;
  Vec z = precondition(r), p = z;
  double rz = r.dot(z);
  int k = 0;
  while (k < kPlaneMaxIterations) {
    ++k;
    multiply(m, normals, p, ap);
    const double pap = p.dot(ap);
    if (!(pap > 0)) break;
    const double alpha = rz / pap;
    x += alpha * p;
    r -= alpha * ap;
    if (r.norm() <= stop) break;
    z = precondition(r);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  return k;
}

EnergySystem::EnergySystem() : impl_(std::make_unique<Impl>()) {}
EnergySystem::~EnergySystem() = default;

// Row of unpinned vertex i: Σj (wij + wji) + Wi + Ki on the diagonal, −(wij + wji) toward each
// unpinned neighbour (pinned ones go to the right-hand side).
bool EnergySystem::factor(const EnergyData& m) {
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
  if (m.unknowns == 0) return false;
  impl_->factor.compute(impl_->a);
  require(impl_->factor.info() == Eigen::Success, "energy tracker matrix",
          "could not be factorised (" + std::to_string(m.unknowns) + " unknowns)",
          "check the rest mesh for non-finite or huge coordinates and the weights for overflow");
  return true;
}

void EnergySystem::solve(double* rhs, int unknowns) const {
  if (unknowns == 0) return;
  impl_->solve_rows(rhs, unknowns);
}

int EnergySystem::solve_planes(const EnergyData& m, const std::vector<Vec3d>& normals,
                               const std::vector<double>& rhs, std::vector<double>& x) const {
  if (m.unknowns == 0) return 0;
  return impl_->conjugate_gradients(m, normals, rhs, x);
}

namespace {

// Bi Pi = Wi (ε Pi + (1 − ε) ni (ni · Pi)).
Vec3d target_pull(const EnergyCall& c, std::size_t i) {
  const EnergyData& m = c.m;
  const Vec3d& p = c.targets.point[i];
  if (!m.planes()) return p * m.iso_w[i];
  const Vec3d& n = c.targets.normal[i];
  if (EnergyData::point_target(n)) return p * m.iso_w[i];
  const double eps = double(m.options.tangent_weight);
  return (p * eps + n * ((1.0 - eps) * dot(n, p))) * m.iso_w[i];
}

}  // namespace

// b_i = Σj (wij Ri + wji Rj)(pi − pj) + Bi Pi + Ki ai + Σ_{j pinned} (wij + wji) aj.
double global_step(EnergyCall& c, std::vector<Vec3d>& next) {
  const EnergyData& m = c.m;
  std::vector<double> rhs(std::size_t(m.unknowns) * 3);
  parallel_for(m.moving.size(), m.options.grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      const std::size_t i = std::size_t(m.moving[a]);
      Vec3d r = target_pull(c, i) + c.anchor[i] * m.anchor_w[i];
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
  if (m.planes()) {
    std::vector<double> x(rhs.size());
    for (std::size_t a = 0; a < m.moving.size(); ++a) {
      const Vec3d& p = c.x[std::size_t(m.moving[a])];
      x[3 * a] = p.x, x[3 * a + 1] = p.y, x[3 * a + 2] = p.z;
    }
    c.stats.solver_iterations += c.m.system.solve_planes(m, c.targets.normal, rhs, x);
    rhs.swap(x);
  } else {
    c.m.system.solve(rhs.data(), m.unknowns);
  }
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
      s += m.iso_w[i] * m.target_distance2(x[i], c.targets.point[i], c.targets.normal[i]) +
           m.anchor_w[i] * squared_norm(x[i] - c.anchor[i]);
      per[i] = s;
    }
  });
  double total = 0;
  for (double v : per) total += v;
  return total;
}

}  // namespace isokit::track::detail
