// SPDX-License-Identifier: MIT
/// \file
/// The rotation closest to a 3×3 matrix in the sense of max tr(Rᵀ A) (the rotation of a weighted
/// Procrustes fit), by the iteration of Müller, Bender, Chentanez and Macklin 2016 ("A robust
/// method to extract the rotational part of deformations", MIG 2016): R ← exp(ω) R with
/// ω = Σ_c r_c × a_c / |Σ_c r_c · a_c|. Private to isokit_skinning (DDM).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace isokit::skinning {

/// Starts at `start` (a good guess makes it exact in zero steps when A = start · symmetric PSD,
/// e.g. at rest and under rigid motion); A is normalised first, so the result does not depend on
/// its scale. A zero matrix returns `start`.
inline Eigen::Matrix3d best_rotation(const Eigen::Matrix3d& a, Eigen::Quaterniond start, int max_steps = 30) {
  const double norm = a.norm();
  if (!(norm > 0)) return start.toRotationMatrix();
  const Eigen::Matrix3d an = a / norm;
  Eigen::Matrix3d r = start.toRotationMatrix();
  for (int it = 0; it < max_steps; ++it) {
    const Eigen::Vector3d num = r.col(0).cross(an.col(0)) + r.col(1).cross(an.col(1)) + r.col(2).cross(an.col(2));
    const double den = std::abs(r.col(0).dot(an.col(0)) + r.col(1).dot(an.col(1)) + r.col(2).dot(an.col(2))) + 1e-9;
    const Eigen::Vector3d w = num / den;
    const double angle = w.norm();
    if (angle < 1e-13) break;
    start = Eigen::Quaterniond(Eigen::AngleAxisd(angle, w / angle)) * start;
    start.normalize();
    r = start.toRotationMatrix();
  }
  return r;
}

}  // namespace isokit::skinning
