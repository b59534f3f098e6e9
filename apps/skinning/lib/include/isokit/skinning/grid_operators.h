// SPDX-License-Identifier: MIT
/// \file
/// The grid operators of a skin's contact and bulge joints (2014 §4.2): the built-in presets, or
/// operators designed by the user as spec files (setup keys `operators.contact_spec`,
/// `operators.bulge_spec`, `joints.NAME.spec`; setup.h). A grid is generated once per process
/// and kept in the operator disk cache (operators/cache.h, `default_operator_cache_dir()`), and
/// checked (operators::check_operator) before use.
#pragma once

#include <memory>
#include <string>

#include "isokit/operators/controller.h"
#include "isokit/operators/grid_operator.h"
#include "isokit/operators/spec.h"
#include "isokit/skinning/fitted_rig.h"
#include "isokit/skinning/setup.h"

namespace isokit::skinning {

/// A contact or bulge joint's operator, ready for the composition tree.
struct JointGridOperator {
  std::shared_ptr<const operators::GridOperator> grid;
  /// The spec file's own controller (OperatorSpec::make_controller), or for a preset the setup's
  /// `operators.contact_controller` / `bulge_controller`.
  operators::Controller controller;
  std::string description;  ///< describe_joint_operator's text
};

/// The spec a contact (`op` kContact) or bulge (kBulge) grid is generated from: `file`'s spec, or
/// the preset when `file` is null, with the setup's `operators.resolution` and `slices`.
operators::OperatorSpec grid_spec(const SkinSetup& setup, const SpecFile* file, JointOperator op);

/// What `joint`'s operator `op` (resolved: SkinSetup::operator_for) is, without generating
/// anything: "union", "blend", "contact (preset)", "bulge (spec PATH, hash HEX)" (HEX: the
/// operator cache key, operators::operator_cache_key). \throw InputError as SkinSetup::spec_for.
std::string describe_joint_operator(const SkinSetup& setup, const std::string& joint, JointOperator op);

/// The grid and controller of `joint`'s contact or bulge operator: from this process's memory,
/// else the disk cache, else generated (and cached). Progress: "operator NAME" (counts of
/// slices) while generating, "operator NAME: cache hit PATH" when loaded, and
/// "operator NAME: warning: ..." for a cache problem (never fatal). A cached grid that fails the
/// check is regenerated once.
/// \throw InputError when the grid fails a check: one line naming the spec file (or preset), the
/// slice, the failed check, its value and the fix (operators::CheckFailure::message).
JointGridOperator joint_grid_operator(const SkinSetup& setup, const std::string& joint, JointOperator op,
                                      const Progress& progress);

}  // namespace isokit::skinning
