// SPDX-License-Identifier: MIT
/// \file
/// Animations as sequences of poses (local joint transforms per frame): a clip of the rig,
/// `--bend JOINT:AXIS:DEGREES` bends, JSON pose scripts, and the sub-stepping of 2014 §5.2.
#pragma once

#include <string>
#include <vector>

#include "isokit/skinning/rig.h"
#include "isokit/skinning/setup.h"

namespace isokit::skinning {

using Pose = std::vector<Affine>;  ///< local transform per joint

/// One `--bend` option: rotate `joint` about axis `axis` (0 = x, 1 = y, 2 = z) of its local
/// frame by `degrees` (at the peak of the bend).
struct BendSpec {
  int joint{-1};
  int axis{0};
  double degrees{0};
};

/// Parses `JOINT:AXIS:DEGREES` (JOINT a name or an index, AXIS x|y|z).
/// \throw InputError naming the option, the joint names when the joint is unknown.
BendSpec parse_bend(const std::string& text, const Rig& rig);

/// The full-body crouch isokit measures the 2014 Table 1 protocol with ("all joints animated
/// simultaneously"): spine, neck, head, arms, forearms, hands, fingers, thighs, knees and feet of
/// the procedural humanoid bent together, arms raised in front, at most 90° per joint; the joints
/// the rig lacks (no fingers) are skipped. docs/performance.md.
std::vector<BendSpec> crouch_bends(const Rig& rig);

/// `frames` poses bending every spec from rest to its angle and back to rest (frame 0 and the
/// last frame are the rest pose; the peak is frame `frames / 2`). \throw InputError if frames < 3.
std::vector<Pose> bend_animation(const Rig& rig, const std::vector<BendSpec>& bends, int frames);

/// The rig's clip `name`. \throw InputError listing the clips when absent.
std::vector<Pose> clip_animation(const Rig& rig, const std::string& name);

/// A pose script (JSON): `{"keys": [{"frame": 0, "joints": {"LeftForeArm": [["z", 90]]}}, ...]}`;
/// each joint's rotations (axis, degrees) are applied in order in its local frame on top of the
/// rest pose; joints absent from a key are at rest; poses between keys are interpolated
/// (quaternion slerp). \throw InputError naming the file and the item.
std::vector<Pose> pose_script_animation(const Rig& rig, const std::string& path);
std::vector<Pose> pose_script_from_json(const Rig& rig, const std::string& text, const std::string& source);

/// Joints `retarget_clip` could not match by name (they stay at rest relative to their parent).
struct RetargetReport {
  std::vector<std::string> unmatched_target;  ///< joints of the target rig no source joint names
  std::vector<std::string> unmatched_source;  ///< animated joints of the source with no namesake
};

/// `clip` (of the skeleton `source`) played on `target`, joints matched by name: each matched
/// joint turns in world space as its namesake turns away from the source's own rest pose (so the
/// two skeletons' rest orientations may differ); bone lengths stay the target's; root joints
/// move as the source's roots do, scaled by the ratio of the two skeletons' rest sizes. Both
/// skeletons must be in the same scene axes. \throw InputError when no joint name matches.
Clip retarget_clip(const Rig& source, const Clip& clip, const Rig& target, RetargetReport* report = nullptr);

/// Pose between `a` and `b` at `t` ∈ [0, 1]: rotations slerped, translations and scales lerped.
Pose interpolate(const Pose& a, const Pose& b, double t);

/// Number of sub-steps from `a` to `b` (≥ 1): 2014 §5.2 (every joint's local rotation per
/// sub-step below a third of its bending angle, floored) and/or a fixed maximum angle.
int substeps(const Rig& rig, const Pose& a, const Pose& b, const SubstepOptions& options);

/// Largest local rotation angle (radians) of any joint between two poses.
double max_rotation_between(const Pose& a, const Pose& b);

}  // namespace isokit::skinning
