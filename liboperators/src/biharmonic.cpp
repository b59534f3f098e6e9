// SPDX-License-Identifier: MIT
#include "isokit/operators/biharmonic.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "isokit/core/error.h"
#include "isokit/core/parallel.h"
#include "isokit/operators/profile.h"
#include "sparse_solver.h"

namespace isokit::operators {

using detail::SpMat;

namespace {

/// Profile constraints of one slice: unknown indices (sorted) and their values.
struct Constraints {
  std::vector<int> u;
  std::vector<double> v;
};

}  // namespace

struct BiharmonicOperatorGenerator::Impl {
  OperatorSpec spec;
  BiharmonicOptions opt;
  GeneratorStats stats;
  bool use_cholmod{false};
  int n{0};
  double h{0};
  std::vector<int> u_of_node;  // node -> unknown index, -1 for fixed nodes
  std::vector<int> node_of_u;
  std::vector<double> fixed;  // value of each fixed node (all nodes; unknowns 0)
  SpMat K;                    // Q restricted to the unknowns
  Eigen::VectorXd b0;         // -Q[U, fixed] x_fixed

  // Schur scheme.
  bool schur{false};
  std::vector<char> is_static;  // per unknown: constrained in every slice
  std::vector<int> d_index;     // per unknown: index in D or -1
  std::vector<int> f_index;     // per unknown: index in F or -1
  std::vector<int> D, F;        // unknown indices
  SpMat M_FF, M_FD;
  Eigen::MatrixXd S;
  Eigen::MatrixXd S_inv;  // S⁻¹, for slices with fewer constrained than free dynamic nodes

  struct Workspace {
    std::unique_ptr<detail::SparseSolver> refactor;  // analysed on K's pattern
    SpMat A;
    std::unique_ptr<detail::SparseSolver> ff;  // factor of M_FF
  };
  Workspace main;

