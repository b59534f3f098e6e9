// SPDX-License-Identifier: MIT
/// \file
/// The composed field of a fitted rig (2013 §4.2 and 2014 §4 trees) posed by skinning matrices:
/// the compiled program of the composition tree (built once) and its poses (one per frame, or
/// one per purpose: the tracker's and the metrics' poses of the same program).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "isokit/implicit/pose.h"
#include "isokit/implicit/program.h"
#include "isokit/operators/controller.h"
#include "isokit/skinning/fitted_rig.h"
#include "isokit/skinning/setup.h"
#include "isokit/track/field.h"

namespace isokit::skinning {

/// The composed field of a fitted rig for one tree kind, posed by skinning matrices.
class SkinField {
 public:
  /// Builds the tree: joints without a primitive are skipped (their children attach to the
  /// nearest ancestor with one; several roots hang under the first). Grid operators (contact,
  /// bulge: presets or the setup's spec files) are generated once per process and kept in the
  /// operator disk cache (grid_operators.h, 2014 §4.2). The current pose is the fitted (rest) one.
  /// \throw InputError for a spec whose grid fails its check, or a joint spec on a union / blend
  /// joint.
  SkinField(const FittedRig& fitted, const SkinSetup& setup, TreeKind tree, const Progress& progress = {});

  /// The pose of skinning matrices `skin` (one per joint): every primitive moved by the rigid
  /// part of its joint's skinning matrix and stretched by the rest (a clip's scale keys: the
  /// stretch seen in the primitive's frame, its shear dropped), each muscle (SkinSetup::muscles) moved with
  /// its bone and scaled by its driver's bend, and (bulge gate, SkinSetup::bulge_gate) each bulge node's
  /// controller capped by its joint's bend. \throw InputError for a wrong matrix count.
  std::shared_ptr<const implicit::Pose> pose_of(const std::vector<Affine>& skin) const;
  /// Makes `pose_of(skin)` the current pose (functions made before keep theirs).
  void set_pose(const std::vector<Affine>& skin);

  /// Value + gradient for the tracker, at the current pose or at `pose` (one of this field's
  /// program). With `contacts`, `contact[k]` is set where a contact node is active (per-node
  /// diagnostics: about 2x slower); without, the contact buffer is left alone. Thread-safe:
  /// every call makes its own evaluator.
  track::FieldFunction function(bool contacts = false) const { return function(pose_, contacts); }
  track::FieldFunction function(std::shared_ptr<const implicit::Pose> pose, bool contacts = false) const;

  const implicit::Program& program() const { return *program_; }
  const std::shared_ptr<const implicit::Program>& shared_program() const { return program_; }
  const std::shared_ptr<const implicit::Pose>& rest_pose() const { return rest_; }  ///< the fitted pose
  const implicit::Pose& pose() const { return *pose_; }
  TreeKind kind() const { return kind_; }
  /// Per-joint operators ("joint: operator", describe_joint_operator: "Bone1: contact (preset)",
  /// "Bone2: bulge (spec my_bulge.json, hash ...)"), for reports.
  std::vector<std::string> joint_operators() const { return joint_ops_; }

 private:
  /// A bulge node gated by the bend between its two primitives' joints.
  struct BulgeGate {
    std::size_t instruction;
    int parent_joint, child_joint;  // skinning-matrix indices
    operators::ControllerTable base;
    operators::Controller controller;  ///< the node's own d_b (preset or spec file), for the cap
  };
  /// A muscle's leaf (SkinSetup::muscles): carried by `bone`, scaled by `driver`'s bend.
  struct MuscleLeaf {
    int id;                           ///< leaf id in the program
    int bone, driver, driver_parent;  ///< rig joints (skinning-matrix indices)
    Affine rest;                      ///< unit-sphere frame -> rest space (rotation + centre)
    MuscleSetup setup;
  };
  /// A rigid piece's leaf (SkinSetup::piece_fields): its distance field, carried by `bone`.
  struct PieceLeaf {
    int id;       ///< leaf id in the program
    int bone;     ///< rig joint (skinning-matrix index): the piece's largest influence
    Affine rest;  ///< the field's frame -> rest space
  };
  struct Skeleton;
  Skeleton compressed_skeleton(const SkinSetup& setup, const Progress& progress);
  void add_muscles(const SkinSetup& setup, const std::vector<int>& index, const Progress& progress,
                   Skeleton& sk);
  void pose_muscles(const std::vector<Affine>& skin, implicit::Pose& pose) const;
  void add_pieces(const SkinSetup& setup, const std::vector<int>& index, const Progress& progress,
                  Skeleton& sk);
  void find_bulge_gates();

  const FittedRig* fitted_;
  TreeKind kind_;
  std::shared_ptr<const implicit::Program> program_;
  std::shared_ptr<const implicit::Pose> rest_, pose_;
  std::vector<int> joint_of_leaf_id_;  ///< leaf id (compressed bone) -> rig joint
  std::vector<std::string> joint_ops_;
  std::vector<BulgeGate> gates_;
  std::vector<MuscleLeaf> muscles_;
  std::vector<PieceLeaf> pieces_;
  /// Per leaf id: the controller of the joint's grid operator (the bulge preset for other joints).
  std::vector<operators::Controller> leaf_controllers_;
};

}  // namespace isokit::skinning
