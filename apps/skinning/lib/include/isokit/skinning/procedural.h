// SPDX-License-Identifier: MIT
/// \file
/// Built-in procedural rigs: closed, manifold, outward-oriented triangle meshes with a skeleton,
/// bind matrices and heat-diffusion weights (weights.h), named `procedural:<canonical spec>`.
/// Every rig passes `validate` and is deterministic (same options → bit-identical rig).
///
/// Joint frames (all rigs): local +y runs along the bone toward the joint's main child (leaves:
/// along their own bone), local +z is the joint's *flexion side*, x = y × z. A positive rotation
/// about local **+x** swings the child toward +z, i.e. flexes the joint:
///  - cylinder, finger: the bone axis is world +y; +x bends toward world +z (finger: the palm side);
///  - humanoid (T-pose, y up, facing +z, its left at +x): Hips/Spine*/Neck/Head bend forward;
///    shoulders, arms and forearms swing forward (`--bend LeftForeArm:x:150` folds the elbow, the
///    hand moving forward and back toward the shoulder); LeftUpLeg swings the leg forward (hip
///    flexion); LeftLeg folds the knee backward (`--bend LeftLeg:x:150`: the foot moves back and
///    up); hands, fingers, thumbs, feet and toes curl toward the palm / sole (world −y).
#pragma once

#include <string>

#include "isokit/skinning/rig.h"
#include "isokit/track/mesh.h"

namespace isokit::skinning {

/// The 2014 paper's Fig. 2 test shape: a cylinder along +y, body from y = 0 to `length`, with
/// hemispherical caps. Joints "Bone0" (root, y = 0) and "Bone1" (y = length/2); Bone1's bone ends
/// at y = length. Tessellated as rings (≈ equilateral triangles, caps with shrinking rings).
struct CylinderOptions {
  int vertices{2000};  ///< requested vertex count (achieved within ~2 %)
  double length{2.0};
  double radius{0.3};
};

/// A finger along +y, palm side +z, slightly tapered (radius 0.09 → 0.072), rounded base and tip,
/// 1.0 long: joints "Finger0" (root, base of the metacarpal, y = 0), "Finger1" (knuckle,
/// y = 0.15), "Finger2" (y = 0.55), "Finger3" (y = 0.80; its bone ends at the tip centre, 0.98).
struct FingerOptions {
  int vertices{3000};  ///< requested vertex count (achieved within ~2 %)
};

/// A ~1.8 tall T-pose humanoid (feet at y = 0, facing +z, left at +x), the smooth union of tapered
/// capsules along the bones, meshed by CGAL Mesh_3 Delaunay refinement (facet angles ≥ 30°).
/// Joints, parents first: Hips, Spine, Spine1, Spine2, Neck, Head, LeftShoulder, LeftArm,
/// LeftForeArm, LeftHand, [LeftHandThumb1..3, LeftHandIndex1..3, LeftHandMiddle1..3,
/// LeftHandPinky1..3,] the Right… twins, LeftUpLeg, LeftLeg, LeftFoot, LeftToeBase, RightUpLeg,
/// RightLeg, RightFoot, RightToeBase: 22 joints, 46 with fingers. Fingers are separate from each
/// other (gaps ≈ one finger radius).
struct HumanoidOptions {
  int vertices{13000};  ///< requested count, 3000 (2000 without fingers) .. 400000; achieved ±10 %
  bool fingers{true};
};

Rig make_cylinder(const CylinderOptions& options = {});
Rig make_finger(const FingerOptions& options = {});
Rig make_humanoid(const HumanoidOptions& options = {});

/// Parses `NAME[?KEY=VALUE[&KEY=VALUE...]]`: `cylinder` (vertices, length, radius), `finger`
/// (vertices), `humanoid` (vertices, fingers=0|1). Example: `humanoid?vertices=13000&fingers=0`.
/// \throw InputError for an unknown name, key or a bad value, listing the valid ones.
Rig make_procedural(const std::string& spec);

/// Geometric checks of a triangle mesh (used by the tests; handy for loaded rigs too).
struct SurfaceReport {
  int boundary_edges{0};           ///< edges with one triangle
  int nonmanifold_edges{0};        ///< edges with more than two triangles
  int nonmanifold_vertices{0};     ///< vertices whose triangles form more than one fan
  int inconsistent_edges{0};       ///< edges traversed twice in the same direction
  int components{0};               ///< connected components (over triangles)
  int euler{0};                    ///< V − E + F (2 for each sphere-like component)
  double volume{0};                ///< enclosed signed volume (> 0 when oriented outward)
  double min_angle_deg{0};         ///< smallest triangle angle
  double fraction_below_20deg{0};  ///< fraction of triangles with an angle below 20°
  bool self_intersects{false};     ///< only when asked (exact: `count_self_intersections`)
};

/// \throw InputError for bad indices.
SurfaceReport inspect_surface(const track::Positions& vertices, const track::Triangles& triangles,
                              bool check_self_intersections = false);

}  // namespace isokit::skinning
