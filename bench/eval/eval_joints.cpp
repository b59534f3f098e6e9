// SPDX-License-Identifier: MIT
#include "eval_joints.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>

namespace isokit::eval {

namespace {

using skinning::Affine;
using skinning::BendSpec;
using skinning::Rig;

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool contains_any(const std::string& s, std::initializer_list<const char*> words) {
  for (const char* w : words)
    if (s.find(w) != std::string::npos) return true;
  return false;
}

bool is_elbow_name(const std::string& name) {
  return contains_any(lower(name), {"forearm", "lowerarm", "lower_arm", "elbow"});
}

bool is_knee_name(const std::string& name) {
  const std::string s = lower(name);
  if (contains_any(s, {"upleg", "upperleg", "upper_leg", "thigh"})) return false;
  return contains_any(s, {"knee", "shin", "calf", "leg"});
}

std::vector<std::vector<int>> children_of(const Rig& rig) {
  std::vector<std::vector<int>> children(rig.joints.size());
  for (std::size_t j = 0; j < rig.joints.size(); ++j)
    if (rig.joints[j].parent >= 0) children[static_cast<std::size_t>(rig.joints[j].parent)].push_back(int(j));
  return children;
}

/// Longest path (in joints) from each joint down to a leaf: 0 for a leaf.
std::vector<int> subtree_heights(const Rig& rig) {
  std::vector<int> height(rig.joints.size(), 0);
  for (std::size_t j = rig.joints.size(); j-- > 0;) {
    const int p = rig.joints[j].parent;
    if (p >= 0)
      height[static_cast<std::size_t>(p)] = std::max(height[static_cast<std::size_t>(p)], height[j] + 1);
  }
  return height;
}

/// Joints matching `match`; in a chain of matching joints, the deepest with a grandchild.
template <typename Match>
std::vector<int> named_joints(const Rig& rig, Match match) {
  const std::vector<int> height = subtree_heights(rig);
  std::vector<int> chosen(rig.joints.size(), -1);  // per chain head: the chosen joint
  std::vector<int> head(rig.joints.size(), -1);
  for (std::size_t j = 0; j < rig.joints.size(); ++j) {
    if (!match(rig.joints[j].name)) continue;
    const int p = rig.joints[j].parent;
    head[j] = (p >= 0 && head[static_cast<std::size_t>(p)] >= 0) ? head[static_cast<std::size_t>(p)] : int(j);
    int& c = chosen[static_cast<std::size_t>(head[j])];
    if (c < 0 || height[j] >= 2) c = int(j);
  }
  std::vector<int> out;
  for (int c : chosen)
    if (c >= 0) out.push_back(c);
  return out;
}

/// The middle joint of each limb chain (runs of single-child joints from a root or a branch)
/// that has a joint whose lower-case name contains `word` (any chain for an empty word).
std::vector<int> chain_middles(const Rig& rig, const std::string& word) {
  const std::vector<std::vector<int>> children = children_of(rig);
  std::vector<std::vector<int>> chains;
  for (std::size_t j = 0; j < rig.joints.size(); ++j) {
    const int p = rig.joints[j].parent;
    if (p >= 0 && children[static_cast<std::size_t>(p)].size() == 1) continue;  // not a chain start
    std::vector<int> chain{int(j)};
    while (children[static_cast<std::size_t>(chain.back())].size() == 1)
      chain.push_back(children[static_cast<std::size_t>(chain.back())][0]);
    const bool named =
        word.empty() || std::any_of(chain.begin(), chain.end(), [&](int c) {
          return lower(rig.joints[static_cast<std::size_t>(c)].name).find(word) != std::string::npos;
        });
    if (chain.size() >= 2 && named) chains.push_back(chain);
  }
  std::stable_sort(chains.begin(), chains.end(),
                   [](const auto& a, const auto& b) { return a.size() > b.size(); });
  if (chains.size() > 4) chains.resize(4);
  std::vector<int> out;
  for (const std::vector<int>& c : chains) out.push_back(c[c.size() / 2]);
  std::sort(out.begin(), out.end());
  return out;
}

/// Direction of the child bone: to the farthest child joint, else to the joint's own vertices.
Eigen::Vector3d child_direction(const Rig& rig, int joint, const std::vector<Eigen::Vector3d>& pos,
                                const std::vector<int>& dominant) {
  Eigen::Vector3d best = Eigen::Vector3d::Zero();
  for (std::size_t c = 0; c < rig.joints.size(); ++c)
    if (rig.joints[c].parent == joint && (pos[c] - pos[joint]).norm() > best.norm())
      best = pos[c] - pos[joint];
  if (best.norm() > 0) return best;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int n = 0;
  for (std::size_t v = 0; v < dominant.size(); ++v)
    if (dominant[v] == joint) {
      sum += rig.rest.row(static_cast<Eigen::Index>(v)).cast<double>().transpose();
      ++n;
    }
  return n > 0 ? Eigen::Vector3d(sum / n - pos[joint]) : Eigen::Vector3d::Zero();
}

/// Direction of the parent bone: from the nearest ancestor at a different place to the joint.
Eigen::Vector3d parent_direction(const Rig& rig, int joint, const std::vector<Eigen::Vector3d>& pos) {
  const double eps = 1e-9 * (1 + pos[joint].norm());
  for (int a = rig.joints[joint].parent; a >= 0; a = rig.joints[a].parent)
    if ((pos[joint] - pos[a]).norm() > eps) return pos[joint] - pos[a];
  return Eigen::Vector3d::Zero();
}

/// The fold axis of `joint` as (axis index, sign), by the rule in eval_joints.h.
BendSpec fold_axis(const Rig& rig, int joint, const std::vector<Eigen::Vector3d>& pos,
                   const std::vector<Affine>& world, const std::vector<int>& dominant, double degrees) {
  const Eigen::Matrix3d to_local = world[joint].linear().inverse();
  const Eigen::Vector3d d = to_local * child_direction(rig, joint, pos, dominant);
  const Eigen::Vector3d p = to_local * parent_direction(rig, joint, pos);
  const Eigen::Vector3d n = p.cross(d);
  BendSpec b;
  b.joint = joint;
  b.degrees = degrees;
  if (n.norm() >= 0.05 * p.norm() * d.norm() && n.norm() > 0) {
    n.cwiseAbs().maxCoeff(&b.axis);
    if (n[b.axis] < 0) b.degrees = -degrees;
    return b;
  }
  const Eigen::Vector3d dn = d.norm() > 0 ? Eigen::Vector3d(d.normalized()) : Eigen::Vector3d::UnitY();
  const double least = dn.cwiseAbs().minCoeff();
  b.axis = std::abs(dn.x()) <= least + 1e-3   ? 0
           : std::abs(dn.y()) <= least + 1e-3 ? 1
                                              : 2;  // x first on ties
  return b;
}

}  // namespace

std::vector<BendSpec> fold_joints(const Rig& rig, double degrees) {
  std::vector<int> joints = named_joints(rig, is_elbow_name);
  if (joints.empty()) joints = chain_middles(rig, "arm");
  std::vector<int> knees = named_joints(rig, is_knee_name);
  if (knees.empty()) knees = chain_middles(rig, "leg");
  joints.insert(joints.end(), knees.begin(), knees.end());
  if (joints.empty()) joints = chain_middles(rig, "");
  const std::vector<Eigen::Vector3d> pos = skinning::rest_joint_positions(rig);
  const std::vector<Affine> world = skinning::world_transforms(rig, skinning::rest_pose(rig));
  const std::vector<int> dominant = skinning::dominant_joint(rig.weights, static_cast<int>(rig.rest.rows()));
  std::vector<BendSpec> out;
  for (int j : joints) out.push_back(fold_axis(rig, j, pos, world, dominant, degrees));
  return out;
}

std::vector<BendSpec> moving_joints(const Rig& rig, const std::vector<skinning::Pose>& poses, int count) {
  const std::vector<int> dominant = skinning::dominant_joint(rig.weights, static_cast<int>(rig.rest.rows()));
  std::vector<char> owns(rig.joints.size(), 0);
  for (int j : dominant) owns[static_cast<std::size_t>(j)] = 1;
  std::vector<BendSpec> all;
  for (std::size_t j = 0; j < rig.joints.size() && !poses.empty(); ++j) {
    if (!owns[j]) continue;
    BendSpec b;
    b.joint = int(j);
    for (const skinning::Pose& pose : poses) {
      const Eigen::AngleAxisd r(Eigen::Matrix3d(poses[0][j].rotation().transpose() * pose[j].rotation()));
      if (std::abs(r.angle()) * 180 / M_PI <= std::abs(b.degrees)) continue;
      b.degrees = r.angle() * 180 / M_PI;
      r.axis().cwiseAbs().maxCoeff(&b.axis);
    }
    all.push_back(b);
  }
  std::stable_sort(all.begin(), all.end(), [](const BendSpec& a, const BendSpec& b) {
    return std::abs(a.degrees) > std::abs(b.degrees);
  });
  if (all.size() > static_cast<std::size_t>(count)) all.resize(static_cast<std::size_t>(count));
  return all;
}

}  // namespace isokit::eval
