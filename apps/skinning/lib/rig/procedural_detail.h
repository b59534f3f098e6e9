// SPDX-License-Identifier: MIT
// Internal: shared pieces of the procedural rigs (joint frames, bind matrices, weights).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "isokit/skinning/rig.h"
#include "isokit/skinning/weights.h"
#include "rig/polygonize.h"

namespace isokit::skinning::detail {

/// One joint of a procedural skeleton, in world (mesh) coordinates at rest.
struct JointSpec {
  std::string name;
  int parent{-1};
  Eigen::Vector3d position{Eigen::Vector3d::Zero()};
  Eigen::Vector3d y_dir{Eigen::Vector3d::UnitY()};  ///< local +y: along the bone
  Eigen::Vector3d z_ref{Eigen::Vector3d::UnitZ()};  ///< local +z: flexion side (made ⟂ y)
  std::vector<Segment> bones;                       ///< segments for the heat weights
};

/// World rest rotation of a joint: columns x = y × z, y, z (orthonormal, right-handed).
Eigen::Matrix3d joint_frame(const Eigen::Vector3d& y_dir, const Eigen::Vector3d& z_ref);

/// Builds the rig (frames, rest_local, inverse_bind = inverse world rest transform, heat
/// weights from the joints' bones), then `validate`s it.
Rig assemble_rig(const std::string& name, TriangleMesh mesh, const std::vector<JointSpec>& joints);

}  // namespace isokit::skinning::detail
