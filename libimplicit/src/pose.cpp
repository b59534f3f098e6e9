// SPDX-License-Identifier: MIT
// A program's pose: leaf transforms, controller tables, and what follows from them (world
// boxes per instruction, the leaves' frames for the sparse evaluator).
#include "isokit/implicit/pose.h"

#include <cmath>
#include <string>

#include "isokit/core/error.h"

namespace isokit::implicit {

Pose::Pose(const Program& program)
    : leaves_(program.leaves()), controllers_(program.controllers()), boxes_(program.size()) {
  update(program);
}

void Pose::require_fits(const Program& program) const {
  if (fits(program)) return;
  require(false, "pose",
          "was made for another program (" + std::to_string(leaves_.size()) + " leaves, " +
              std::to_string(boxes_.size()) + " instructions; the program has " +
              std::to_string(program.leaves().size()) + " and " + std::to_string(program.size()) + ")",
          "make the pose from the program it is used with: Pose(program)");
}

void Pose::set_leaf_transform(const Program& program, std::size_t leaf, const Rigid3f& xf) {
  require_fits(program);
  require(leaf < leaves_.size(), "pose leaf " + std::to_string(leaf),
          "is out of range (" + std::to_string(leaves_.size()) + " leaves)",
          "use an index into Program::leaves()");
  validate_rigid(xf, "pose leaf transform");
  leaves_[leaf].local_to_world = xf;
  update(program);
}

void Pose::set_transform_of(const Program& program, int id, const Rigid3f& xf) {
  require_fits(program);
  validate_rigid(xf, "pose leaf transform");
  bool any = false;
  for (TapeLeaf& l : leaves_)
    if (l.id == id) l.local_to_world = xf, any = true;
  require(any, "pose leaf id " + std::to_string(id), "tags no leaf",
          "use the id given to CompositionTree::leaf");
  update(program);
}

const operators::ControllerTable& Pose::controller(const Program& program, std::size_t instruction) const {
  require_fits(program);
  return controllers_[program.operator_of(instruction)];
}

void Pose::set_controller(const Program& program, std::size_t instruction,
                          const operators::ControllerTable& table) {
  require_fits(program);
  const std::size_t op = program.operator_of(instruction);
  for (float v : table.values)
    require(v >= 0.f && v <= 1.f, "pose controller for instruction " + std::to_string(instruction),
            "has a value outside [0, 1] (or NaN)", "pass d(α) values in [0, 1]");
  controllers_[op] = table;
}

void Pose::update(const Program& program) {
  if (program.sparse()) update_frames(program);
  // World boxes in post-order: a leaf's is its support moved by its transform, a node's the
  // union of its children's.
  const std::vector<TapeInstr>& instr = program.instructions();
  std::vector<std::int32_t> st;
  for (std::size_t i = 0; i < instr.size(); ++i) {
    const TapeInstr& in = instr[i];
    if (in.leaf >= 0) {
      const TapeLeaf& l = leaves_[std::size_t(in.leaf)];
      boxes_[i] = transform_box(program.leaf_support(std::size_t(in.leaf)), l.local_to_world);
    } else {
      const Box3f b = boxes_[std::size_t(st.back())];
      st.pop_back();
      const Box3f a = boxes_[std::size_t(st.back())];
      st.pop_back();
      Box3f u = a;
      if (!b.empty()) {
        u.extend(b.lo);
        u.extend(b.hi);
      }
      boxes_[i] = u;
    }
    st.push_back(std::int32_t(i));
  }
}

void Pose::update_frames(const Program& program) {
  // The leaves' frames and local boxes, one row per coordinate (see frames()).
  const std::size_t m = program.frame_stride();
  frames_.assign(18 * m, 0.f);
  for (std::size_t k = 0; k < m; ++k) {
    Box3f box;  // padding: empty
    box.lo = Vec3f{INFINITY, INFINITY, INFINITY};
    box.hi = Vec3f{-INFINITY, -INFINITY, -INFINITY};
    if (k < leaves_.size()) {
      const TapeLeaf& l = leaves_[k];
      for (std::size_t c = 0; c < 9; ++c) frames_[c * m + k] = l.local_to_world.R.m[c];
      for (int c = 0; c < 3; ++c) frames_[std::size_t(9 + c) * m + k] = l.local_to_world.t[c];
      box = program.leaf_test_box(k);
    }
    for (int c = 0; c < 3; ++c) {
      frames_[std::size_t(12 + c) * m + k] = box.lo[c];
      frames_[std::size_t(15 + c) * m + k] = box.hi[c];
    }
  }
}

TapeSparseLayout sparse_layout(const Program& program, const Pose& pose) {
  require(program.sparse(), "program",
          "is not evaluated sparsely (2 to 63 leaves and a root node are needed)",
          "compose between 2 and 63 primitives");
  require(pose.fits(program), "pose", "was made for another program",
          "make the pose from the program it is used with: Pose(program)");
  TapeSparseLayout l;
  l.leaves = program.leaves().size();
  l.frame_stride = program.frame_stride();
  l.frames = pose.frames().data();
  l.lca = program.lca().data();
  l.nodes = program.sparse_nodes().data();
  l.node_count = program.sparse_nodes().size();
  l.leaf_records = pose.leaves().data();
  l.controllers = pose.controllers().data();
  l.grids = program.grids().data();
  l.operator_count = program.grids().size();
  return l;
}

}  // namespace isokit::implicit
