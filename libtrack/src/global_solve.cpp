// SPDX-License-Identifier: MIT
// The tangent-plane ARAP system of 2014 eq. 3 – 4 solved exactly per iteration (TangentSolver), and
// the per-frame solve that alternates it with safeguarded Newton projections (solve_frame);
// docs/tracking.md, "The global solve".
#include "global_solve.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "field_eval.h"
#include "mesh_geometry.h"
#include "newton_step.h"
#include "points.h"
#include "sparse_factor.h"

namespace isokit::track::detail {

namespace {

// Preconditioned CG on the current matrix with the last numeric factor: stop when the
// preconditioned residual norm fell by this factor (relative; the tangential tolerance is then
// met to 1e-5 of the move); refactor when it needed more than kRefactorAfter iterations, and solve
// directly after a refactorisation when it did not converge within kMaxPcgIterations.
constexpr double kPcgRelTolerance = 1e-5;
constexpr int kRefactorAfter = 8;
constexpr int kMaxPcgIterations = 30;
// A vertex held in place for one iteration (no usable normal: lost) gets this × Σj wij on its
// diagonal.
constexpr double kHoldStiffness = 1e6;
// Floor of the curvature term's eigenvalues (× Σj wij); the matrix's diagonal blocks stay ≥ half
// the Laplacian's.
constexpr float kMinCurvature = 0.f;

}  // namespace

Vec3f perpendicular(const Vec3f& n) {
  const Vec3f axis =
      std::abs(n.x) < 0.6f ? Vec3f{1, 0, 0} : (std::abs(n.y) < 0.6f ? Vec3f{0, 1, 0} : Vec3f{0, 0, 1});
  const Vec3f t = cross(n, axis);
  return t / std::sqrt(squared_norm(t));
}

struct TangentSolver::Impl {
  bool ready{false};
  std::vector<int> offset, ndof;  // per vertex: first unknown, unknown count (0, 2 or 3)
  int dofs{0};
  std::vector<Vec3f> t1;  // per vertex: first tangent vector, carried from call to call
  std::vector<Vec3f> t2;  // second tangent vector (n × t1) of the current iteration
  SpMat a;                // full symmetric storage, pattern fixed
  // Value indices into `a`: per directed edge, the start of its ndof_i × ndof_j block's indices
  // in `block_index`; per vertex, the start of its ndof_i² diagonal block's in `diag_index`.
  std::vector<int> block_at, block_index, diag_block, diag_index;
  Factor factor;
  bool factored{false}, refactor{true};
  int factorizations{0};  // numeric factorisations so far
  Eigen::VectorXd b, x, r, z, p, q;

