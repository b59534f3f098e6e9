// SPDX-License-Identifier: MIT
// Compiling a composition tree into a program: the post-order instructions, leaf and operator
// records, node tags, and the sparse evaluator's structure (leaf ranges and lowest common
// ancestors). Nothing here depends on a pose.
#include "isokit/implicit/program.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "isokit/core/error.h"
#include "isokit/implicit/grid_field.h"
#include "tree_node.h"

namespace isokit::implicit {

Program::Program(const CompositionTree& tree, ProgramOptions options) : options_(options) {
  compile(tree);
  grid_owners_.clear();
  grid_owners_.shrink_to_fit();
  build_sparse();
}

void Program::compile(const CompositionTree& tree) {
  using NodeP = const CompositionTree::Node*;
  // Iterative post-order with stack-depth tracking (no recursion limit on deep chains).
  std::vector<std::pair<NodeP, int>> stack{{tree.n_.get(), 0}};
  std::vector<std::int32_t> child_results;
  int depth = 0;
  while (!stack.empty()) {
    auto& [n, state] = stack.back();
    if (n->field) {
      child_results.push_back(std::int32_t(instr_.size()));
      add_leaf(n->field, n->xf, n->id);
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
      child_results.pop_back();  // the second child
      const std::int32_t a = child_results.back();
      child_results.pop_back();
      TapeInstr in;
      in.kind = n->op.kind;
      in.op = add_operator(n->op);
      const std::int32_t self = std::int32_t(instr_.size());
      instr_[std::size_t(a)].chain_parent = self;  // the first child starts this subtree
      child_results.push_back(self);
      instr_.push_back(in);
      tags_.push_back(n->tag);
      --depth;
      stack.pop_back();
    }
    require(stack.size() <= 8192, "composition tree", "is deeper than 4096", "build a balanced tree");
  }
}

void Program::add_leaf(const FieldPtr& field, const Rigid3f& xf, int id) {
  TapeInstr in;
  in.leaf = std::int32_t(leaves_.size());
  fields_.push_back(field);
  TapeLeaf leaf{xf, std::int32_t(fields_.size() - 1), id, {}};
  if (const auto* g = dynamic_cast<const GridField*>(field.get())) leaf.grid = g->view();
  leaves_.push_back(leaf);
  supports_.push_back(field->support());
  instr_.push_back(in);
  tags_.push_back(NodeTag{});
}

namespace {

/// Upper bounds of a grid operator's bicubic interpolant per (f1, f2) cell over every slice
/// (Program::grid_bounds), from its padded samples (decoded, when packed: the bound of what is
/// evaluated). The 2D Catmull-Rom weight of a stencil node
/// is positive on the inner 2 × 2 nodes and the 4 corners, negative on the 8 others, and the
/// negative weights sum to at least -0.28125 (1D: -t (1 - t) / 2 ≥ -1/8, so 2 × 1/8 × 9/8 in
/// 2D); with the weights summing to 1, the interpolant is at most the largest positive-weight
/// sample plus 0.28125 times its excess over the smallest negative-weight one. Blending two
/// slices in d keeps every node between its two samples.
std::vector<float> grid_bound_table(const operators::GridOperatorView& g) {
  const int nf = g.nf, n = nf + 2, cells = nf - 1;
  std::vector<float> out(std::size_t(cells) * std::size_t(cells));
  for (int i1 = 0; i1 < cells; ++i1)
    for (int i2 = 0; i2 < cells; ++i2) {
      float positive = -INFINITY, negative = INFINITY;
      for (int k = 0; k < g.nd; ++k)
        for (int a = 0; a < 4; ++a)
          for (int b = 0; b < 4; ++b) {
            // Padded rows i1 .. i1 + 3 are the stencil rows i1 - 1 .. i1 + 2 of the samples.
            const float v =
                g.packed ? g.unpack(k, i1 + a, i2 + b)
                         : g.padded[(std::size_t(k) * std::size_t(n) + std::size_t(i1 + a)) * std::size_t(n) +
                                    std::size_t(i2 + b)];
            const bool inner_a = a == 1 || a == 2, inner_b = b == 1 || b == 2;
            if (inner_a == inner_b)
              positive = std::max(positive, v);
            else
              negative = std::min(negative, v);
          }
      const float excess = std::max(0.f, positive - negative);
      out[std::size_t(i1) * std::size_t(cells) + std::size_t(i2)] =
          positive + 0.28125f * excess + 1e-4f * (1.f + std::fabs(positive) + std::fabs(negative));
    }
  return out;
}

}  // namespace

std::int32_t Program::add_operator(const NodeOperator& op) {
  const std::int32_t index = std::int32_t(controllers_.size());
  controllers_.push_back(op.controller);
  operators::GridOperatorView gv{};
  const float* bounds = nullptr;
  if (op.grid) {
    // One padded copy per grid operator (edge-free stencils), shared by the nodes that use it and
    // by copies of the program; the same for its bound table. The tree's samples are not kept.
    std::size_t same = 0;
    while (same < grid_owners_.size() && grid_owners_[same] != op.grid.get()) ++same;
    if (same < grid_owners_.size()) {
      gv = grids_[same];
      bounds = grid_bounds_[same];
    } else {
      const operators::GridOperatorView source = op.grid->view();
      auto padded = std::make_shared<std::vector<float>>(source.padded_size());
      source.fill_padded(padded->data());
      gv.nd = source.nd;
      gv.nf = source.nf;
      if (options_.operator_storage == GridStorage::fixed16) {
        auto packed = std::make_shared<std::vector<std::int16_t>>(padded->size());
        auto tiles = std::make_shared<std::vector<float>>(2 * gv.packed_tile_count());
        gv.pack_padded(padded->data(), packed->data(), tiles->data());
        gv.packed = packed->data();
        gv.packed_tiles = tiles->data();
        operator_packed_.push_back(std::move(packed));
        operator_floats_.push_back(std::move(tiles));
      } else {
        gv.padded = padded->data();
        operator_floats_.push_back(std::move(padded));
      }
      auto table = std::make_shared<const std::vector<float>>(grid_bound_table(gv));
      bounds = table->data();
      bound_tables_.push_back(std::move(table));
    }
  }
  grids_.push_back(gv);
  grid_bounds_.push_back(bounds);
  grid_owners_.push_back(op.grid.get());
  return index;
}

void Program::build_sparse() {
  const std::size_t L = leaves_.size();
  sparse_ = L >= 2 && L <= kSparseMaxLeaves;
  if (!sparse_) return;
  // Post-order pass: the leaf range of every node, and the lowest common ancestor of every pair
  // of leaves (the node where the first leaf is under its first child, the second under its
  // second child); each node's children (a sparse node index, or -1 - leaf for a leaf).
  struct Item {
    std::int32_t lo, hi, node;
  };
  std::vector<Item> st;
  std::vector<std::int32_t> first_child, second_child, range_lo, range_hi;
  lca_.assign(L * L, 0);
  for (const TapeInstr& in : instr_) {
    if (in.leaf >= 0) {
      st.push_back({in.leaf, in.leaf + 1, -1 - in.leaf});
      continue;
    }
    const Item b = st.back();
    st.pop_back();
    const Item a = st.back();
    st.pop_back();
    const std::size_t self = sparse_nodes_.size();
    for (std::int32_t i = a.lo; i < a.hi; ++i)
      for (std::int32_t j = b.lo; j < b.hi; ++j)
        lca_[std::size_t(i) * L + std::size_t(j)] = std::uint8_t(self);
    sparse_nodes_.push_back(TapeSparseNode{in.kind, in.op, b.lo});
    first_child.push_back(a.node);
    second_child.push_back(b.node);
    range_lo.push_back(a.lo);
    range_hi.push_back(b.hi);
    st.push_back({a.lo, b.hi, std::int32_t(self)});
  }
  frame_stride_ = (L + 3) / 4 * 4;
  build_max_runs(first_child, second_child, range_lo, range_hi);
}

void Program::build_max_runs(const std::vector<std::int32_t>& first_child,
                             const std::vector<std::int32_t>& second_child,
                             const std::vector<std::int32_t>& range_lo,
                             const std::vector<std::int32_t>& range_hi) {
  // For every max node, its run's operands left to right (a depth-first walk through max
  // children); an operand's leaves are a contiguous range of the post-order.
  const std::size_t count = sparse_nodes_.size();
  max_run_begin_.assign(count + 1, 0);
  auto operand = [&](std::int32_t child) {
    MaxRunOperand o;
    const bool leaf = child < 0;
    o.first_leaf = leaf ? -1 - child : range_lo[std::size_t(child)];
    o.leaf_count = leaf ? 1 : range_hi[std::size_t(child)] - range_lo[std::size_t(child)];
    for (std::int32_t k = o.first_leaf; k < o.first_leaf + o.leaf_count; ++k)
      o.leaves[k / 64] |= std::uint64_t(1) << (k % 64);
    if (!leaf && sparse_nodes_[std::size_t(child)].kind == OpKind::Grid && o.leaf_count == 2 &&
        first_child[std::size_t(child)] < 0 && second_child[std::size_t(child)] < 0)
      o.grid_pair_op = sparse_nodes_[std::size_t(child)].op;
    return o;
  };
  for (std::size_t node = 0; node < count; ++node) {
    max_run_begin_[node] = std::int32_t(max_operands_.size());
    if (sparse_nodes_[node].kind != OpKind::Max) continue;
    // Steps: open a max node (its children, first child next), or emit an operand.
    struct Step {
      std::int32_t child;
      bool open;
    };
    std::vector<Step> steps{{std::int32_t(node), true}};
    while (!steps.empty()) {
      const Step step = steps.back();
      steps.pop_back();
      if (!step.open) {
        max_operands_.push_back(operand(step.child));
        continue;
      }
      const auto m = std::size_t(step.child);
      for (const std::int32_t child : {second_child[m], first_child[m]})
        steps.push_back({child, child >= 0 && sparse_nodes_[std::size_t(child)].kind == OpKind::Max});
    }
  }
  max_run_begin_[count] = std::int32_t(max_operands_.size());
}

Box3f Program::leaf_test_box(std::size_t leaf) const {
  const TapeLeaf& l = leaves_[leaf];
  // A grid leaf's box is the one eval_grid tests; any field is 0 outside its support.
  return l.grid.valid() ? l.grid.box : supports_[leaf];
}

std::size_t Program::memory_bytes() const {
  std::size_t bytes = 0;
  for (std::size_t i = 0; i < fields_.size(); ++i) {
    const auto* g = dynamic_cast<const GridField*>(fields_[i].get());
    bool first = true;
    for (std::size_t j = 0; j < i && first; ++j) first = fields_[j] != fields_[i];
    if (g && first) bytes += g->bytes();
  }
  for (const auto& p : operator_floats_) bytes += p->size() * sizeof(float);
  for (const auto& p : operator_packed_) bytes += p->size() * sizeof(std::int16_t);
  for (const auto& t : bound_tables_) bytes += t->size() * sizeof(float);
  return bytes;
}

std::size_t Program::operator_of(std::size_t instruction) const {
  require(instruction < instr_.size() && instr_[instruction].leaf < 0,
          "program instruction " + std::to_string(instruction),
          "is not an inner node (" + std::to_string(instr_.size()) + " instructions)",
          "use the index of an instruction with leaf < 0");
  return std::size_t(instr_[instruction].op);
}

}  // namespace isokit::implicit
