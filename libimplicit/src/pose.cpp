// SPDX-License-Identifier: MIT
// A program's pose: leaf transforms, controller tables, and what follows from them (world
// boxes per instruction, the leaves' frames for the sparse evaluator).
#include "isokit/implicit/pose.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "isokit/core/error.h"

namespace isokit::implicit {

Pose::Pose(const Program& program)
    : leaves_(program.leaves()),
      scales_(program.leaves().size(), Vec3f{1.f, 1.f, 1.f}),
      controllers_(program.controllers()),
      boxes_(program.size()) {
  update(program);
}

namespace {

void validate_scale(const Vec3f& s) {
  for (int c = 0; c < 3; ++c)
    require(std::isfinite(s[c]) && s[c] > 0.f, "pose leaf scale",
            "component " + std::to_string(c) + " is " + format_number(s[c]) + ", not finite and > 0",
            "pass a positive scale per local axis (1 = unchanged)");
}

}  // namespace

// The leaf record of a posed leaf: R S⁻¹ (columns of R divided by the scale) and t.
void Pose::place(TapeLeaf& leaf, std::size_t index, const Rigid3f& xf, const Vec3f& scale) {
  leaf.local_to_world = xf;
  scales_[index] = scale;
  if (scale.x == 1.f && scale.y == 1.f && scale.z == 1.f) return;  // bit for bit the rigid pose
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) leaf.local_to_world.R.m[3 * r + c] /= scale[c];
}

void Pose::require_fits(const Program& program) const {
  if (fits(program)) return;
  require(false, "pose",
          "was made for another program (" + std::to_string(leaves_.size()) + " leaves, " +
              std::to_string(boxes_.size()) + " instructions; the program has " +
              std::to_string(program.leaves().size()) + " and " + std::to_string(program.size()) + ")",
          "make the pose from the program it is used with: Pose(program)");
}

void Pose::set_leaf_transform(const Program& program, std::size_t leaf, const Rigid3f& xf,
                              const Vec3f& scale) {
  require_fits(program);
  require(leaf < leaves_.size(), "pose leaf " + std::to_string(leaf),
          "is out of range (" + std::to_string(leaves_.size()) + " leaves)",
          "use an index into Program::leaves()");
  validate_rigid(xf, "pose leaf transform");
  validate_scale(scale);
  place(leaves_[leaf], leaf, xf, scale);
  update(program);
}

void Pose::set_transform_of(const Program& program, int id, const Rigid3f& xf, const Vec3f& scale) {
  require_fits(program);
  validate_rigid(xf, "pose leaf transform");
  validate_scale(scale);
  bool any = false;
  for (std::size_t k = 0; k < leaves_.size(); ++k)
    if (leaves_[k].id == id) place(leaves_[k], k, xf, scale), any = true;
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
  // World boxes in post-order: a leaf's is its support moved by its transform, a node's the
  // union of its children's.
  const std::vector<TapeInstr>& instr = program.instructions();
  std::vector<std::int32_t> st;
  for (std::size_t i = 0; i < instr.size(); ++i) {
    const TapeInstr& in = instr[i];
    if (in.leaf >= 0) {
      // The support moved by the forward map t + R S x = t + (R S⁻¹) S² x.
      const TapeLeaf& l = leaves_[std::size_t(in.leaf)];
      const Vec3f& s = scales_[std::size_t(in.leaf)];
      Rigid3f forward = l.local_to_world;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) forward.R.m[3 * r + c] *= s[c] * s[c];
      boxes_[i] = transform_box(program.leaf_support(std::size_t(in.leaf)), forward);
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
  if (program.sparse()) update_frames(program), update_copies(program);
}

void Pose::update_copies(const Program& program) {
  const std::size_t L = leaves_.size();
  leaf_copies_.assign(2 * L, 0);
  distinct_[0] = distinct_[1] = 0;
  auto same = [](const Rigid3f& a, const Rigid3f& b) {
    for (int c = 0; c < 9; ++c)
      if (!(a.R.m[c] == b.R.m[c])) return false;
    return a.t.x == b.t.x && a.t.y == b.t.y && a.t.z == b.t.z;
  };
  for (std::size_t k = 0; k < L; ++k) {
    // The first equal leaf is distinct itself (equality is transitive).
    std::size_t first = 0;
    const Field* f = &program.field(std::size_t(leaves_[k].field));
    while (first < k && !(&program.field(std::size_t(leaves_[first].field)) == f &&
                          same(leaves_[first].local_to_world, leaves_[k].local_to_world) &&
                          scales_[first].x == scales_[k].x && scales_[first].y == scales_[k].y &&
                          scales_[first].z == scales_[k].z))
      ++first;
    if (first == k)
      distinct_[k / 64] |= std::uint64_t(1) << (k % 64);
    else
      leaf_copies_[2 * first + k / 64] |= std::uint64_t(1) << (k % 64);
  }
  gather_distinct(program.frame_stride());
}

void Pose::gather_distinct(std::size_t m) {
  const std::size_t L = leaves_.size();
  std::vector<std::int32_t> slots;
  for (std::size_t k = 0; k < L; ++k)
    if ((distinct_[k / 64] >> (k % 64)) & 1u) slots.push_back(std::int32_t(k));
  const std::size_t d = (slots.size() + 3) / 4 * 4;
  slots.resize(d, -1);
  distinct_leaf_ = slots;
  distinct_frames_.assign(18 * d, 0.f);
  distinct_boxes_.assign(6 * d, 0.f);
  for (std::size_t slot = 0; slot < d; ++slot) {
    const std::int32_t k = slots[slot];
    for (std::size_t row = 0; row < 18; ++row)
      distinct_frames_[row * d + slot] = k >= 0 ? frames_[row * m + std::size_t(k)]
                                                : (row < 12   ? 0.f
                                                   : row < 15 ? INFINITY
                                                              : -INFINITY);
    for (std::size_t row = 0; row < 6; ++row)
      distinct_boxes_[row * d + slot] =
          k >= 0 ? leaf_boxes_[row * m + std::size_t(k)] : (row < 3 ? INFINITY : -INFINITY);
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
  // The leaves' world boxes (the instructions' boxes), grown past the rounding of the frame
  // test so that a point outside one is outside the leaf's local box too.
  leaf_boxes_.assign(6 * m, 0.f);
  for (std::size_t k = 0; k < m; ++k)
    for (int c = 0; c < 3; ++c)
      leaf_boxes_[std::size_t(c) * m + k] = INFINITY, leaf_boxes_[std::size_t(3 + c) * m + k] = -INFINITY;
  const std::vector<TapeInstr>& instr = program.instructions();
  for (std::size_t i = 0; i < instr.size(); ++i) {
    if (instr[i].leaf < 0) continue;
    const Box3f& b = boxes_[i];
    if (b.empty()) continue;
    const auto k = std::size_t(instr[i].leaf);
    float reach = 0.f;
    for (int c = 0; c < 3; ++c) reach = std::max({reach, std::fabs(b.lo[c]), std::fabs(b.hi[c])});
    const float grow = 1e-4f * reach;
    for (int c = 0; c < 3; ++c) {
      leaf_boxes_[std::size_t(c) * m + k] = b.lo[c] - grow;
      leaf_boxes_[std::size_t(3 + c) * m + k] = b.hi[c] + grow;
    }
  }
}

TapeSparseLayout sparse_layout(const Program& program, const Pose& pose) {
  require(program.sparse() && program.leaves().size() <= Program::kLayoutMaxLeaves, "program",
          "has no sparse layout (2 to 63 leaves and a root node are needed; it has " +
              std::to_string(program.leaves().size()) + ")",
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
