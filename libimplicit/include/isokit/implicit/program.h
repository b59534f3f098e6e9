// SPDX-License-Identifier: MIT
/// \file
/// A composition tree compiled into an immutable program (libfive's tree / deck split): a flat
/// tape of instructions in post-order, read by a small value-stack machine, with the leaves,
/// the operators and the node tags as plain-data records (the layout GPU kernels read, see
/// tape_records.h). What changes per frame — leaf transforms, controller tables, and the world
/// boxes that follow from them — is a separate `Pose` (pose.h); the evaluators (evaluators.h)
/// read a program and a pose.
///
/// A program is a value: immutable once built, copyable (copies share the fields and the padded
/// grid operators), and safe to share between threads.
///
/// \note Field convention: values in [0, 1], inside > 0.5, gradients inward, compact support.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "isokit/implicit/field.h"
#include "isokit/implicit/grid_field.h"
#include "isokit/implicit/node_eval.h"
#include "isokit/implicit/tape_records.h"
#include "isokit/implicit/tree.h"

namespace isokit::implicit {

/// An operand of a run of max nodes (Program::max_operands): a leaf, or a node of another kind,
/// with its leaves (a range, in post-order) as a two-word mask.
struct MaxRunOperand {
  std::uint64_t leaves[2]{0, 0};  ///< bit k: leaf k (low word leaves 0..63)
  std::int32_t first_leaf{0};
  std::int32_t leaf_count{1};
  /// A grid operator node over two leaves (its value has a bound table: Program::grid_bounds).
  std::int32_t grid_pair_op{-1};  ///< its `TapeSparseNode::op`, else -1
};

/// One instruction (post-order): a leaf, or an inner node combining the two values on top of
/// the stack.
struct TapeInstr {
  std::int32_t leaf{-1};          ///< index into the leaf records, or -1 for an inner node
  OpKind kind{OpKind::Max};       ///< inner nodes
  std::int32_t op{-1};            ///< index into the controller / grid-operator arrays
  std::int32_t chain_parent{-1};  ///< parent, if this instruction is its first child; else -1
};

/// How a program is compiled.
struct ProgramOptions {
  /// How the program stores its grid operators' samples (one padded copy per operator, with the
  /// ghost nodes; GridOperatorView::padded / packed). `fixed16` (not in the papers): 16 bits per
  /// sample in 8 × 8 tiles with their own offset and step (2.1 bytes a sample), each sample within
  /// half its tile's step (the tile's range / 65534) of the float; `float32` (default): the
  /// floats, evaluated bit for bit as the tree's operator (the 2014 paper's 128³ float grids,
  /// §4.2). Either way the program keeps no other copy: the tree's operators are not referenced
  /// after the build.
  GridStorage operator_storage = GridStorage::float32;
};

class Program {
 public:
  /// Most leaves of a sparse program (one bit per leaf in a 128-bit mask, one spare).
  static constexpr std::size_t kSparseMaxLeaves = 127;
  /// Most leaves of a sparse layout (TapeSparseLayout, the CUDA tape: a 64-bit mask, one spare).
  static constexpr std::size_t kLayoutMaxLeaves = 63;

  /// Compiles `tree`. \throw InputError if the tree is deeper than 4096.
  explicit Program(const CompositionTree& tree, ProgramOptions options = {});

  std::size_t size() const { return instr_.size(); }
  const std::vector<TapeInstr>& instructions() const { return instr_; }
  /// Leaf records in post-order, with the tree's transforms (a `Pose` holds the current ones).
  const std::vector<TapeLeaf>& leaves() const { return leaves_; }
  /// The field at `index` (what `TapeLeaf::field` indexes).
  const Field& field(std::size_t index) const { return *fields_[index]; }
  /// The support box of leaf `leaf`'s field, in the leaf's frame.
  const Box3f& leaf_support(std::size_t leaf) const { return supports_[leaf]; }
  /// The box the sparse evaluator tests a leaf's local point against: the grid's box for a grid
  /// leaf (the one `eval_grid` tests), else the field's support.
  Box3f leaf_test_box(std::size_t leaf) const;
  /// Bytes of sampled data the program holds: the leaves' grids (each field once) and the grid
  /// operators (the padded copy and the bound table, each operator once). HRBF and analytic
  /// leaves, a few kilobytes each, are not counted.
  std::size_t memory_bytes() const;
  /// Most values on the stack during an evaluation.
  int max_stack() const { return max_stack_; }

