// SPDX-License-Identifier: MIT
/// \file
/// The rotation closest to a 3×3 matrix A in the sense of max tr(Rᵀ A): the rotation of a
/// weighted Procrustes fit (ARAP's local step, Sorkine & Alexa 2007; ddm's per-vertex fit). Two
/// forms: the exact one from the SVD A = U Σ Vᵀ, R = U diag(1, 1, det(U Vᵀ)) Vᵀ; and the iteration
/// of Müller, Bender, Chentanez and Macklin 2016 ("A robust method to extract the rotational part
/// of deformations", MIG 2016), R ← exp(ω) R with ω = Σ_c r_c × a_c / |Σ_c r_c · a_c| (r_c, a_c
/// the columns of R and A), exact in zero steps from the answer. It converges linearly, at a rate
/// set by the spread of A's singular values, so it pays only where few steps are wanted.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <cmath>

namespace isokit {

/// The exact maximiser of tr(Rᵀ A) over rotations, by the SVD (for a rank-deficient A one of the
/// maximisers).
inline Eigen::Matrix3d procrustes_rotation(const Eigen::Matrix3d& a) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(a, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  if ((u * svd.matrixV().transpose()).determinant() < 0) u.col(2) = -u.col(2);  // smallest σ last
  return u * svd.matrixV().transpose();
}

/// Müller et al.'s iteration from `start`, until the step's angle is below `angle_tolerance`
/// (radians) or `max_steps`; A is normalised first, so the result does not depend on its scale.
/// Exact in zero steps when A = start · a symmetric positive semi-definite matrix (at rest and
/// under a rigid motion). Where it has not converged within `max_steps` (ill-conditioned A: thin
/// or folded neighbourhoods), or converged to a critical point worse than `start` (a saddle of
/// tr(Rᵀ A)), it returns the SVD's answer. A zero matrix returns `start`.
inline Eigen::Matrix3d best_rotation(const Eigen::Matrix3d& a, Eigen::Quaterniond start, int max_steps = 8,
                                     double angle_tolerance = 1e-10) {
  const double norm = a.norm();
  if (!(norm > 0)) return start.toRotationMatrix();
  const Eigen::Matrix3d an = a / norm;
  Eigen::Matrix3d r = start.toRotationMatrix();
  const double at_start = (r.transpose() * an).trace();
  for (int it = 0; it < max_steps; ++it) {
    const Eigen::Vector3d num =
        r.col(0).cross(an.col(0)) + r.col(1).cross(an.col(1)) + r.col(2).cross(an.col(2));
    const double den =
        std::abs(r.col(0).dot(an.col(0)) + r.col(1).dot(an.col(1)) + r.col(2).dot(an.col(2))) + 1e-9;
    const Eigen::Vector3d w = num / den;
    const double angle = w.norm();
    if (angle < angle_tolerance) {
      if ((r.transpose() * an).trace() >= at_start) return r;
      break;
    }
    start = Eigen::Quaterniond(Eigen::AngleAxisd(angle, w / angle)) * start;
    start.normalize();
    r = start.toRotationMatrix();
  }
  return procrustes_rotation(an);
}

}  // namespace isokit
