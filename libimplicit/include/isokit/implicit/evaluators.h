// SPDX-License-Identifier: MIT
/// \file
/// Evaluators of a program at a pose (program.h, pose.h): each is made from `(program, pose)`,
/// keeps references to both (they must outlive it) and owns its scratch, so an evaluator is
/// used by one thread at a time — make one per thread or per call (they are cheap to make).
/// All of them give the same bits for the same point.
///
/// - `ScalarEvaluator`: the instruction loop, any program. Pruning: at the first instruction of
///   a subtree, if the point lies outside its world box (`Pose::boxes`), the evaluator pushes 0
///   and jumps past the largest subtree starting there whose box excludes the point (its
///   ancestors along first-child links, `TapeInstr::chain_parent`). Pruned subtrees are exactly
///   0 with a 0 gradient, so pruning changes no result. Optional per-node diagnostics.
/// - `SparseEvaluator`: programs of 2 to 127 leaves (`Program::sparse`). The point is taken into
///   every leaf's frame at once (SSE2 where available) and tested against the leaf's local box
///   (tighter than its world box); only the leaves containing it are evaluated, and only the
///   nodes whose two operands are both non-zero are composed: the lowest common ancestor of the
///   leftmost and rightmost non-zero leaves, recursively in its two subtrees. Every node in
///   between would pass its non-zero operand through unchanged (`compose_node`'s pass-through
///   rule), so the result is the recursive evaluation's bit for bit. Grid operators are read
///   from a copy padded with their ghost nodes (`GridOperatorView::padded`), with the same
///   results. Work skipped, none of it changing a result: a leaf that repeats an earlier one
///   (`Pose::leaf_copies`) takes its sample; a grid leaf is not read where its cell's brick
///   stores only zeros (`grid_cell_occupied`); a run of max nodes composes its operands in
///   decreasing order of an upper bound (a leaf's value, a grid operator's bound table over two
///   leaves: `Program::grid_bounds`) and stops when the next bound is below the best value.
/// - `BatchEvaluator`: many points, serially; sparse programs in blocks of points (the leaves
///   of every point of a block first, then the compositions back to back), others through the
///   instruction loop. For a parallel loop, one batch evaluator per task. A block tests only
///   the leaves whose world box meets the block's box (`BatchOptions::cull`; points in mesh
///   order lie close together). That changes no result: every point gets the bits it gets
///   alone.
///
/// \note Field convention: values in [0, 1], inside > 0.5, gradients inward, compact support.
#pragma once

#include <cstdint>
#include <vector>

#include "isokit/implicit/pose.h"
#include "isokit/implicit/program.h"

namespace isokit::implicit {

class ScalarEvaluator {
 public:
  /// \throw InputError if `pose` was not made for `program`.
  ScalarEvaluator(const Program& program, const Pose& pose);

  /// Value and gradient at `p`. With `diag` (`program.size()` entries, indexed by instruction;
  /// leaves get their value only) and optional pruning (off: every instruction is evaluated;
  /// the same result).
  FieldSample eval(const Vec3f& p, NodeDiagnostics* diag = nullptr, bool prune = true);

 private:
  static constexpr int kLocalStack = 64;  ///< values on the C stack; deeper programs use `heap_`

  const Program& program_;
  const Pose& pose_;
  std::vector<FieldSample> heap_;
};

/// One bit per leaf of a sparse program (bit k: leaf k; Program::kSparseMaxLeaves + 1 bits).
__extension__ typedef unsigned __int128 LeafMask;  // GCC / Clang (64-bit targets)

class SparseEvaluator {
 public:
  /// \throw InputError if the program is not sparse or `pose` was not made for it.
  SparseEvaluator(const Program& program, const Pose& pose);

  FieldSample eval(const Vec3f& p) const;
  /// The leaves that are non-zero at `p` (bit k: leaf k), their samples written to `samples[k]`
  /// (`Program::kSparseMaxLeaves` entries; the others are left alone).
  LeafMask eval_leaves(const Vec3f& p, FieldSample* samples) const;
  /// The same, testing only the distinct leaves' slots (`Pose::distinct_leaf`) in `candidates`:
  /// the caller guarantees `p` lies outside the others' test boxes (e.g. outside their
  /// `Pose::distinct_boxes`).
  LeafMask eval_slots(const Vec3f& p, FieldSample* samples, LeafMask candidates) const;
  /// The root's value from the non-zero leaves `leaves` (two bits or more) and their samples.
  FieldSample compose(LeafMask leaves, const FieldSample* samples) const;

 private:
  /// eval_slots in two steps: `locate` writes `p` in every candidate slot's frame to `q` (3 rows
  /// of `Pose::distinct_stride` floats) and returns the slots whose local box contains it;
  /// `eval_located` evaluates their leaves (not where a grid's brick is empty) and returns the
  /// non-zero leaves, copies included.
  LeafMask locate(const Vec3f& p, float* q, LeafMask candidates) const;
  LeafMask eval_located(LeafMask inside, const float* q, FieldSample* samples) const;
  /// `compose` at max node `node` (an index into `Program::sparse_nodes`): its run of max
  /// nodes' operands, the ones that may win.
  FieldSample compose_max(LeafMask leaves, const FieldSample* samples, std::size_t node) const;

  const Program& program_;
  const Pose& pose_;
};

/// How a batch evaluator does its work (results do not depend on it).
struct BatchOptions {
  /// Per block of 32 consecutive points, test only the leaves whose world box
  /// (`Pose::distinct_boxes`) meets the block's box. Default true (not in the papers; measured in
  /// docs/performance.md, "Field evaluation at memory speed").
  bool cull = true;
};

class BatchEvaluator {
 public:
  /// \throw InputError if `pose` was not made for `program`.
  BatchEvaluator(const Program& program, const Pose& pose, const BatchOptions& options = {});

  /// `out[i]` = the field at `points[i]`, `i < n`.
  void eval(const Vec3f* points, std::size_t n, FieldSample* out);
  /// The same, written as `values[i]` and `gradients[i]`.
  void eval(const Vec3f* points, std::size_t n, float* values, Vec3f* gradients);

 private:
  static constexpr std::size_t kBlock = 32;  ///< points per block (sparse programs)
  void eval_block(const Vec3f* points, std::size_t count, FieldSample* out);
  /// The slots whose world box meets the box of `points` (all without culling).
  LeafMask block_candidates(const Vec3f* points, std::size_t count) const;

  const Program& program_;
  const Pose& pose_;
  BatchOptions options_;
  ScalarEvaluator scalar_;
  std::vector<FieldSample> samples_;  ///< kBlock rows of (leaves + 1) samples
  std::vector<FieldSample> block_;    ///< kBlock results (split outputs)
};

}  // namespace isokit::implicit