  void build_system();
  Constraints constraints_at(const OperatorSpec& sp, double d) const;
  Constraints constraints_at(double d) const { return constraints_at(spec, d); }
  void init_schur();
  std::vector<int> constraint_counts() const;
  void partition_nodes(const std::vector<int>& count);
  SpMat split_system();
  void schur_complement(const SpMat& M_DD);
  void invert_schur();
  void prepare(Workspace& w, bool need_ff) const;
  std::vector<float> solve(Workspace& w, double d) const;
  std::vector<double> solve_refactor(Workspace& w, const Constraints& c) const;
  bool solve_schur(Workspace& w, const Constraints& c, std::vector<double>& x) const;
  Eigen::MatrixXd solve_ff(Workspace& w, const Eigen::MatrixXd& rhs) const;
  std::vector<float> assemble(const std::vector<double>& xu) const;
};

void BiharmonicOperatorGenerator::Impl::build_system() {
  const int N = n * n;
  auto id = [&](int i1, int i2) { return i1 * n + i2; };
  fixed.assign(N, 0.0);
  u_of_node.assign(N, -1);
  node_of_u.clear();
  for (int i1 = 0; i1 < n; ++i1)
    for (int i2 = 0; i2 < n; ++i2) {
      double v = 0;
      bool is_fixed = true;
      if (i1 == 0)
        v = i2 * h;  // g(0, f2) = f2
      else if (i2 == 0)
        v = i1 * h;  // g(f1, 0) = f1
      else if (i1 == n - 1 || i2 == n - 1)
        v = 1.0;  // g(1, f2) = g(f1, 1) = 1
      else if (i1 == 1)
        v = i2 * h;  // clamp: ∂g/∂f1 = 0 on f1 = 0
      else if (i2 == 1)
        v = i1 * h;  // clamp: ∂g/∂f2 = 0 on f2 = 0
      else
        is_fixed = false;
      if (is_fixed) {
        fixed[id(i1, i2)] = v;
      } else {
        u_of_node[id(i1, i2)] = static_cast<int>(node_of_u.size());
        node_of_u.push_back(id(i1, i2));
      }
    }
  // L: 5-point Laplacian at the interior nodes; Q = Lᵀ L.
  std::vector<Eigen::Triplet<double>> t;
  int row = 0;
  for (int i1 = 1; i1 < n - 1; ++i1)
    for (int i2 = 1; i2 < n - 1; ++i2, ++row) {
      t.emplace_back(row, id(i1, i2), -4.0);
      t.emplace_back(row, id(i1 - 1, i2), 1.0);
      t.emplace_back(row, id(i1 + 1, i2), 1.0);
      t.emplace_back(row, id(i1, i2 - 1), 1.0);
      t.emplace_back(row, id(i1, i2 + 1), 1.0);
    }
  SpMat L(row, N);
  L.setFromTriplets(t.begin(), t.end());
  const SpMat Q = SpMat(L.transpose()) * L;
  const int U = static_cast<int>(node_of_u.size());
  std::vector<Eigen::Triplet<double>> tk;
  b0 = Eigen::VectorXd::Zero(U);
  for (int c = 0; c < Q.outerSize(); ++c)
    for (SpMat::InnerIterator it(Q, c); it; ++it) {
      const int ur = u_of_node[it.row()], uc = u_of_node[c];
      if (ur < 0) continue;
      if (uc >= 0)
        tk.emplace_back(ur, uc, it.value());
      else
        b0[ur] -= it.value() * fixed[c];
    }
  K.resize(U, U);
  K.setFromTriplets(tk.begin(), tk.end());
  K.makeCompressed();
  stats.unknowns = U;
}

Constraints BiharmonicOperatorGenerator::Impl::constraints_at(const OperatorSpec& sp, double d) const {
  const SliceProfile profile(sp, d);
  const int cells = n - 1;
  std::vector<char> cell(static_cast<std::size_t>(cells) * cells, 0);
  for (const auto& pl : profile.polylines())
    for (std::size_t s = 0; s + 1 < pl.points.size(); ++s) {
      const Point2 &a = pl.points[s], &b = pl.points[s + 1];
      const int m =
          std::max(1, static_cast<int>(std::ceil(std::hypot(b[0] - a[0], b[1] - a[1]) / (0.25 * h))));
      for (int j = 0; j <= m; ++j) {
        const double x = a[0] + (b[0] - a[0]) * j / m, y = a[1] + (b[1] - a[1]) * j / m;
        const int cx = std::clamp(static_cast<int>(std::floor(x / h)), 0, cells - 1);
        const int cy = std::clamp(static_cast<int>(std::floor(y / h)), 0, cells - 1);
        cell[static_cast<std::size_t>(cx) * cells + cy] = 1;
      }
    }
  std::vector<char> node(static_cast<std::size_t>(n) * n, 0);
  for (int cx = 0; cx < cells; ++cx)
    for (int cy = 0; cy < cells; ++cy)
      if (cell[static_cast<std::size_t>(cx) * cells + cy])
        for (int a = 0; a < 2; ++a)
          for (int b = 0; b < 2; ++b) node[static_cast<std::size_t>(cx + a) * n + cy + b] = 1;
  Constraints c;
  for (int u = 0; u < static_cast<int>(node_of_u.size()); ++u) {
    const int nd = node_of_u[u];
    if (!node[nd]) continue;
    const Point2 p{(nd / n) * h, (nd % n) * h};
    const double v = 0.5 + sp.distance_slope * profile.constraint_distance(p);
    c.u.push_back(u);
    c.v.push_back(std::clamp(v, 0.0, 1.0));
  }
  return c;
}

void BiharmonicOperatorGenerator::Impl::init_schur() {
  partition_nodes(constraint_counts());
  const bool want = opt.scheme == SliceScheme::kSchur ||
                    (opt.scheme == SliceScheme::kAuto &&
                     (opt.edit_band_cells > 0 || stats.dynamic_nodes <= opt.max_schur_nodes));
  if (!want) return;
  const SpMat M_DD = split_system();
  prepare(main, true);
  schur_complement(M_DD);
  invert_schur();
  schur = true;
}

/// Per unknown, the number of slices that constrain it; when editing, 1 for every node within
/// `edit_band_cells` of any slice's constraints (count 1 marks "some slices"), else 0.
std::vector<int> BiharmonicOperatorGenerator::Impl::constraint_counts() const {
  const int U = static_cast<int>(node_of_u.size());
  // Constrained-node sets of every slice (in parallel; each slice writes its own entry).
  std::vector<std::vector<int>> sets(static_cast<std::size_t>(spec.slices));
  parallel_for(sets.size(), opt.tasks == 1 ? 0 : 8, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) sets[k] = constraints_at(double(k) / (spec.slices - 1)).u;
  });
  std::vector<int> count(U, 0);
  for (const auto& set : sets)
    for (int u : set) ++count[u];
  if (opt.edit_band_cells > 0) {
    // Editing: nothing is static; every node within the band of any slice's constraints is
    // dynamic (count 1 marks "some slices").
    const int r = opt.edit_band_cells;
    std::vector<int> band(U, 0);
    for (int u = 0; u < U; ++u) {
      if (count[u] == 0) continue;
      const int i1 = node_of_u[u] / n, i2 = node_of_u[u] % n;
      for (int a = std::max(0, i1 - r); a <= std::min(n - 1, i1 + r); ++a)
        for (int b = std::max(0, i2 - r); b <= std::min(n - 1, i2 + r); ++b) {
          const int v = u_of_node[a * n + b];
          if (v >= 0) band[v] = 1;
        }
    }
    for (int u = 0; u < U; ++u) count[u] = band[u];
  }
  return count;
}

