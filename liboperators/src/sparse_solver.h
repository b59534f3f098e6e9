// SPDX-License-Identifier: MIT
// Internal: the sparse SPD solver behind the biharmonic generator — CHOLMOD (when built with
// it) or Eigen's SparseLU. No CHOLMOD header leaks out of sparse_solver.cpp.
#pragma once

#include <memory>
#include <string>

#include <Eigen/Dense>
#include <Eigen/SparseCore>

namespace isokit::operators::detail {

using SpMat = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

class SparseSolver {
 public:
  virtual ~SparseSolver() = default;
  /// Symbolic analysis of the pattern of `a` (full symmetric storage).
  virtual void analyze(const SpMat& a) = 0;
  /// Numeric factorisation; `a` has the analysed pattern. \throw std::runtime_error on failure.
  virtual void factorize(const SpMat& a) = 0;
  virtual Eigen::MatrixXd solve(const Eigen::MatrixXd& b) = 0;
  virtual std::string name() const = 0;
};

bool have_cholmod();
/// `use_cholmod` false → SparseLU. \throw isokit::InputError when CHOLMOD is asked for but absent.
std::unique_ptr<SparseSolver> make_sparse_solver(bool use_cholmod);

}  // namespace isokit::operators::detail
