// SPDX-License-Identifier: MIT
/// \file
/// The composition tree (2014 §4.1, after Wyvill et al. 1999): leaves are primitives (any field,
/// in its local frame, placed by a rigid transform), inner nodes a binary operator `g(f1, f2; d)`
/// with a controller `d(α)`, `α` the angle between the operands' gradients. The tree is an
/// immutable value (shared nodes); compile it into a `Program` (program.h), pose it with a
/// `Pose` (pose.h) and evaluate it with an evaluator (evaluators.h) or a `ProgramField`.
///
/// \note Field convention: values in [0, 1], inside > 0.5, gradients inward, compact support.
/// Every operator must satisfy `g(0, 0; d) = 0` so that a node's support is the union of its
/// children's supports (checked for grid operators).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "isokit/implicit/field.h"
#include "isokit/implicit/node_eval.h"
#include "isokit/operators/controller.h"
#include "isokit/operators/grid_operator.h"

namespace isokit::implicit {

/// The operator of an inner node. Kind numbers are fixed (saved files and GPU programs use them).
struct NodeOperator {
  OpKind kind{OpKind::Max};
  operators::ControllerTable controller{};              ///< d(α) (gradient blend and grid only)
  std::shared_ptr<const operators::GridOperator> grid;  ///< OpKind::Grid only
  std::string name{"max"};

  static NodeOperator max();
  static NodeOperator sum_blend();
  static NodeOperator clean_union();
  /// 2013 Appendix A gradient-based blend, blend amount `d = controller(α)`.
  static NodeOperator gradient_blend(const operators::Controller& controller);
  /// A sampled operator (e.g. the 2014 contact or bulge operator) with its controller.
  /// \throw InputError if `grid` is null, empty, or `g(0, 0; d) != 0` (beyond 1e-4).
  static NodeOperator grid_operator(std::shared_ptr<const operators::GridOperator> grid,
                                    const operators::Controller& controller, std::string name);
};

/// What the operator of an inner node does at its joint (fixed numbers). Set by the callers of
/// the skeleton builders through `JointSetup::role`; the evaluation never reads it.
enum class NodeRole : std::int32_t { None = 0, Union = 1, Blend = 2, Contact = 3, Bulge = 4 };

/// The tag of an inner node: which joint of a skeleton it composes (skeleton.h). A node made by
/// hand, or a `max` over the 2013 pairs, has the default tag (no joint). Kept in the compiled
/// program (`Program::tag`), so callers find their nodes without walking the tree.
struct NodeTag {
  std::int32_t joint{-1};   ///< the child bone of the joint: its operands meet across the edge
  std::int32_t parent{-1};  ///< (joint's parent bone, joint); -1: no joint
  NodeRole role{NodeRole::None};
};

class CompositionTree {
 public:
  /// A primitive `local` (its own frame) placed by `local_to_world`; `id` tags the leaf (the
  /// builders use the bone index) so a pose can move all leaves of one bone at once.
  /// \throw InputError if `local` is null or the transform is not rigid.
  static CompositionTree leaf(FieldPtr local, const Rigid3f& local_to_world = {}, int id = -1);
  static CompositionTree node(NodeOperator op, CompositionTree first, CompositionTree second,
                              NodeTag tag = {});

  bool is_leaf() const;
  const FieldPtr& field() const;     ///< leaf only
  const Rigid3f& transform() const;  ///< leaf only
  int id() const;                    ///< leaf only
  const NodeOperator& op() const;    ///< inner node only
  const NodeTag& tag() const;        ///< inner node only
  CompositionTree first() const;     ///< inner node only
  CompositionTree second() const;    ///< inner node only
  std::size_t node_count() const;
  std::size_t leaf_count() const;

  /// Reference evaluation: plain recursion, no pruning (tests compare the evaluators with it).
  FieldSample eval_recursive(const Vec3f& p) const;

 private:
  friend class Program;
  struct Node;
  explicit CompositionTree(std::shared_ptr<const Node> n) : n_(std::move(n)) {}
  std::shared_ptr<const Node> n_;
};

}  // namespace isokit::implicit
