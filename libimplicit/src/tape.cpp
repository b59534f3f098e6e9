// SPDX-License-Identifier: MIT
#include "isokit/implicit/tape.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <new>

#include "isokit/core/error.h"
#include "isokit/implicit/grid_field.h"

namespace isokit::implicit {

// ---------------------------------------------------------------------------------------------
// CompositionTree

struct CompositionTree::Node {
  FieldPtr field;  // leaf
  Rigid3f xf{};
  int id{-1};
  NodeOperator op{};  // inner
  std::shared_ptr<const Node> first, second;
  std::size_t nodes{1}, leaves{1};
};

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
  // The tape passes an operand through where the other one is 0: g(f, 0) = f and g(0, f) = f
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

CompositionTree CompositionTree::node(NodeOperator op, CompositionTree a, CompositionTree b) {
  require(a.n_ && b.n_, "composition tree node " + op.name, "has an empty operand", "pass two trees");
  require(op.kind != OpKind::Grid || op.grid != nullptr, "composition tree node " + op.name,
          "is a grid operator without a grid", "use NodeOperator::grid_operator");
  auto n = std::make_shared<Node>();
  n->op = std::move(op);
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

// ---------------------------------------------------------------------------------------------
// Tape

Tape::Tape(const CompositionTree& tree) {
  using NodeP = const CompositionTree::Node*;
  // Iterative post-order with stack-depth tracking (no recursion limit on deep chains).
  std::vector<std::pair<NodeP, int>> stack{{tree.n_.get(), 0}};
  std::vector<std::int32_t> child_results;
  int depth = 0;
  while (!stack.empty()) {
    auto& [n, state] = stack.back();
    if (n->field) {
      TapeInstr in;
      in.leaf = std::int32_t(leaves_.size());
      fields_.push_back(n->field);
      TapeLeaf leaf{n->xf, std::int32_t(fields_.size() - 1), n->id, {}};
      if (const auto* g = dynamic_cast<const GridField*>(n->field.get())) leaf.grid = g->view();
      leaves_.push_back(leaf);
      child_results.push_back(std::int32_t(instr_.size()));
      instr_.push_back(in);
      ++depth;
      max_stack_ = std::max(max_stack_, depth);
      stack.pop_back();
    } else if (state == 0) {
      state = 1;
      stack.push_back({n->first.get(), 0});
    } else if (state == 1) {
      state = 2;
      stack.push_back({n->second.get(), 0});
    } else {
      const std::int32_t b = child_results.back();
      child_results.pop_back();
      const std::int32_t a = child_results.back();
      child_results.pop_back();
      TapeInstr in;
      in.kind = n->op.kind;
      in.op = std::int32_t(controllers_.size());
      controllers_.push_back(n->op.controller);
      grids_.push_back(n->op.grid ? n->op.grid->view() : operators::GridOperatorView{});
      grid_owners_.push_back(n->op.grid);
      const std::int32_t self = std::int32_t(instr_.size());
      instr_[std::size_t(a)].chain_parent = self;  // the first child starts this subtree
      (void)b;
      child_results.push_back(self);
      instr_.push_back(in);
      --depth;
      stack.pop_back();
    }
    require(stack.size() <= 8192, "composition tree", "is deeper than 4096", "build a balanced tree");
  }
  update_boxes();
}

void Tape::update_boxes() {
  std::vector<std::int32_t> st;
  for (std::size_t i = 0; i < instr_.size(); ++i) {
    TapeInstr& in = instr_[i];
    if (in.leaf >= 0) {
      const TapeLeaf& l = leaves_[std::size_t(in.leaf)];
      in.box = transform_box(fields_[std::size_t(l.field)]->support(), l.local_to_world);
    } else {
      const Box3f b = instr_[std::size_t(st.back())].box;
      st.pop_back();
      const Box3f a = instr_[std::size_t(st.back())].box;
      st.pop_back();
      Box3f u = a;
      if (!b.empty()) {
        u.extend(b.lo);
        u.extend(b.hi);
      }
      in.box = u;
    }
    st.push_back(std::int32_t(i));
  }
}

Box3f Tape::support() const {
  return instr_.back().box;
}

void Tape::set_leaf_transform(std::size_t leaf, const Rigid3f& xf) {
  require(leaf < leaves_.size(), "tape leaf " + std::to_string(leaf),
          "is out of range (" + std::to_string(leaves_.size()) + " leaves)", "use an index from leaves()");
  validate_rigid(xf, "tape leaf transform");
  leaves_[leaf].local_to_world = xf;
  update_boxes();
}

void Tape::set_transform_of(int id, const Rigid3f& xf) {
  validate_rigid(xf, "tape leaf transform");
  bool any = false;
  for (TapeLeaf& l : leaves_)
    if (l.id == id) l.local_to_world = xf, any = true;
  require(any, "tape leaf id " + std::to_string(id), "tags no leaf",
          "use the id given to CompositionTree::leaf");
  update_boxes();
}

FieldSample Tape::eval(const Vec3f& p, NodeDiagnostics* diag, bool prune) const {
  // Value stack: left uninitialised (every slot is written before it is read).
  constexpr int kLocal = 64;
  alignas(FieldSample) unsigned char raw[kLocal * sizeof(FieldSample)];
  std::vector<FieldSample> heap;
  FieldSample* st = reinterpret_cast<FieldSample*>(raw);
  if (max_stack_ > kLocal) {
    heap.resize(std::size_t(max_stack_));
    st = heap.data();
  }
  int sp = 0;
  const std::size_t n = instr_.size();
  std::size_t i = 0;
  while (i < n) {
    const TapeInstr& in = instr_[i];
    // Only a subtree's first instruction (always a leaf) is tested: an inner node whose box
    // excludes p was already skipped with the chain that starts at its first leaf.
    if (prune && in.leaf >= 0 && !in.box.contains(p)) {
      std::size_t j = i;
      while (instr_[j].chain_parent >= 0 && !instr_[std::size_t(instr_[j].chain_parent)].box.contains(p))
        j = std::size_t(instr_[j].chain_parent);
      if (diag)
        for (std::size_t k = i; k <= j; ++k) diag[k] = NodeDiagnostics{};
      new (&st[sp++]) FieldSample{};
      i = j + 1;
      continue;
    }
    if (in.leaf >= 0) {
      const TapeLeaf& l = leaves_[std::size_t(in.leaf)];
      const Vec3f q = l.local_to_world.apply_inverse(p);
      FieldSample s = l.grid.nodes ? eval_grid(l.grid, q) : fields_[std::size_t(l.field)]->eval(q);
      s.gradient = l.local_to_world.rotate(s.gradient);
      new (&st[sp++]) FieldSample(s);
      if (diag) diag[i] = NodeDiagnostics{0.f, 0.f, s.value, 1, 0, 0};
    } else {
      const FieldSample& b = st[sp - 1];
      FieldSample& a = st[sp - 2];
      --sp;
      if (diag || (a.value != 0.f && b.value != 0.f)) {
        const std::size_t o = std::size_t(in.op);
        a = compose_node(in.kind, controllers_[o], grids_[o], a, b, diag ? diag + i : nullptr);
      } else if (a.value == 0.f) {
        // compose_node's pass-through rule, inlined (the common case); two zeros give 0.
        a = b.value == 0.f ? FieldSample{} : b;
      }
    }
    ++i;
  }
  return st[0];
}

}  // namespace isokit::implicit
