// SPDX-License-Identifier: MIT
/// \file
/// A composition tree compiled into a flat tape (libfive's tree/deck split): instructions in
/// post-order, read by a small value-stack machine. Leaves are evaluated through their field;
/// inner nodes through `compose_node` (node_eval.h). Records are plain data (the layout GPU
/// kernels will read).
///
/// Pruning: every instruction carries its world support box (a node's box is the union of its
/// children's). At the first instruction of a subtree, if the point lies outside, the evaluator
/// pushes 0 and jumps past the largest subtree starting there whose box excludes the point (its
/// ancestors along first-child links, `chain_parent`). Pruning changes no result: pruned
/// subtrees are exactly 0 with a 0 gradient.
///
/// Sparse evaluation (`eval(p)` and `eval_batch` of trees with at most 63 leaves; the other modes
/// run the instruction loop): the point is taken into every leaf's frame at once and tested
/// against the leaf's local support box (tighter than its world box); only the leaves containing
/// it are evaluated, and only the nodes whose two operands are both non-zero are composed: the
/// lowest common ancestor of the leftmost and rightmost non-zero leaves, recursively in its two
/// subtrees. Every node in between would pass its non-zero operand through unchanged (the
/// pass-through rule of `compose_node`), so the result is the recursive evaluation's bit for
/// bit. Grid operators are read from a copy padded with their ghost nodes (one per operator,
/// shared by copies of the tape; `GridOperatorView::padded`), with the same results.
///
/// \note Field convention: values in [0, 1], inside > 0.5, gradients inward, compact support.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "isokit/implicit/field.h"
#include "isokit/implicit/node_eval.h"
#include "isokit/implicit/tape_records.h"
#include "isokit/implicit/tree.h"

namespace isokit::implicit {

/// One tape instruction (post-order).
struct TapeInstr {
  std::int32_t leaf{-1};          ///< index into the leaf records, or -1 for an inner node
  OpKind kind{OpKind::Max};       ///< inner nodes
  std::int32_t op{-1};            ///< index into the controller / grid-operator arrays
  std::int32_t chain_parent{-1};  ///< parent, if this instruction is its first child; else -1
  Box3f box{};                    ///< world support box
};

class Tape final : public Field {
 public:
  /// \throw InputError if the tree is deeper than 4096.
  explicit Tape(const CompositionTree& tree);

  FieldSample eval(const Vec3f& p) const override;
  /// With `diag` (size() entries, indexed by instruction; leaves get their value only) and
  /// optional pruning (off: every instruction is evaluated; same result).
  FieldSample eval(const Vec3f& p, NodeDiagnostics* diag, bool prune) const;
  Box3f support() const override;
  /// The same results as `eval` point by point, without a virtual call per point.
  void eval_batch(const Vec3f* points, std::size_t n, FieldSample* out,
                  std::size_t grain = kDefaultGrain) const override;
  using Field::eval_batch;

  /// Moves one leaf (by its position among the leaves, post-order) or every leaf tagged `id`;
  /// the boxes are updated, nothing is rebuilt. Not to be called while other threads evaluate.
  /// \throw InputError for an out-of-range leaf or a non-rigid transform.
  void set_leaf_transform(std::size_t leaf, const Rigid3f& local_to_world);
  void set_transform_of(int id, const Rigid3f& local_to_world);

  /// Replaces the controller table of inner instruction `instruction` (e.g. a controller gated by
  /// the pose); nothing is rebuilt, and a device copy of the tape made before is not updated.
  /// Not to be called while other threads evaluate.
  /// \throw InputError for a leaf or out-of-range instruction, or a value outside [0, 1].
  void set_controller(std::size_t instruction, const operators::ControllerTable& table);
  /// The controller table of inner instruction `instruction`. \throw InputError as set_controller.
  const operators::ControllerTable& controller(std::size_t instruction) const;

  std::size_t size() const { return instr_.size(); }
  const std::vector<TapeInstr>& instructions() const { return instr_; }
  const std::vector<TapeLeaf>& leaves() const { return leaves_; }
  int max_stack() const { return max_stack_; }
  /// True when `eval` runs the sparse evaluator (see above).
  bool sparse() const { return sparse_; }
  /// The sparse evaluator's records. \throw InputError when the tape is not sparse.
  TapeSparseLayout sparse_layout() const;

 private:
  void update_boxes();
  void build_sparse();
  FieldSample eval_sparse(const Vec3f& p) const;
  std::uint64_t eval_leaves(const Vec3f& p, FieldSample* samples) const;
  FieldSample compose_sparse(std::uint64_t leaves, const FieldSample* samples) const;

  using SparseNode = TapeSparseNode;
  static constexpr std::size_t kSparseMaxLeaves = 63;
  bool sparse_{false};           ///< at most kSparseMaxLeaves leaves and a root node
  std::size_t frame_stride_{0};  ///< leaf count padded to a multiple of 4
  /// Per leaf, in rows of frame_stride_ floats: R (9 rows, row-major), t (3), and the local
  /// support box lo (3), hi (3). Padding leaves have an empty box.
  std::vector<float> leaf_frames_;
  /// lca_[a * leaves + b], a < b: the smallest node (index into sparse_nodes_) above leaves a, b.
  std::vector<std::uint8_t> lca_;
  std::vector<SparseNode> sparse_nodes_;
  std::vector<TapeInstr> instr_;
  std::vector<TapeLeaf> leaves_;
  std::vector<FieldPtr> fields_;
  std::vector<operators::ControllerTable> controllers_;
  std::vector<operators::GridOperatorView> grids_;
  std::vector<std::shared_ptr<const operators::GridOperator>> grid_owners_;
  std::vector<std::shared_ptr<const std::vector<float>>> padded_grids_;  ///< GridOperatorView::padded
  int max_stack_{0};
};

}  // namespace isokit::implicit