/// Splits the unknowns into static (constrained in every slice), dynamic (D: in some slices, or
/// in the editing band) and free (F: the rest, static included).
void BiharmonicOperatorGenerator::Impl::partition_nodes(const std::vector<int>& count) {
  const int U = static_cast<int>(node_of_u.size());
  is_static.assign(U, 0);
  d_index.assign(U, -1);
  f_index.assign(U, -1);
  D.clear();
  F.clear();
  for (int u = 0; u < U; ++u) {
    const bool dynamic = opt.edit_band_cells > 0 ? count[u] > 0 : (count[u] > 0 && count[u] < spec.slices);
    if (opt.edit_band_cells <= 0 && count[u] == spec.slices) is_static[u] = 1;
    if (dynamic) {
      d_index[u] = static_cast<int>(D.size());
      D.push_back(u);
    } else {
      f_index[u] = static_cast<int>(F.size());
      F.push_back(u);
    }
  }
  stats.dynamic_nodes = static_cast<int>(D.size());
}

/// M = K with the static nodes' rows and columns replaced by identity, split into the blocks
/// M_FF, M_FD (members) and M_DD (returned).
SpMat BiharmonicOperatorGenerator::Impl::split_system() {
  std::vector<Eigen::Triplet<double>> tff, tfd, tdd;
  for (int c = 0; c < K.outerSize(); ++c)
    for (SpMat::InnerIterator it(K, c); it; ++it) {
      const int r = it.row();
      double v = it.value();
      if (is_static[r] || is_static[c]) v = (r == c) ? 1.0 : 0.0;
      if (v == 0.0) continue;
      if (f_index[r] >= 0 && f_index[c] >= 0)
        tff.emplace_back(f_index[r], f_index[c], v);
      else if (f_index[r] >= 0 && d_index[c] >= 0)
        tfd.emplace_back(f_index[r], d_index[c], v);
      else if (d_index[r] >= 0 && d_index[c] >= 0)
        tdd.emplace_back(d_index[r], d_index[c], v);
    }
  const int nf = static_cast<int>(F.size()), ndyn = static_cast<int>(D.size());
  M_FF.resize(nf, nf);
  M_FF.setFromTriplets(tff.begin(), tff.end());
  M_FF.makeCompressed();
  M_FD.resize(nf, ndyn);
  M_FD.setFromTriplets(tfd.begin(), tfd.end());
  SpMat M_DD(ndyn, ndyn);
  M_DD.setFromTriplets(tdd.begin(), tdd.end());
  return M_DD;
}

/// S = M_DD - M_DF M_FF⁻¹ M_FD (M_DF = M_FDᵀ), in column blocks (bounded memory), the blocks
/// split over parallel tasks; each task but the first factors M_FF for itself.
void BiharmonicOperatorGenerator::Impl::schur_complement(const SpMat& M_DD) {
  const int ndyn = static_cast<int>(D.size());
  S = Eigen::MatrixXd(M_DD);
  constexpr int kBlock = 32;
  const int blocks = (ndyn + kBlock - 1) / kBlock;
  int tasks = opt.tasks > 0 ? opt.tasks : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  tasks = std::min(tasks, blocks);
  const std::size_t grain = tasks <= 1 ? 0 : static_cast<std::size_t>((blocks + tasks - 1) / tasks);
  std::mutex mutex;
  bool main_used = false;
  parallel_for(static_cast<std::size_t>(blocks), grain, [&](std::size_t begin, std::size_t end) {
    Workspace local;
    Workspace* w = &local;
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (!main_used) main_used = true, w = &main;
    }
    prepare(*w, true);
    Eigen::MatrixXd rhs, Z;
    for (std::size_t blk = begin; blk < end; ++blk) {
      const int c0 = static_cast<int>(blk) * kBlock, bc = std::min(kBlock, ndyn - c0);
      rhs = Eigen::MatrixXd(M_FD.middleCols(c0, bc));
      Z = solve_ff(*w, rhs);
      S.middleCols(c0, bc) -= M_FD.transpose() * Z;  // disjoint columns per task
    }
  });
}

