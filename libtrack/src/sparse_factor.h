// SPDX-License-Identifier: MIT
// The sparse Cholesky factor of libtrack's global solves (the 2014 tracker's tangent-plane solve,
// global_solve.cpp, and the energy tracker's global step, energy_system.cpp): CHOLMOD's
// simplicial LLᵀ when the build has CHOLMOD — measured faster than its supernodal mode (Debian's
// reference BLAS) and than Eigen's SimplicialLLT on these systems (docs/performance.md, "The
// global solve") — else Eigen's SimplicialLLT with AMD ordering (not installed).
#pragma once

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#ifdef ISOKIT_HAVE_CHOLMOD
#include <Eigen/CholmodSupport>
#endif

namespace isokit::track::detail {

using SpMat = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
#ifdef ISOKIT_HAVE_CHOLMOD
class Factor : public Eigen::CholmodDecomposition<SpMat, Eigen::Lower> {
 public:
  Factor() { setMode(Eigen::CholmodSimplicialLLt); }
};
#else
using Factor = Eigen::SimplicialLLT<SpMat, Eigen::Lower, Eigen::AMDOrdering<int> >;
#endif

}  // namespace isokit::track::detail
