// SPDX-License-Identifier: MIT
/// \file
/// The composed field of a fitted rig (2013 §4.2 and 2014 §4 trees) posed by skinning matrices:
/// the compiled composition tree and what changes per frame.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "isokit/implicit/tape.h"
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
  /// bulge) are generated once per process and resolution (2014 §4.2).
  SkinField(const FittedRig& fitted, const SkinSetup& setup, TreeKind tree, const Progress& progress = {});

  /// Moves every primitive by the rigid part of its joint's skinning matrix, and (bulge gate,
  /// SkinSetup::bulge_gate) caps each bulge pair's controller by its joint's bend.
  void set_pose(const std::vector<Affine>& skin);
  /// Value + gradient for the tracker. With `contacts`, `contact[k]` is set where a contact node
  /// is active (per-node diagnostics: about 2x slower); without, the contact buffer is left alone.
  track::FieldFunction function(bool contacts = false) const;
  const implicit::Tape& tape() const { return *tape_; }
  TreeKind kind() const { return kind_; }
  /// Per-instruction operator names (for reports).
  std::vector<std::string> joint_operators() const { return joint_ops_; }

 private:
  const FittedRig* fitted_;
  TreeKind kind_;
  std::shared_ptr<implicit::Tape> tape_;
  std::vector<int> joint_of_leaf_id_;
  std::vector<std::string> joint_ops_;
  /// A bulge node gated by the bend between its two primitives' joints.
  struct BulgeGate {
    std::size_t instruction;
    int parent_joint, child_joint;  // skinning-matrix indices
    operators::ControllerTable base;
  };
  std::vector<BulgeGate> gates_;
  operators::Controller bulge_controller_;  ///< the gate's d_b (SkinSetup::bulge_controller)
};

}  // namespace isokit::skinning