/// S⁻¹ = L⁻ᵀ L⁻¹ from the Cholesky factor (triangular inverse + symmetric rank-k product).
void BiharmonicOperatorGenerator::Impl::invert_schur() {
  const int ndyn = static_cast<int>(D.size());
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  Eigen::MatrixXd Linv = Eigen::MatrixXd::Identity(ndyn, ndyn);
  llt.matrixL().solveInPlace(Linv);
  S_inv = Eigen::MatrixXd::Zero(ndyn, ndyn);
  S_inv.selfadjointView<Eigen::Lower>().rankUpdate(Linv.transpose());
  S_inv.triangularView<Eigen::StrictlyUpper>() = S_inv.transpose();
}

void BiharmonicOperatorGenerator::Impl::prepare(Workspace& w, bool need_ff) const {
  // No free node (the band or the constraints cover every unknown, e.g. at resolution 8): there
  // is no M_FF to factor, and sparse backends must not be handed an empty matrix.
  if (need_ff && !w.ff && !F.empty()) {
    w.ff = detail::make_sparse_solver(use_cholmod);
    w.ff->analyze(M_FF);
    w.ff->factorize(M_FF);
  }
  if (!need_ff && !w.refactor) {
    w.refactor = detail::make_sparse_solver(use_cholmod);
    w.A = K;
    w.refactor->analyze(w.A);
  }
}

/// M_FF⁻¹ rhs; with no free node (F empty) the result has no rows.
Eigen::MatrixXd BiharmonicOperatorGenerator::Impl::solve_ff(Workspace& w, const Eigen::MatrixXd& rhs) const {
  if (F.empty()) return Eigen::MatrixXd(0, rhs.cols());
  return w.ff->solve(rhs);
}

std::vector<double> BiharmonicOperatorGenerator::Impl::solve_refactor(Workspace& w,
                                                                      const Constraints& c) const {
  prepare(w, false);
  const int U = static_cast<int>(node_of_u.size());
  std::vector<char> mask(U, 0);
  for (int u : c.u) mask[u] = 1;
  Eigen::VectorXd b = b0;
  // Same pattern as K: constrained rows/columns become identity (explicit zeros kept).
  const double* kv = K.valuePtr();
  double* av = w.A.valuePtr();
  for (int col = 0; col < U; ++col)
    for (int p = K.outerIndexPtr()[col]; p < K.outerIndexPtr()[col + 1]; ++p) {
      const int r = K.innerIndexPtr()[p];
      av[p] = (mask[r] || mask[col]) ? (r == col ? 1.0 : 0.0) : kv[p];
    }
  for (std::size_t i = 0; i < c.u.size(); ++i)
    for (SpMat::InnerIterator it(K, c.u[i]); it; ++it) b[it.row()] -= it.value() * c.v[i];
  for (std::size_t i = 0; i < c.u.size(); ++i) b[c.u[i]] = c.v[i];
  w.refactor->factorize(w.A);
  const Eigen::VectorXd x = w.refactor->solve(b);
  return std::vector<double>(x.data(), x.data() + x.size());
}

