// SPDX-License-Identifier: MIT
/// \file
/// What changes per frame in a compiled program (program.h): the leaves' transforms and the
/// inner nodes' controller tables, with what follows from them — every instruction's world
/// support box (for pruning) and the leaves' frames and local boxes in rows (for the sparse
/// evaluator's SIMD test). Nothing is recompiled when a pose changes.
///
/// A pose is a value of one program: made from it (`Pose(program)`: the tree's own transforms
/// and controllers), changed through setters that take the same program, then read by any
/// number of evaluators at once. Do not change a pose while evaluators read it: make another
/// (copies are cheap: no fields, only records), e.g. one per frame, or one per purpose (the
/// skinning's tracker and metrics each have theirs).
///
/// \note Field convention: values in [0, 1], inside > 0.5, gradients inward, compact support.
#pragma once

#include <cstdint>
#include <vector>

#include "isokit/implicit/program.h"

namespace isokit::implicit {

class Pose {
 public:
  /// The pose of `program` with the tree's transforms and controllers.
  explicit Pose(const Program& program);

  /// Moves one leaf (by its position among the leaves, post-order) or every leaf tagged `id`;
  /// the boxes and frames follow. `scale` (> 0 per axis; default 1) stretches the leaf's field
  /// along its local axes before the rigid move: the posed field is `f(S⁻¹ Rᵀ (p − t))` (e.g. a
  /// unit sphere leaf posed as an ellipsoid, a muscle that swells; not in the papers). The leaf
  /// record then holds `R S⁻¹` in place of R (see `leaves()`), which every evaluator — host and
  /// device — already applies as `(R S⁻¹)ᵀ (p − t)` to points and `R S⁻¹ ∇f` to gradients: the
  /// chain rule of the stretched field.
  /// \throw InputError for an out-of-range leaf, an id that tags no leaf, a non-rigid transform,
  /// a scale that is not finite and > 0, or a program other than this pose's (by its sizes).
  void set_leaf_transform(const Program& program, std::size_t leaf, const Rigid3f& local_to_world,
                          const Vec3f& scale = Vec3f{1.f, 1.f, 1.f});
  void set_transform_of(const Program& program, int id, const Rigid3f& local_to_world,
                        const Vec3f& scale = Vec3f{1.f, 1.f, 1.f});

  /// Replaces the controller table of inner instruction `instruction` (e.g. a controller gated
  /// by the joint's bend); a device copy made from this pose before is not updated.
  /// \throw InputError for a leaf or out-of-range instruction, or a value outside [0, 1].
  void set_controller(const Program& program, std::size_t instruction,
                      const operators::ControllerTable& table);
  /// The controller table of inner instruction `instruction`. \throw InputError as set_controller.
  const operators::ControllerTable& controller(const Program& program, std::size_t instruction) const;

  /// True when this pose was made for `program` (same leaf and instruction counts).
  bool fits(const Program& program) const {
    return leaves_.size() == program.leaves().size() && boxes_.size() == program.size();
  }
  /// The program's leaf records with this pose's transforms (`local_to_world.R` is `R S⁻¹` for a
  /// leaf posed with a scale, R otherwise).
  const std::vector<TapeLeaf>& leaves() const { return leaves_; }
  /// Per leaf, the scale it was posed with (1, 1, 1 unless set).
  const std::vector<Vec3f>& scales() const { return scales_; }
  /// Controller tables, indexed by `TapeInstr::op`.
  const std::vector<operators::ControllerTable>& controllers() const { return controllers_; }
  /// World support box of every instruction (a node's box is the union of its children's).
  const std::vector<Box3f>& boxes() const { return boxes_; }
  /// The root's world box: the field is 0 outside.
  Box3f support() const { return boxes_.back(); }
  /// Sparse programs: per leaf, in rows of `frame_stride` floats, R (9 rows, row-major), t (3)
  /// and the local test box lo (3), hi (3); padding leaves have an empty box.
  const std::vector<float>& frames() const { return frames_; }
  /// Sparse programs: leaves that repeat an earlier leaf — the same field with the same
  /// transform and scale (a 2013 tree holds a bone once per pair it is in) — are evaluated once.
  /// `leaf_copies()[2 k]`, `[2 k + 1]`: the low and high words of the mask of the later leaves
  /// that repeat leaf k (0 for a leaf that repeats another); `distinct_leaves()`: the mask, in
  /// the same two words, of the leaves that repeat none.
  const std::vector<std::uint64_t>& leaf_copies() const { return leaf_copies_; }
  const std::uint64_t* distinct_leaves() const { return distinct_; }
  /// Sparse programs: the distinct leaves in slots (ascending leaf order), padded to a multiple
  /// of 4: `distinct_leaf()[slot]` (-1 for padding); their rows of `frames()` gathered into
  /// `distinct_frames()` (18 rows of `distinct_stride()` floats; padding has an empty box); and
  /// their world boxes `distinct_boxes()` (lo 3, hi 3 rows), grown past the frame test's
  /// rounding, so that a point outside one is outside the leaf's local test box (what the batch
  /// evaluator's per-block cull relies on).
  std::size_t distinct_stride() const { return distinct_leaf_.size(); }
  const std::vector<std::int32_t>& distinct_leaf() const { return distinct_leaf_; }
  const std::vector<float>& distinct_frames() const { return distinct_frames_; }
  const std::vector<float>& distinct_boxes() const { return distinct_boxes_; }

 private:
  void require_fits(const Program& program) const;
  void update(const Program& program);
  void update_frames(const Program& program);
  void update_copies(const Program& program);
  void gather_distinct(std::size_t frame_stride);

  void place(TapeLeaf& leaf, std::size_t index, const Rigid3f& xf, const Vec3f& scale);
  std::vector<TapeLeaf> leaves_;
  std::vector<Vec3f> scales_;
  std::vector<operators::ControllerTable> controllers_;
  std::vector<Box3f> boxes_;
  std::vector<float> frames_;
  std::vector<float> leaf_boxes_;  ///< per leaf (frame_stride columns), gathered into distinct_boxes_
  std::vector<std::uint64_t> leaf_copies_;
  std::uint64_t distinct_[2]{0, 0};
  std::vector<std::int32_t> distinct_leaf_;
  std::vector<float> distinct_frames_, distinct_boxes_;
};

/// The sparse evaluator's records of a program at a pose, as flat arrays (what a device copy
/// uploads); the pointers are into `program` and `pose`, valid while both live unchanged.
/// \throw InputError when the program is not sparse or the pose is not the program's.
TapeSparseLayout sparse_layout(const Program& program, const Pose& pose);

}  // namespace isokit::implicit
