// SPDX-License-Identifier: MIT
#include "sparse_solver.h"

#include <stdexcept>

#include <Eigen/SparseLU>

#include "isokit/core/error.h"

#ifdef ISOKIT_HAVE_CHOLMOD
#include <Eigen/CholmodSupport>
#endif

namespace isokit::operators::detail {
namespace {

class SparseLuSolver final : public SparseSolver {
 public:
  void analyze(const SpMat& a) override { lu_.analyzePattern(a); }
  void factorize(const SpMat& a) override {
    lu_.factorize(a);
    if (lu_.info() != Eigen::Success)
      throw std::runtime_error("SparseLU factorisation failed: " + lu_.lastErrorMessage());
  }
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) override { return lu_.solve(b); }
  std::string name() const override { return "sparselu"; }

 private:
  Eigen::SparseLU<SpMat, Eigen::COLAMDOrdering<int>> lu_;
};

#ifdef ISOKIT_HAVE_CHOLMOD
/// Eigen's CHOLMOD wrapper with access to the factor, for cholmod_solve2 with reused buffers
/// (cholmod_solve allocates its result per call; large dense right-hand sides then page-fault).
class CholmodLlt : public Eigen::CholmodDecomposition<SpMat, Eigen::Lower> {
 public:
  cholmod_factor* factor() { return this->m_cholmodFactor; }
};

class CholmodSolver final : public SparseSolver {
 public:
  CholmodSolver() {
    // Simplicial LLᵀ with CHOLMOD's default (AMD) ordering: measured faster than supernodal and
    // than METIS on these 13-point grid systems with Debian's reference BLAS (docs/performance.md).
    llt_.setMode(Eigen::CholmodSimplicialLLt);
  }
  ~CholmodSolver() override {
    for (cholmod_dense** d : {&x_, &y_, &e_})
      if (*d) cholmod_free_dense(d, &llt_.cholmod());
  }
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;
  void analyze(const SpMat& a) override { llt_.analyzePattern(a); }
  void factorize(const SpMat& a) override {
    llt_.factorize(a);
    if (llt_.info() != Eigen::Success)
      throw std::runtime_error("CHOLMOD factorisation failed (matrix not SPD)");
  }
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) override {
    cholmod_dense B{};
    B.nrow = static_cast<std::size_t>(b.rows());
    B.ncol = static_cast<std::size_t>(b.cols());
    B.nzmax = B.nrow * B.ncol;
    B.d = B.nrow;
    B.x = const_cast<double*>(b.data());
    B.xtype = CHOLMOD_REAL;
    B.dtype = CHOLMOD_DOUBLE;
    if (!cholmod_solve2(CHOLMOD_A, llt_.factor(), &B, nullptr, &x_, nullptr, &y_, &e_, &llt_.cholmod()))
      throw std::runtime_error("CHOLMOD solve failed");
    return Eigen::Map<const Eigen::MatrixXd>(static_cast<const double*>(x_->x), b.rows(), b.cols());
  }
  std::string name() const override { return "cholmod"; }

 private:
  CholmodLlt llt_;
  cholmod_dense *x_{nullptr}, *y_{nullptr}, *e_{nullptr};
};
#endif

}  // namespace

bool have_cholmod() {
#ifdef ISOKIT_HAVE_CHOLMOD
  return true;
#else
  return false;
#endif
}

std::unique_ptr<SparseSolver> make_sparse_solver(bool use_cholmod) {
#ifdef ISOKIT_HAVE_CHOLMOD
  if (use_cholmod) return std::make_unique<CholmodSolver>();
#else
  require(!use_cholmod, "backend cholmod", "this isokit build has no CHOLMOD",
          "use the sparselu backend or rebuild with libsuitesparse-dev installed");
#endif
  return std::make_unique<SparseLuSolver>();
}

}  // namespace isokit::operators::detail