  void build(const TrackState& s);
  void assemble(const TrackState& s, const std::vector<Vec3f>& normals, const std::vector<Sym3>& curvature,
                float min_eigen);
  int solve_pcg();
  // The 2 × 2 tangent-plane block `Tiᵀ K Ti` of the curvature tensor K, its eigenvalues clamped
  // to ≥ `floor`.
  void curvature_block(const Sym3& k, std::size_t i, double floor, double out[4]) const {
    const Vec3f u = t1[i], v = t2[i];
    auto apply = [&](const Vec3f& w) {
      return Vec3f{k[0] * w.x + k[3] * w.y + k[4] * w.z, k[3] * w.x + k[1] * w.y + k[5] * w.z,
                   k[4] * w.x + k[5] * w.y + k[2] * w.z};
    };
    const Vec3f ku = apply(u), kv = apply(v);
    const double kuu = dot(u, ku), kuv = 0.5 * (double(dot(u, kv)) + double(dot(v, ku))), kvv = dot(v, kv);
    // Eigen-decomposition of [[kuu, kuv], [kuv, kvv]], eigenvalues clamped.
    const double mean = 0.5 * (kuu + kvv), rad = std::sqrt(0.25 * (kuu - kvv) * (kuu - kvv) + kuv * kuv);
    const double l1 = std::max(mean + rad, floor), l2 = std::max(mean - rad, floor);
    double ex = 1, ey = 0;  // eigenvector of l1
    if (rad > 0) {
      ex = kuv, ey = (mean + rad) - kuu;
      if (std::abs(ex) + std::abs(ey) < 1e-30 * (std::abs(kuu) + std::abs(kvv) + 1)) ex = 1, ey = 0;
      const double len = std::sqrt(ex * ex + ey * ey);
      ex /= len, ey /= len;
    }
    out[0] = l1 * ex * ex + l2 * ey * ey;
    out[1] = out[2] = (l1 - l2) * ex * ey;
    out[3] = l1 * ey * ey + l2 * ex * ex;
  }
  // Column c of the basis of vertex i (ndof 3: the unit axes).
  Vec3f basis(std::size_t i, int c) const {
    if (ndof[i] == 3) return c == 0 ? Vec3f{1, 0, 0} : (c == 1 ? Vec3f{0, 1, 0} : Vec3f{0, 0, 1});
    return c == 0 ? t1[i] : t2[i];
  }
};

namespace {

// Value index of entry (row, col) of a compressed column-major matrix.
int value_index(const SpMat& a, int row, int col) {
  const int* inner = a.innerIndexPtr();
  const int* b = inner + a.outerIndexPtr()[col];
  const int* e = inner + a.outerIndexPtr()[col + 1];
  const int* it = std::lower_bound(b, e, row);
  return static_cast<int>(it - inner);
}

}  // namespace

// The unknowns: 2 per vertex (its tangent plane), 3 for a free vertex, none for a vertex with
// mask 0 or without neighbours; the pattern of the block matrix, analysed once.
void TangentSolver::Impl::build(const TrackState& s) {
  const TrackerModel& m = s.m;
  const std::size_t n = s.n;
  offset.assign(n, -1);
  ndof.assign(n, 0);
  dofs = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!(m.mask[i] > 0.f) || m.adj.degree(static_cast<int>(i)) == 0 || s.pinned(i)) continue;
    ndof[i] = m.free[i] ? 3 : 2;
    offset[i] = dofs;
    dofs += ndof[i];
  }
  std::vector<Eigen::Triplet<double, int>> trips;
  for (std::size_t i = 0; i < n; ++i) {
    if (ndof[i] == 0) continue;
    for (int a0 = 0; a0 < ndof[i]; ++a0)
      for (int b0 = 0; b0 < ndof[i]; ++b0) trips.emplace_back(offset[i] + a0, offset[i] + b0, 0.0);
    for (int k = m.adj.offsets[i]; k < m.adj.offsets[i + 1]; ++k) {
      const std::size_t j = std::size_t(m.adj.neighbors[std::size_t(k)]);
      for (int a0 = 0; a0 < ndof[i]; ++a0)
        for (int b0 = 0; b0 < ndof[j]; ++b0) trips.emplace_back(offset[i] + a0, offset[j] + b0, 0.0);
    }
  }
  a.resize(dofs, dofs);
  a.setFromTriplets(trips.begin(), trips.end());
  a.makeCompressed();
  diag_block.assign(n, 0);
  diag_index.clear();
  block_at.assign(m.adj.neighbors.size(), 0);
  block_index.clear();
  for (std::size_t i = 0; i < n; ++i) {
    if (ndof[i] == 0) continue;
    diag_block[i] = static_cast<int>(diag_index.size());
    for (int a0 = 0; a0 < ndof[i]; ++a0)
      for (int b0 = 0; b0 < ndof[i]; ++b0)
        diag_index.push_back(value_index(a, offset[i] + a0, offset[i] + b0));
    for (int k = m.adj.offsets[i]; k < m.adj.offsets[i + 1]; ++k) {
      const std::size_t j = std::size_t(m.adj.neighbors[std::size_t(k)]);
      block_at[std::size_t(k)] = static_cast<int>(block_index.size());
      for (int a0 = 0; a0 < ndof[i]; ++a0)
        for (int b0 = 0; b0 < ndof[j]; ++b0)
          block_index.push_back(value_index(a, offset[i] + a0, offset[j] + b0));
    }
  }
  t1.assign(n, Vec3f{});
  t2.assign(n, Vec3f{});
  if (dofs > 0) factor.analyzePattern(a);
  factored = false;
  refactor = true;
  ready = true;
}

// Tangent bases from the plane normals (the first vector carried over by the least rotation, so
// that the stale factor stays a good preconditioner), then the matrix values and right-hand side.
void TangentSolver::Impl::assemble(const TrackState& s, const std::vector<Vec3f>& normals,
                                   const std::vector<Sym3>& curvature, float min_eigen) {
  const TrackerModel& m = s.m;
  const float eps = m.options.global_regularization;
  for (std::size_t i = 0; i < s.n; ++i) {
    if (ndof[i] != 2 || normals[i] == Vec3f{}) continue;
    const Vec3f nrm = normals[i];
    Vec3f t = t1[i] - nrm * dot(t1[i], nrm);
    const float len2 = squared_norm(t);
    t = len2 > 1e-4f ? t / std::sqrt(len2) : perpendicular(nrm);
    t1[i] = t;
    t2[i] = cross(nrm, t);
  }
  double* val = a.valuePtr();
  b.setZero(dofs);
  for (std::size_t i = 0; i < s.n; ++i) {
    const int nd = ndof[i];
    if (nd == 0) continue;
    const double wsum = m.weight_sum[i];
    double alpha = double(eps) * wsum + wsum * (1.0 / double(m.mask[i]) - 1.0);
    // The anchor's pull (set_anchor_stiffness): k / (1 - k) Σj wij ||pi + d - ai||².
    const double ks = s.stiffness(i), pull = ks > 0 ? wsum * ks / (1.0 - ks) : 0.0;
    alpha += pull;
    const bool hold = nd == 2 && (normals[i] == Vec3f{} || t2[i] == Vec3f{});
    if (hold) alpha = kHoldStiffness * wsum;
    const int* di = diag_index.data() + diag_block[i];
    double k2[4] = {0, 0, 0, 0};
    if (nd == 2 && alpha < kHoldStiffness * wsum) curvature_block(curvature[i], i, min_eigen * wsum, k2);
    for (int a0 = 0; a0 < nd; ++a0)
      for (int b0 = 0; b0 < nd; ++b0)
        val[di[a0 * nd + b0]] = (a0 == b0 ? wsum + alpha : 0.0) + (nd == 2 ? k2[a0 * 2 + b0] : 0.0);
    Vec3f g{};
    const Vec3f pi = s.cur[i];
    for (int k = m.adj.offsets[i]; k < m.adj.offsets[i + 1]; ++k) {
      const std::size_t j = std::size_t(m.adj.neighbors[std::size_t(k)]);
      const float w = m.weights[std::size_t(k)];
      g += ((s.cur[j] - pi) + s.targets[std::size_t(k)]) * w;
      const int nj = ndof[j];
      const int* bi = block_index.data() + block_at[std::size_t(k)];
      for (int a0 = 0; a0 < nd; ++a0)
        for (int b0 = 0; b0 < nj; ++b0)
          val[bi[a0 * nj + b0]] = -double(w) * double(dot(basis(i, a0), basis(j, b0)));
    }
    if (pull > 0 && !hold) g += (s.anchors[i] - pi) * float(pull);
    for (int a0 = 0; a0 < nd; ++a0) b[offset[i] + a0] = double(dot(basis(i, a0), g));
  }
}

