// SPDX-License-Identifier: MIT
// retarget_clip: a clip of one skeleton played on another by joint name, each joint turning in
// world space as its namesake turns away from the source's rest pose.
#include <algorithm>
#include <cmath>

#include "isokit/core/error.h"
#include "isokit/skinning/animation.h"

namespace isokit::skinning {

namespace {

// Size of a skeleton at rest: the diagonal of its joints' bounding box over `joints`.
double rest_extent(const Rig& rig, const std::vector<int>& joints) {
  const std::vector<Eigen::Vector3d> p = rest_joint_positions(rig);
  Eigen::AlignedBox3d box;
  for (int j : joints) box.extend(p[static_cast<std::size_t>(j)]);
  return box.isEmpty() ? 0.0 : box.diagonal().norm();
}

// One retargeted frame: `source_world` the source's world transforms at the frame.
Pose retarget_frame(const Rig& target, const std::vector<Affine>& target_rest_world,
                    const std::vector<int>& match, const std::vector<Affine>& source_rest_world,
                    const std::vector<Affine>& source_world, double scale) {
  const std::size_t n = target.joints.size();
  std::vector<Affine> world(n);
  Pose local(n);
  for (std::size_t j = 0; j < n; ++j) {
    const Joint& joint = target.joints[j];
    const int p = joint.parent;
    const int s = match[j];
    Eigen::Matrix3d rotation = target_rest_world[j].linear();
    if (s >= 0) {  // the source joint's world rotation away from its own rest, applied to ours
      const auto si = static_cast<std::size_t>(s);
      rotation = source_world[si].linear() * source_rest_world[si].linear().inverse() * rotation;
    } else if (p >= 0) {  // unmatched: rigid with its parent
      rotation = world[static_cast<std::size_t>(p)].linear() *
                 target_rest_world[static_cast<std::size_t>(p)].linear().inverse() * rotation;
    }
    Affine w = Affine::Identity();
    w.linear() = rotation;
    if (p < 0) {
      w.translation() = target_rest_world[j].translation();
      if (s >= 0)
        w.translation() += scale * (source_world[static_cast<std::size_t>(s)].translation() -
                                    source_rest_world[static_cast<std::size_t>(s)].translation());
      local[j] = w;
    } else {
      w.translation() = world[static_cast<std::size_t>(p)] * joint.rest_local.translation();
      local[j] = world[static_cast<std::size_t>(p)].inverse(Eigen::Affine) * w;
    }
    world[j] = w;
  }
  return local;
}

}  // namespace

Clip retarget_clip(const Rig& source, const Clip& clip, const Rig& target, RetargetReport* report) {
  std::vector<int> match(target.joints.size(), -1);
  std::vector<int> matched_source;
  std::vector<char> used(source.joints.size(), 0);
  RetargetReport local_report;
  RetargetReport& r = report ? *report : local_report;
  r = RetargetReport{};
  for (std::size_t j = 0; j < target.joints.size(); ++j) {
    match[j] = source.joint_index(target.joints[j].name);
    if (match[j] < 0) {
      r.unmatched_target.push_back(target.joints[j].name);
      continue;
    }
    used[static_cast<std::size_t>(match[j])] = 1;
    matched_source.push_back(match[j]);
  }
  for (std::size_t s = 0; s < source.joints.size(); ++s)
    if (!used[s]) r.unmatched_source.push_back(source.joints[s].name);
  require(!matched_source.empty(), "clip " + clip.name + " of " + source.name,
          "shares no joint name with " + target.name,
          "use a clip made for this skeleton (joints are matched by name)");
  std::vector<int> matched_target;
  for (std::size_t j = 0; j < match.size(); ++j)
    if (match[j] >= 0) matched_target.push_back(static_cast<int>(j));
  const double source_size = rest_extent(source, matched_source);
  const double scale = source_size > 0 ? rest_extent(target, matched_target) / source_size : 1.0;
  const std::vector<Affine> target_rest_world = world_transforms(target, rest_pose(target));
  const std::vector<Affine> source_rest_world = world_transforms(source, rest_pose(source));
  Clip out;
  out.name = clip.name;
  out.fps = clip.fps;
  for (const std::vector<Affine>& frame : clip_frames(clip))
    out.local.push_back(retarget_frame(target, target_rest_world, match, source_rest_world,
                                       world_transforms(source, frame), scale));
  return out;
}

}  // namespace isokit::skinning