bool BiharmonicOperatorGenerator::Impl::solve_schur(Workspace& w, const Constraints& c,
                                                    std::vector<double>& x) const {
  const int U = static_cast<int>(node_of_u.size());
  std::vector<char> mask(U, 0);
  for (int u : c.u) {
    mask[u] = 1;
    if (!is_static[u] && d_index[u] < 0) return false;  // constrained node outside static ∪ D
  }
  for (int u = 0; u < U; ++u)
    if (is_static[u] && !mask[u]) return false;
  prepare(w, true);
  Eigen::VectorXd b = b0;
  for (std::size_t i = 0; i < c.u.size(); ++i)
    if (is_static[c.u[i]])
      for (SpMat::InnerIterator it(K, c.u[i]); it; ++it) b[it.row()] -= it.value() * c.v[i];
  for (std::size_t i = 0; i < c.u.size(); ++i)
    if (is_static[c.u[i]]) b[c.u[i]] = c.v[i];
  const int nf = static_cast<int>(F.size()), ndyn = static_cast<int>(D.size());
  Eigen::VectorXd bF(nf), bD(ndyn);
  for (int i = 0; i < nf; ++i) bF[i] = b[F[i]];
  for (int i = 0; i < ndyn; ++i) bD[i] = b[D[i]];
  const Eigen::VectorXd y = solve_ff(w, bF);
  const Eigen::VectorXd rD = bD - M_FD.transpose() * y;
  // Split D into constrained (known) and free.
  Eigen::VectorXd xD = Eigen::VectorXd::Zero(ndyn);
  std::vector<int> free_d;
  for (std::size_t i = 0; i < c.u.size(); ++i)
    if (d_index[c.u[i]] >= 0) xD[d_index[c.u[i]]] = c.v[i];
  for (int i = 0; i < ndyn; ++i)
    if (!mask[D[i]]) free_d.push_back(i);
  std::vector<int> fixed_d;
  for (int i = 0; i < ndyn; ++i)
    if (mask[D[i]]) fixed_d.push_back(i);
  if (!free_d.empty() && free_d.size() <= fixed_d.size()) {
    // Direct: S_ff x_f = r_f - S_fc x_c, a dense Cholesky of the free dynamic nodes.
    const int m = static_cast<int>(free_d.size());
    Eigen::MatrixXd Sff(m, m);
    Eigen::VectorXd rhs(m);
    const Eigen::VectorXd SxD = S * xD;  // known part (xD is zero on the free entries)
    for (int a = 0; a < m; ++a) {
      rhs[a] = rD[free_d[a]] - SxD[free_d[a]];
      for (int bb = 0; bb < m; ++bb) Sff(a, bb) = S(free_d[a], free_d[bb]);
    }
    const Eigen::VectorXd xf = Sff.llt().solve(rhs);
    for (int a = 0; a < m; ++a) xD[free_d[a]] = xf[a];
  } else if (!free_d.empty()) {
    // Capacitance form: minimise ½ xᵀ S x - r_Dᵀ x subject to x_c = v, i.e.
    // x = S⁻¹ (r_D + E_c λ) with (S⁻¹)_cc λ = v - (S⁻¹ r_D)_c: a dense Cholesky of the
    // constrained dynamic nodes only.
    const int m = static_cast<int>(fixed_d.size());
    const Eigen::VectorXd sr = S_inv * rD;
    Eigen::MatrixXd C(m, m);
    Eigen::VectorXd rhs(m);
    for (int a = 0; a < m; ++a) {
      rhs[a] = xD[fixed_d[a]] - sr[fixed_d[a]];
      for (int bb = 0; bb < m; ++bb) C(a, bb) = S_inv(fixed_d[a], fixed_d[bb]);
    }
    const Eigen::VectorXd lambda = C.llt().solve(rhs);
    Eigen::VectorXd xs = sr;
    for (int a = 0; a < m; ++a) xs += S_inv.col(fixed_d[a]) * lambda[a];
    for (int i : free_d) xD[i] = xs[i];  // constrained entries keep their exact values
  }
  const Eigen::VectorXd xF = solve_ff(w, bF - M_FD * xD);
  x.assign(U, 0.0);
  for (int i = 0; i < nf; ++i) x[F[i]] = xF[i];
  for (int i = 0; i < ndyn; ++i) x[D[i]] = xD[i];
  return true;
}

std::vector<float> BiharmonicOperatorGenerator::Impl::assemble(const std::vector<double>& xu) const {
  std::vector<float> out(static_cast<std::size_t>(n) * n);
  for (std::size_t node = 0; node < out.size(); ++node) {
    const int u = u_of_node[node];
    out[node] = static_cast<float>(u >= 0 ? xu[u] : fixed[node]);
  }
  return out;
}

std::vector<float> BiharmonicOperatorGenerator::Impl::solve(Workspace& w, double d) const {
  const Constraints c = constraints_at(d);
  std::vector<double> x;
  if (!(schur && solve_schur(w, c, x))) x = solve_refactor(w, c);
  return assemble(x);
}

