// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include "isokit/core/rotation_fit.h"
#include "test_util.h"

using namespace isokit;

namespace {

Eigen::Matrix3d to_eigen(const Mat3T<double>& r) {
  Eigen::Matrix3d out;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) out(a, b) = r(a, b);
  return out;
}

// A = R S: a random rotation times a symmetric positive definite stretch with singular values
// in [lo, hi] (their spread bounds how fast the iteration converges).
Eigen::Matrix3d stretched_rotation(test::Rng& rng, const Eigen::Matrix3d& r, double lo, double hi) {
  const Eigen::Matrix3d q = to_eigen(rng.rotation());
  const Eigen::Vector3d s(rng.uniform(lo, hi), rng.uniform(lo, hi), rng.uniform(lo, hi));
  return r * q * s.asDiagonal() * q.transpose();
}

bool is_rotation(const Eigen::Matrix3d& r) {
  return (r.transpose() * r - Eigen::Matrix3d::Identity()).norm() < 1e-12 &&
         std::abs(r.determinant() - 1) < 1e-12;
}

}  // namespace

TEST_CASE("rotation fit: the SVD maximises tr(R^T A) over rotations, reflections included", "[core]") {
  test::Rng rng(3);
  for (int trial = 0; trial < 300; ++trial) {
    Eigen::Matrix3d a = Eigen::Matrix3d::Random() * rng.uniform(0.1, 10);
    if (trial % 3 == 0) a.col(2) = a.col(0) * 0.5 - a.col(1);  // rank 2: a flat neighbourhood
    const Eigen::Matrix3d r = procrustes_rotation(a);
    REQUIRE(is_rotation(r));
    const double best = (r.transpose() * a).trace();
    for (int k = 0; k < 20; ++k) CHECK((to_eigen(rng.rotation()).transpose() * a).trace() <= best + 1e-12);
  }
}

TEST_CASE("rotation fit: the warm-started iteration reaches the SVD's rotation", "[core]") {
  test::Rng rng(4);
  for (int trial = 0; trial < 500; ++trial) {
    const Eigen::Matrix3d truth = to_eigen(rng.rotation());
    const Eigen::Matrix3d a = stretched_rotation(rng, truth, 0.5, 2.0) * rng.uniform(1e-3, 1e3);
    // A start up to 60 degrees from the answer.
    const Eigen::Vector3d axis = Eigen::Vector3d::Random().normalized();
    const Eigen::Quaterniond start(Eigen::AngleAxisd(rng.uniform(0, 1.05), axis) * truth);
    const Eigen::Matrix3d r = best_rotation(a, start, 50);
    REQUIRE(is_rotation(r));
    CHECK((r - procrustes_rotation(a)).norm() < 1e-8);
  }
}

TEST_CASE("rotation fit: exact in zero steps at the answer, a zero matrix keeps the start", "[core]") {
  test::Rng rng(5);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Matrix3d truth = to_eigen(rng.rotation());
    const Eigen::Matrix3d a = stretched_rotation(rng, truth, 0.2, 5.0);
    CHECK((best_rotation(a, Eigen::Quaterniond(truth), 0) - truth).norm() < 1e-9);
    CHECK((best_rotation(Eigen::Matrix3d::Zero(), Eigen::Quaterniond(truth)) - truth).norm() < 1e-12);
  }
}

TEST_CASE("rotation fit: from any start the result is a rotation no worse than the start", "[core]") {
  test::Rng rng(6);
  for (int trial = 0; trial < 500; ++trial) {
    Eigen::Matrix3d a = Eigen::Matrix3d::Random();
    if (trial % 4 == 0) a.col(1) = a.col(0) * 2.0;  // rank 2
    const Eigen::Matrix3d start = to_eigen(rng.rotation());
    const Eigen::Matrix3d r = best_rotation(a, Eigen::Quaterniond(start), 8);
    REQUIRE(is_rotation(r));
    CHECK((r.transpose() * a).trace() >= (start.transpose() * a).trace() - 1e-12);
  }
}
