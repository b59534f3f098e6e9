// SPDX-License-Identifier: MIT
// The composition tree: node operators (with the checks every evaluator relies on), the
// immutable tree value and its reference (recursive) evaluation.
#include "isokit/implicit/tree.h"

#include <cmath>

#include "isokit/core/error.h"
#include "tree_node.h"

namespace isokit::implicit {

NodeOperator NodeOperator::max() {
  return NodeOperator{OpKind::Max, {}, nullptr, "max"};
}
NodeOperator NodeOperator::sum_blend() {
  return NodeOperator{OpKind::SumBlend, {}, nullptr, "sum-blend"};
}
NodeOperator NodeOperator::clean_union() {
  return NodeOperator{OpKind::CleanUnion, {}, nullptr, "clean-union"};
}
NodeOperator NodeOperator::gradient_blend(const operators::Controller& c) {
  return NodeOperator{OpKind::GradientBlend2013, c.table(), nullptr, "gradient-blend-2013/" + c.name()};
}
NodeOperator NodeOperator::grid_operator(std::shared_ptr<const operators::GridOperator> grid,
                                         const operators::Controller& c, std::string name) {
  require(grid != nullptr && grid->nd() >= 1 && grid->nf() >= 2, "grid operator " + name, "is empty",
          "generate it first (liboperators generate_operator)");
  for (double d : {0.0, 0.5, 1.0}) {
    const float g = grid->eval(0.f, 0.f, float(d)).g;
    require(std::abs(g) <= 1e-4f, "grid operator " + name,
            "g(0, 0; " + format_number(d) + ") = " + format_number(g) +
                " is not 0, so nodes would lose compact support",
            "constrain g(f1, 0) = f1 and g(0, f2) = f2");
  }
  // The evaluators pass an operand through where the other one is 0: g(f, 0) = f and g(0, f) = f
  // must hold on the grid (to 1e-3).
  for (double d : {0.0, 0.5, 1.0})
    for (double f : {0.125, 0.25, 0.5, 0.75, 1.0}) {
      const float e1 = grid->eval(float(f), 0.f, float(d)).g - float(f);
      const float e2 = grid->eval(0.f, float(f), float(d)).g - float(f);
      require(std::abs(e1) <= 1e-3f && std::abs(e2) <= 1e-3f, "grid operator " + name,
              "g(f, 0) = f or g(0, f) = f fails at f = " + format_number(f) + ", d = " + format_number(d),
              "constrain g(f1, 0) = f1 and g(0, f2) = f2");
    }
  return NodeOperator{OpKind::Grid, c.table(), std::move(grid), std::move(name)};
}

CompositionTree CompositionTree::leaf(FieldPtr local, const Rigid3f& xf, int id) {
  require(local != nullptr, "composition tree leaf " + std::to_string(id), "has no field",
          "pass a primitive");
  validate_rigid(xf, "composition tree leaf transform");
  auto n = std::make_shared<Node>();
  n->field = std::move(local);
  n->xf = xf;
  n->id = id;
  return CompositionTree(std::move(n));
}

CompositionTree CompositionTree::node(NodeOperator op, CompositionTree a, CompositionTree b, NodeTag tag) {
  require(a.n_ && b.n_, "composition tree node " + op.name, "has an empty operand", "pass two trees");
  require(op.kind != OpKind::Grid || op.grid != nullptr, "composition tree node " + op.name,
          "is a grid operator without a grid", "use NodeOperator::grid_operator");
  auto n = std::make_shared<Node>();
  n->op = std::move(op);
  n->tag = tag;
  n->nodes = 1 + a.n_->nodes + b.n_->nodes;
  n->leaves = a.n_->leaves + b.n_->leaves;
  n->first = std::move(a.n_);
  n->second = std::move(b.n_);
  return CompositionTree(std::move(n));
}

bool CompositionTree::is_leaf() const {
  return n_->field != nullptr;
}
const FieldPtr& CompositionTree::field() const {
  return n_->field;
}
const Rigid3f& CompositionTree::transform() const {
  return n_->xf;
}
int CompositionTree::id() const {
  return n_->id;
}
const NodeOperator& CompositionTree::op() const {
  return n_->op;
}
const NodeTag& CompositionTree::tag() const {
  return n_->tag;
}
std::size_t CompositionTree::node_count() const {
  return n_->nodes;
}
std::size_t CompositionTree::leaf_count() const {
  return n_->leaves;
}

CompositionTree CompositionTree::first() const {
  return CompositionTree(n_->first);
}
CompositionTree CompositionTree::second() const {
  return CompositionTree(n_->second);
}

FieldSample CompositionTree::eval_recursive(const Vec3f& p) const {
  const Node& n = *n_;
  if (n.field) {
    FieldSample s = n.field->eval(n.xf.apply_inverse(p));
    s.gradient = n.xf.rotate(s.gradient);
    return s;
  }
  const FieldSample a = CompositionTree(n.first).eval_recursive(p);
  const FieldSample b = CompositionTree(n.second).eval_recursive(p);
  const operators::GridOperatorView gv = n.op.grid ? n.op.grid->view() : operators::GridOperatorView{};
  return compose_node(n.op.kind, n.op.controller, gv, a, b, nullptr);
}

}  // namespace isokit::implicit
