// SPDX-License-Identifier: MIT
/// \file
/// The rotation closest to a 3×3 matrix in the sense of max tr(Rᵀ A) (the rotation of a weighted
/// Procrustes fit). First the iteration of Müller, Bender, Chentanez and Macklin 2016 ("A robust
/// method to extract the rotational part of deformations", MIG 2016): R ← exp(ω) R with
/// ω = Σ_c r_c × a_c / |Σ_c r_c · a_c|, cheap and exact in zero steps from a good start; where it
/// has not converged within `max_steps` (ill-conditioned A: thin or folded neighbourhoods), the
/// exact answer of the SVD A = U Σ Vᵀ, R = U diag(1, 1, det(U Vᵀ)) Vᵀ. Private to isokit_skinning.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <cmath>

namespace isokit::skinning {

/// Starts at `start` (exact in zero steps when A = start · a symmetric positive semi-definite
/// matrix: at rest and under a rigid motion); A is normalised first, so the result does not depend
/// on its scale. A zero matrix returns `start`.
inline Eigen::Matrix3d best_rotation(const Eigen::Matrix3d& a, Eigen::Quaterniond start, int max_steps = 8) {
  const double norm = a.norm();
  if (!(norm > 0)) return start.toRotationMatrix();
  const Eigen::Matrix3d an = a / norm;
  Eigen::Matrix3d r = start.toRotationMatrix();
  for (int it = 0; it < max_steps; ++it) {
    const Eigen::Vector3d num =
        r.col(0).cross(an.col(0)) + r.col(1).cross(an.col(1)) + r.col(2).cross(an.col(2));
    const double den =
        std::abs(r.col(0).dot(an.col(0)) + r.col(1).dot(an.col(1)) + r.col(2).dot(an.col(2))) + 1e-9;
    const Eigen::Vector3d w = num / den;
    const double angle = w.norm();
    if (angle < 1e-10) return r;
    start = Eigen::Quaterniond(Eigen::AngleAxisd(angle, w / angle)) * start;
    start.normalize();
    r = start.toRotationMatrix();
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(an, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  if ((u * svd.matrixV().transpose()).determinant() < 0) u.col(2) = -u.col(2);
  return u * svd.matrixV().transpose();
}

}  // namespace isokit::skinning
