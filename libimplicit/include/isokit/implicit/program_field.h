// SPDX-License-Identifier: MIT
/// \file
/// A program at a pose as a `Field` (program.h, pose.h, evaluators.h): for code that takes any
/// field, and for short call sites. `eval` makes an evaluator per call (the sparse one when the
/// program is sparse, else the instruction loop); `eval_batch` one batch evaluator per task.
///
/// \note Field convention: values in [0, 1], inside > 0.5, gradients inward, compact support.
#pragma once

#include <memory>

#include "isokit/implicit/evaluators.h"
#include "isokit/implicit/field.h"

namespace isokit::implicit {

class ProgramField final : public Field {
 public:
  /// \throw InputError if either is null or `pose` was not made for `program`.
  ProgramField(std::shared_ptr<const Program> program, std::shared_ptr<const Pose> pose);
  /// Compiles `tree` (with `options`) and poses it with the tree's own transforms and controllers.
  explicit ProgramField(const CompositionTree& tree, ProgramOptions options = {});

  FieldSample eval(const Vec3f& p) const override;
  Box3f support() const override { return pose_->support(); }
  /// The same results as `eval` point by point, without a virtual call per point.
  void eval_batch(const Vec3f* points, std::size_t n, FieldSample* out,
                  std::size_t grain = kDefaultGrain) const override;
  using Field::eval_batch;

  const Program& program() const { return *program_; }
  const Pose& pose() const { return *pose_; }
  const std::shared_ptr<const Program>& shared_program() const { return program_; }
  /// The same program at another pose (nothing is recompiled).
  ProgramField with_pose(std::shared_ptr<const Pose> pose) const {
    return ProgramField(program_, std::move(pose));
  }

 private:
  std::shared_ptr<const Program> program_;
  std::shared_ptr<const Pose> pose_;
};

}  // namespace isokit::implicit
