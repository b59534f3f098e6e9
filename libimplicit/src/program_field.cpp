// SPDX-License-Identifier: MIT
#include "isokit/implicit/program_field.h"

#include <utility>

#include "isokit/core/error.h"
#include "isokit/core/parallel.h"

namespace isokit::implicit {

ProgramField::ProgramField(std::shared_ptr<const Program> program, std::shared_ptr<const Pose> pose)
    : program_(std::move(program)), pose_(std::move(pose)) {
  require(program_ != nullptr && pose_ != nullptr, "ProgramField", "needs a program and a pose",
          "pass both (Pose(program) is the tree's own pose)");
  require(pose_->fits(*program_), "ProgramField pose", "was made for another program",
          "make the pose from the same program: Pose(program)");
}

ProgramField::ProgramField(const CompositionTree& tree, ProgramOptions options)
    : program_(std::make_shared<const Program>(tree, options)) {
  pose_ = std::make_shared<const Pose>(*program_);
}

FieldSample ProgramField::eval(const Vec3f& p) const {
  if (program_->sparse()) return SparseEvaluator(*program_, *pose_).eval(p);
  return ScalarEvaluator(*program_, *pose_).eval(p, nullptr, true);
}

void ProgramField::eval_batch(const Vec3f* points, std::size_t n, FieldSample* out, std::size_t grain) const {
  parallel_for(n, grain, [&](std::size_t begin, std::size_t end) {
    BatchEvaluator(*program_, *pose_).eval(points + begin, end - begin, out + begin);
  });
}

}  // namespace isokit::implicit
