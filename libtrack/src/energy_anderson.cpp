// SPDX-License-Identifier: MIT
// Anderson acceleration of the energy tracker's local–global map (Walker & Ni 2011; Peng et al.
// 2018, "Anderson Acceleration for Geometry Optimization and Physics Simulation"): the caller
// keeps E monotone by rejecting an accelerated iterate that raises it (energy_tracker.cpp).
#include <algorithm>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/QR>

#include "energy_model.h"

namespace isokit::track::detail {

bool Anderson::step(std::vector<double>& x, const std::vector<double>& g) {
  if (window_ <= 0) {
    x = g;
    return false;
  }
  const std::size_t dim = g.size();
  std::vector<double> f(dim);
  for (std::size_t k = 0; k < dim; ++k) f[k] = g[k] - x[k];
  if (count_ > 0) {  // the newest differences replace the oldest in the ring
    const std::size_t col = std::size_t((count_ - 1) % window_);
    df_.resize(std::size_t(window_));
    dg_.resize(std::size_t(window_));
    df_[col].resize(dim);
    dg_[col].resize(dim);
    for (std::size_t k = 0; k < dim; ++k) df_[col][k] = f[k] - f_prev_[k], dg_[col][k] = g[k] - g_prev_[k];
  }
  const int cols = std::min(count_, window_);
  ++count_;
  f_prev_ = f;
  g_prev_ = g;
  x = g;
  if (cols == 0) return false;
  Eigen::MatrixXd a(dim, cols);
  for (int j = 0; j < cols; ++j)
    a.col(j) = Eigen::Map<const Eigen::VectorXd>(df_[std::size_t(j)].data(), long(dim));
  const Eigen::VectorXd theta =
      a.colPivHouseholderQr().solve(Eigen::Map<const Eigen::VectorXd>(f.data(), long(dim)));
  if (!theta.allFinite()) return false;
  for (int j = 0; j < cols; ++j)
    for (std::size_t k = 0; k < dim; ++k) x[k] -= theta[j] * dg_[std::size_t(j)][k];
  return true;
}

}  // namespace isokit::track::detail
