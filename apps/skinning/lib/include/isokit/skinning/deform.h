// SPDX-License-Identifier: MIT
/// \file
/// Geometric skinning: linear blend skinning (LBS) and dual-quaternion skinning (DQS, Kavan et
/// al. 2008), the baselines and the initial/rotation sources of the implicit methods. Skinning
/// matrices come from `skinning_matrices(rig, pose)`; DQS blends their rigid parts (rotation from
/// the polar decomposition, see `rigid_part`) after the linear blend of their stretches (a clip's
/// scale keys; Kavan et al. 2008 §4.2), LBS the full affine matrices.
#pragma once

#include <vector>

#include "isokit/core/math.h"
#include "isokit/skinning/rig.h"
#include "isokit/track/mesh.h"

namespace isokit::skinning {

/// The rigid part of an affine matrix: the rotation of its polar decomposition (SVD, det +1)
/// and its translation.
Affine rigid_part(const Affine& a);
/// The stretch of an affine matrix: `P` with `a.linear() = R P` (R = rigid_part(a).linear(), P
/// symmetric positive definite; the identity for a rigid matrix).
Eigen::Matrix3d stretch_part(const Affine& a);
/// Largest difference of a stretch from the identity (or from another) that counts as none:
/// files store their transforms in single precision (exporters write scales of 0.99999988).
constexpr double kStretchTolerance = 1e-5;
/// `rigid_part(a)` as the float rigid transform the implicit fields take.
Rigid3f to_rigid3f(const Affine& a);
/// A rigid transform of libimplicit as an affine matrix.
Affine to_affine(const Rigid3d& x);

/// `out[v] = Σ w_vj M_j rest[v]`. `out` is resized. \throw InputError for size mismatches.
void linear_blend(const SkinWeights& weights, const std::vector<Affine>& skin, const track::Positions& rest,
                  track::Positions& out, std::size_t grain = 1024);

/// Dual-quaternion blending of the rigid parts of `skin` (antipodality fixed against each
/// vertex's largest-weight joint), applied to each rest vertex first stretched by the blend of
/// the matrices' stretches `Σ w_j P_j` (Kavan et al. 2008 §4.2: scale keys are kept; with rigid
/// matrices — within kStretchTolerance — the vertex is used as it is, bit for bit). `rotations`, when not
/// null, receives each vertex's blended rotation (the 2014 tracker's target rotations R_i, §5.1), times the
/// stretch blend when there is one (the ARAP targets then keep the scaled edge lengths).
void dual_quaternion_blend(const SkinWeights& weights, const std::vector<Affine>& skin,
                           const track::Positions& rest, track::Positions& out, std::vector<Mat3f>* rotations,
                           std::size_t grain = 1024);

/// Largest rotation angle (radians) of `rigid_part(a)` for each matrix.
double rotation_angle(const Affine& a);

}  // namespace isokit::skinning