// CG on `a x = b` preconditioned by the last factor (refactored first when asked, then solved
// directly); returns the CG iterations. `factored` false on return: `a` is not positive definite.
int TangentSolver::Impl::solve_pcg() {
  if (refactor || !factored) {
    ++factorizations;
    factor.factorize(a);
    factored = factor.info() == Eigen::Success;
    refactor = false;
    if (factored) x = factor.solve(b);
    return 0;  // solved, or not positive definite (factored false)
  }
  x.setZero(dofs);
  r = b;
  z = factor.solve(r);
  p = z;
  double rz = r.dot(z);
  const double rz0 = rz;
  int it = 0;
  while (rz > kPcgRelTolerance * kPcgRelTolerance * rz0 && it < kMaxPcgIterations) {
    ++it;
    q.noalias() = a * p;
    const double pq = p.dot(q);
    if (!(pq > 0.0)) {  // not positive definite: the caller retries without negative curvature
      factored = false;
      return it;
    }
    const double alpha = rz / pq;
    x += alpha * p;
    r -= alpha * q;
    z = factor.solve(r);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  if (it > kRefactorAfter) refactor = true;
  if (rz > kPcgRelTolerance * kPcgRelTolerance * rz0) {  // not converged: refactor and solve directly
    ++factorizations;
    factor.factorize(a);
    factored = factor.info() == Eigen::Success;
    refactor = false;
    if (factored) x = factor.solve(b);
  }
  return it;
}

TangentSolver::TangentSolver() : impl_(std::make_unique<Impl>()) {}
TangentSolver::~TangentSolver() = default;

TangentSolverCache::TangentSolverCache() = default;
TangentSolverCache::~TangentSolverCache() = default;
TangentSolverCache::TangentSolverCache(const TangentSolverCache&) {}
TangentSolverCache& TangentSolverCache::operator=(const TangentSolverCache&) {
  reset();
  return *this;
}
TangentSolverCache::TangentSolverCache(TangentSolverCache&&) noexcept = default;
TangentSolverCache& TangentSolverCache::operator=(TangentSolverCache&&) noexcept = default;
void TangentSolverCache::reset() {
  solver_.reset();
}
TangentSolver& TangentSolverCache::get() {
  if (!solver_) solver_ = std::make_unique<TangentSolver>();
  return *solver_;
}

void TangentSolver::solve(TrackState& s, const std::vector<Vec3f>& normals,
                          const std::vector<Sym3>& curvature, std::vector<Vec3f>& d) {
  Impl& im = *impl_;
  if (!im.ready || im.ndof.size() != s.n) im.build(s);
  d.assign(s.n, Vec3f{});
  if (im.dofs == 0) return;
  const int before = im.factorizations;
  // Negative curvature terms first (clamped); if the matrix is then not positive definite, none.
  for (float floor : {kMinCurvature, 0.f}) {
    im.assemble(s, normals, curvature, floor);
    s.stats.solver_iterations += im.solve_pcg();
    if (im.factored) break;
    im.refactor = true;
  }
  s.stats.factorizations += im.factorizations - before;
  if (!im.factored) return;  // not positive definite (cannot happen with eps > 0 and floor 0): no move
  for (std::size_t i = 0; i < s.n; ++i) {
    const int nd = im.ndof[i];
    Vec3f v{};
    for (int c = 0; c < nd; ++c) v += im.basis(i, c) * float(im.x[im.offset[i] + c]);
    d[i] = finite(v) ? v : Vec3f{};
  }
}

}  // namespace isokit::track::detail
