// SPDX-License-Identifier: MIT
// The energy tracker's global step (energy_tracker.h): with point targets the matrix (2 L + W + K)
// over the unpinned vertices, factored once per stiffness (CHOLMOD when available, else Eigen's
// simplicial LLᵀ); with plane targets the coupled (2 L + B + K) over their 3 coordinates, solved by
// conjugate gradients preconditioned by a factor of it taken in each call; the right-hand sides of
// the minimiser of E for fixed R, P and n, and E itself.
#include <algorithm>
#include <array>
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

// Conjugate-gradient iterations of a plane solve beyond which the next solve refactors: the
// normals have moved since the factor. Each call also refactors at its first global step, so a
// call's result depends on its inputs only.
constexpr int kRefactorAfter = 4;
// A plane solve stops when the residual fell to kPlaneStepTolerance of the step's own (the
// residual at xk), or to kPlaneTolerance of ‖b‖, or at the cap; the iterate is used whichever
// ends it, as every one lowers E. The step's error is then a small fraction of the step, so the
// convergence test still sees the move (measured on CesiumMan's walk: 1e-2 instead of solving to
// 1e-10 of ‖b‖ takes 189 → 118 ms per frame with the same quality metrics).
constexpr double kPlaneStepTolerance = 1e-2;
constexpr double kPlaneTolerance = 1e-10;
constexpr int kPlaneMaxIterations = 100;

struct EnergySystem::Impl {
  SpMat a;
  Factor factor;
  // Plane targets: the 3n × 3n matrix (full storage, interleaved per unknown), the positions of
  // each unknown's 3 × 3 diagonal block in its value array, the constant part of those blocks
  // (Σj (wij + wji) + Ki on the diagonal), and a factor of it at earlier normals.
  SpMat planes;
  std::vector<std::array<int, 9>> block;
  std::vector<double> block_base;
  Factor plane_factor;
  bool plane_factored{false};
  int last_iterations{0};
  int plane_factorizations{0};

  void build_planes(const EnergyData& m);
  void set_plane_blocks(const EnergyData& m, const std::vector<Vec3d>& normals);
  int conjugate_gradients(const std::vector<double>& rhs, std::vector<double>& x);
};

// The plane system's pattern from the point system's (each entry of `a` becomes a 3 × 3 block:
// −(wij + wji) I off the diagonal, a full block on it) and the positions of the diagonal blocks.
void EnergySystem::Impl::build_planes(const EnergyData& m) {
  const int n = m.unknowns;
  std::vector<Eigen::Triplet<double, int>> trips;
  trips.reserve(std::size_t(a.nonZeros()) * 3 + std::size_t(n) * 6);
  block_base.assign(std::size_t(n), 0.0);
  for (int col = 0; col < n; ++col)
    for (SpMat::InnerIterator it(a, col); it; ++it) {
      const int row = int(it.row());
      if (row == col) {
        block_base[std::size_t(row)] = it.value() - m.iso_w[std::size_t(m.moving[std::size_t(row)])];
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) trips.emplace_back(3 * row + r, 3 * col + c, 0.0);
      } else {
        for (int k = 0; k < 3; ++k) trips.emplace_back(3 * row + k, 3 * col + k, it.value());
      }
    }
  planes.resize(3 * n, 3 * n);
  planes.setFromTriplets(trips.begin(), trips.end());
  planes.makeCompressed();
  block.assign(std::size_t(n), {});
  for (int u = 0; u < n; ++u)
    for (int c = 0; c < 3; ++c)
      for (SpMat::InnerIterator it(planes, 3 * u + c); it; ++it) {
        const int r = int(it.row()) - 3 * u;
        if (r >= 0 && r < 3)
          block[std::size_t(u)][std::size_t(3 * r + c)] = int(&it.value() - planes.valuePtr());
      }
  plane_factored = false;
  last_iterations = 0;
  if (n > 0) plane_factor.analyzePattern(planes);
}

