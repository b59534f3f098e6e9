// SPDX-License-Identifier: MIT
/// \file
/// Which joints the real-rig evaluation bends, and about which local axis (docs/skinning-real-rigs.md,
/// "Bend-and-return rows"):
/// - elbows and knees by common names (ForeArm / LowerArm / Elbow; Knee / Shin / Calf / Leg, but
///   not UpLeg / UpperLeg / Thigh); in a chain of matching joints (Fox's `LeftLeg01` → `LeftLeg02`)
///   the deepest one with a grandchild; without an elbow (knee) name, the middle joint of each
///   limb chain (a run of single-child joints from a root or a branching joint) with "arm" ("leg")
///   in a joint's name; with neither, the middle joints of the four longest limb chains;
/// - the fold axis: the bend plane holds the parent bone P (parent → joint) and the child bone D
///   (joint → its farthest child, or → the centroid of the joint's own vertices for a leaf); the
///   axis is the local axis (x, y or z of the joint's frame) closest to P × D, signed so that the
///   bend deepens the rest fold; a straight limb (|P × D| < 0.05 |P| |D|) takes the local axis
///   most perpendicular to D (x first on ties), positive.
#pragma once

#include <vector>

#include "isokit/skinning/animation.h"

namespace isokit::eval {

/// The elbows and knees of `rig`, each bent to `degrees` about its fold axis.
std::vector<skinning::BendSpec> fold_joints(const skinning::Rig& rig, double degrees);

/// The `count` joints whose local rotation from the first pose grows largest over `poses`
/// (joints that own no vertex left out), as bends (axis: the local axis closest to the rotation
/// axis at that frame; degrees: its angle) for close-up views.
std::vector<skinning::BendSpec> moving_joints(const skinning::Rig& rig,
                                              const std::vector<skinning::Pose>& poses, int count);

}  // namespace isokit::eval