BiharmonicOperatorGenerator::BiharmonicOperatorGenerator(OperatorSpec spec, BiharmonicOptions options)
    : impl_(std::make_unique<Impl>()) {
  const auto t0 = std::chrono::steady_clock::now();
  validate(spec, "spec '" + spec.name + "'");
  impl_->spec = std::move(spec);
  impl_->opt = std::move(options);
  auto& m = *impl_;
  m.use_cholmod = m.opt.backend == SparseBackend::kCholmod ||
                  (m.opt.backend == SparseBackend::kAuto && detail::have_cholmod());
  if (m.opt.backend == SparseBackend::kCholmod)
    require(detail::have_cholmod(), "backend cholmod", "this isokit build has no CHOLMOD",
            "use SparseBackend::kSparseLU or rebuild with libsuitesparse-dev");
  m.stats.backend = m.use_cholmod ? "cholmod" : "sparselu";
  m.n = m.spec.resolution;
  m.h = 1.0 / (m.n - 1);
  m.build_system();
  if (m.opt.scheme != SliceScheme::kRefactor) m.init_schur();
  m.stats.scheme = m.schur ? "schur" : "refactor";
  m.stats.setup_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

BiharmonicOperatorGenerator::~BiharmonicOperatorGenerator() = default;

std::vector<float> BiharmonicOperatorGenerator::solve_slice(double d) {
  require(std::isfinite(d) && d >= 0 && d <= 1, "slice d", "must be in [0, 1] (got " + format_number(d) + ")",
          "d is the operator parameter");
  return impl_->solve(impl_->main, d);
}

std::vector<float> BiharmonicOperatorGenerator::solve_edited(double d, const OperatorSpec& edited) {
  require(std::isfinite(d) && d >= 0 && d <= 1, "slice d", "must be in [0, 1] (got " + format_number(d) + ")",
          "d is the operator parameter");
  validate(edited, "edited spec '" + edited.name + "'");
  require(edited.resolution == impl_->spec.resolution, "edited spec resolution",
          "must equal the generator's (" + std::to_string(impl_->spec.resolution) + ", got " +
              std::to_string(edited.resolution) + ")",
          "build a new generator to change the resolution");
  auto& m = *impl_;
  const Constraints c = m.constraints_at(edited, d);
  std::vector<double> x;
  last_edit_schur_ = m.schur && m.solve_schur(m.main, c, x);
  if (!last_edit_schur_) x = m.solve_refactor(m.main, c);
  return m.assemble(x);
}

GridOperator BiharmonicOperatorGenerator::generate() {
  const auto& m = *impl_;
  const int nd = m.spec.slices, nf = m.n;
  const std::size_t slice_size = static_cast<std::size_t>(nf) * nf;
  std::vector<float> data(slice_size * nd);
  int tasks =
      m.opt.tasks > 0 ? m.opt.tasks : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  tasks = std::min(tasks, nd);
  const std::size_t grain = tasks <= 1 ? 0 : static_cast<std::size_t>((nd + tasks - 1) / tasks);
  std::mutex mutex;
  int done = 0;
  bool main_used = false;
  parallel_for(static_cast<std::size_t>(nd), grain, [&](std::size_t begin, std::size_t end) {
    // The first chunk reuses the generator's workspace (already factored); others build theirs.
    Impl::Workspace local;
    Impl::Workspace* w = &local;
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (!main_used) main_used = true, w = &impl_->main;
    }
    for (std::size_t k = begin; k < end; ++k) {
      const std::vector<float> s = m.solve(*w, nd == 1 ? 0.0 : double(k) / (nd - 1));
      std::copy(s.begin(), s.end(), data.begin() + static_cast<std::ptrdiff_t>(k * slice_size));
      if (m.opt.progress) {
        std::lock_guard<std::mutex> lock(mutex);
        m.opt.progress(++done, nd);
      }
    }
  });
  return GridOperator(nd, nf, std::move(data));
}

const OperatorSpec& BiharmonicOperatorGenerator::spec() const {
  return impl_->spec;
}
const GeneratorStats& BiharmonicOperatorGenerator::stats() const {
  return impl_->stats;
}
bool BiharmonicOperatorGenerator::has_cholmod() {
  return detail::have_cholmod();
}

GridOperator generate_operator(const OperatorSpec& spec, const BiharmonicOptions& options) {
  BiharmonicOperatorGenerator gen(spec, options);
  return gen.generate();
}

}  // namespace isokit::operators