// The diagonal blocks Σj (wij + wji) I + Ki I + Wi (ε I + (1 − ε) ni niᵀ) at the given normals (a
// zero normal is a point target: Wi I).
void EnergySystem::Impl::set_plane_blocks(const EnergyData& m, const std::vector<Vec3d>& normals) {
  const double eps = double(m.options.tangent_weight);
  double* v = planes.valuePtr();
  parallel_for(m.moving.size(), m.options.grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t u = b; u < e; ++u) {
      const std::size_t i = std::size_t(m.moving[u]);
      const double w = m.iso_w[i], nv[3] = {normals[i].x, normals[i].y, normals[i].z};
      const bool point = EnergyData::point_target(normals[i]);  // Bi = Wi I
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
          v[block[u][std::size_t(3 * r + c)]] =
              point ? (r == c ? block_base[u] + w : 0.0)
                    : (r == c ? block_base[u] + w * eps : 0.0) + w * (1.0 - eps) * nv[r] * nv[c];
    }
  });
}

// Preconditioned conjugate gradients on `planes` from x (Saad, Iterative Methods, alg. 9.1); the
// preconditioner is the factor. Returns the iterations.
int EnergySystem::Impl::conjugate_gradients(const std::vector<double>& rhs, std::vector<double>& xv) {
  using Vec = Eigen::VectorXd;
  const Eigen::Map<const Vec> b(rhs.data(), Eigen::Index(rhs.size()));
  Eigen::Map<Vec> x(xv.data(), Eigen::Index(xv.size()));
  Vec r = b - planes * x;
  const double stop = std::max(kPlaneStepTolerance * r.norm(), kPlaneTolerance * b.norm());
  if (r.norm() <= kPlaneTolerance * b.norm()) return 0;
  Vec z = plane_factor.solve(r), p = z, ap(x.size());
  double rz = r.dot(z);
  int k = 0;
  while (k < kPlaneMaxIterations) {
    ++k;
    ap.noalias() = planes * p;
    const double pap = p.dot(ap);
    if (!(pap > 0)) break;
    const double alpha = rz / pap;
    x += alpha * p;
    r -= alpha * ap;
    if (r.norm() <= stop) break;
    z = plane_factor.solve(r);
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
  if (m.planes()) {  // the plane system is factored in each call (solve_planes)
    impl_->build_planes(m);
    return false;
  }
  if (m.unknowns == 0) return false;
  impl_->factor.compute(impl_->a);
  require(impl_->factor.info() == Eigen::Success, "energy tracker matrix",
          "could not be factorised (" + std::to_string(m.unknowns) + " unknowns)",
          "check the rest mesh for non-finite or huge coordinates and the weights for overflow");
  return true;
}

void EnergySystem::solve(double* rhs, int unknowns) const {
  if (unknowns == 0) return;
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>> b(rhs, unknowns, 3);
  const Eigen::MatrixXd x = impl_->factor.solve(Eigen::MatrixXd(b));
  b = x;
}

int EnergySystem::solve_planes(const EnergyData& m, const std::vector<Vec3d>& normals,
                               const std::vector<double>& rhs, std::vector<double>& x) const {
  Impl& im = *impl_;
  if (m.unknowns == 0) return 0;
  im.set_plane_blocks(m, normals);
  if (!im.plane_factored || im.last_iterations > kRefactorAfter) {
    im.plane_factor.factorize(im.planes);
    require(im.plane_factor.info() == Eigen::Success, "energy tracker plane system",
            "could not be factorised (" + std::to_string(3 * m.unknowns) + " unknowns)",
            "check the rest mesh for non-finite or huge coordinates and the weights for overflow");
    im.plane_factored = true;
    ++im.plane_factorizations;
  }
  im.last_iterations = im.conjugate_gradients(rhs, x);
  return im.last_iterations;
}

void EnergySystem::begin_call() const {
  impl_->plane_factored = false;
}

int EnergySystem::take_plane_factorizations() const {
  const int k = impl_->plane_factorizations;
  impl_->plane_factorizations = 0;
  return k;
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