  /// The tag of instruction `instruction` (the default tag for leaves; tree.h).
  const NodeTag& tag(std::size_t instruction) const { return tags_[instruction]; }
  /// The index of inner instruction `instruction` into the operator arrays.
  /// \throw InputError for a leaf or an out-of-range instruction.
  std::size_t operator_of(std::size_t instruction) const;
  /// The tree's controller table of inner instruction `instruction` (a pose may replace it).
  /// \throw InputError as operator_of.
  const operators::ControllerTable& controller(std::size_t instruction) const {
    return controllers_[operator_of(instruction)];
  }
  /// The tree's controller tables and the grid operators (empty views for other kinds), indexed
  /// by `TapeInstr::op`. A grid operator's view reads the program's padded copy (`padded`, or
  /// `packed` with fixed16 storage); its `data` is null.
  const std::vector<operators::ControllerTable>& controllers() const { return controllers_; }
  const std::vector<operators::GridOperatorView>& grids() const { return grids_; }

  /// True when the sparse evaluator runs it (2 to kSparseMaxLeaves leaves; evaluators.h).
  bool sparse() const { return sparse_; }
  /// Sparse programs: the leaf count padded to a multiple of 4 (the SIMD frame test's rows).
  std::size_t frame_stride() const { return frame_stride_; }
  /// Sparse programs: `lca()[a * leaves + b]`, a < b: the smallest node (index into
  /// `sparse_nodes()`) above leaves a and b.
  const std::vector<std::uint8_t>& lca() const { return lca_; }
  const std::vector<TapeSparseNode>& sparse_nodes() const { return sparse_nodes_; }
  /// Per operator (indexed by `TapeInstr::op`), for grid operators: an upper bound of the
  /// operator's value over each cell of its (f1, f2) grid, whatever `d` —
  /// `bounds[i1 * (nf - 1) + i2]` for the cell `GridOperatorView::locate` gives; null for other
  /// kinds. The bicubic interpolant stays below the cell's largest sample of positive weight plus
  /// 0.28125 (the Catmull-Rom weights' negative mass in 2D) times its excess over the smallest
  /// sample of negative weight, plus a margin for the float rounding. The sparse evaluator skips operands of
  /// a max that cannot win with it.
  const std::vector<const float*>& grid_bounds() const { return grid_bounds_; }
  /// Sparse programs: for each sparse node that is a max, the operands of the run of max nodes
  /// below it (reached through max children), left to right: `max_operands()[i]` for i in
  /// `[max_run_begin()[node], max_run_begin()[node + 1])`; an empty range for other nodes.
  const std::vector<MaxRunOperand>& max_operands() const { return max_operands_; }
  const std::vector<std::int32_t>& max_run_begin() const { return max_run_begin_; }

 private:
  void compile(const CompositionTree& tree);
  void add_leaf(const FieldPtr& field, const Rigid3f& xf, int id);
  std::int32_t add_operator(const NodeOperator& op);
  void build_sparse();

  std::vector<TapeInstr> instr_;
  std::vector<NodeTag> tags_;
  std::vector<TapeLeaf> leaves_;
  std::vector<Box3f> supports_;
  std::vector<FieldPtr> fields_;
  std::vector<operators::ControllerTable> controllers_;
  std::vector<operators::GridOperatorView> grids_;
  /// The tree's operator of each grid view while compiling (identity only; cleared after).
  std::vector<const operators::GridOperator*> grid_owners_;
  /// The grid operators' copies: GridOperatorView::padded (float32), or ::packed with its
  /// ::packed_tiles (fixed16).
  std::vector<std::shared_ptr<const std::vector<float>>> operator_floats_;
  std::vector<std::shared_ptr<const std::vector<std::int16_t>>> operator_packed_;
  ProgramOptions options_;
  std::vector<std::shared_ptr<const std::vector<float>>> bound_tables_;  ///< grid_bounds() storage
  std::vector<const float*> grid_bounds_;
  int max_stack_{0};
  bool sparse_{false};
  std::size_t frame_stride_{0};
  std::vector<std::uint8_t> lca_;
  std::vector<TapeSparseNode> sparse_nodes_;
  std::vector<MaxRunOperand> max_operands_;
  std::vector<std::int32_t> max_run_begin_;
  void build_max_runs(const std::vector<std::int32_t>& first_child,
                      const std::vector<std::int32_t>& second_child,
                      const std::vector<std::int32_t>& range_lo, const std::vector<std::int32_t>& range_hi);
};

}  // namespace isokit::implicit
