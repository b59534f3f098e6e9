// SPDX-License-Identifier: MIT
#include "isokit/implicit/tape.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <new>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

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
      operators::GridOperatorView gv{};
      if (n->op.grid) {
        // One padded copy per grid operator (edge-free stencils; same results), shared by the
        // nodes that use it and by copies of the tape.
        std::size_t same = 0;
        while (same < grid_owners_.size() && grid_owners_[same] != n->op.grid) ++same;
        if (same < grid_owners_.size()) {
          gv = grids_[same];
        } else {
          gv = n->op.grid->view();
          auto padded = std::make_shared<std::vector<float>>(gv.padded_size());
          gv.fill_padded(padded->data());
          gv.padded = padded->data();
          padded_grids_.push_back(std::move(padded));
        }
      }
      grids_.push_back(gv);
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
  build_sparse();
  update_boxes();
}

void Tape::build_sparse() {
  const std::size_t L = leaves_.size();
  sparse_ = L >= 2 && L <= kSparseMaxLeaves;
  if (!sparse_) return;
  // Post-order pass: the leaf range of every node, and the lowest common ancestor of every pair
  // of leaves (the node where the first leaf is under its first child, the second under its
  // second child).
  struct Item {
    std::int32_t lo, hi;
  };
  std::vector<Item> st;
  lca_.assign(L * L, 0);
  for (const TapeInstr& in : instr_) {
    if (in.leaf >= 0) {
      st.push_back({in.leaf, in.leaf + 1});
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
    sparse_nodes_.push_back(SparseNode{in.kind, in.op, b.lo});
    st.push_back({a.lo, b.hi});
  }
  frame_stride_ = (L + 3) / 4 * 4;
}

void Tape::update_boxes() {
  if (sparse_) {
    // The leaves' frames and local boxes, one row per coordinate (see tape.h).
    const std::size_t m = frame_stride_;
    leaf_frames_.assign(18 * m, 0.f);
    for (std::size_t k = 0; k < m; ++k) {
      Box3f box;  // padding: empty
      box.lo = Vec3f{INFINITY, INFINITY, INFINITY};
      box.hi = Vec3f{-INFINITY, -INFINITY, -INFINITY};
      if (k < leaves_.size()) {
        const TapeLeaf& l = leaves_[k];
        for (std::size_t c = 0; c < 9; ++c) leaf_frames_[c * m + k] = l.local_to_world.R.m[c];
        for (int c = 0; c < 3; ++c) leaf_frames_[std::size_t(9 + c) * m + k] = l.local_to_world.t[c];
        // A grid leaf's box is the one eval_grid tests; any field is 0 outside its support.
        box = l.grid.nodes ? l.grid.box : fields_[std::size_t(l.field)]->support();
      }
      for (int c = 0; c < 3; ++c) {
        leaf_frames_[std::size_t(12 + c) * m + k] = box.lo[c];
        leaf_frames_[std::size_t(15 + c) * m + k] = box.hi[c];
      }
    }
  }
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

const operators::ControllerTable& Tape::controller(std::size_t instruction) const {
  require(instruction < instr_.size() && instr_[instruction].leaf < 0,
          "tape instruction " + std::to_string(instruction),
          "is not an inner node (" + std::to_string(instr_.size()) + " instructions)",
          "use the index of an instruction with leaf < 0");
  return controllers_[std::size_t(instr_[instruction].op)];
}

void Tape::set_controller(std::size_t instruction, const operators::ControllerTable& table) {
  controller(instruction);  // validates the index
  for (float v : table.values)
    require(v >= 0.f && v <= 1.f, "tape controller for instruction " + std::to_string(instruction),
            "has a value outside [0, 1] (or NaN)", "pass d(α) values in [0, 1]");
  controllers_[std::size_t(instr_[instruction].op)] = table;
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

namespace {

using tape_detail::highest_bit;
using tape_detail::lowest_bit;

/// Bit k set when leaf k's local box contains its local point `q_k = R_k^T (p - t_k)`, written to
/// q (3 rows of `m` floats). `frames`: see Tape::leaf_frames_. The same operations, in the same
/// order, as `Rigid3f::apply_inverse` and `Box3f::contains` (the same bits).
std::uint64_t local_points(const float* frames, std::size_t m, const Vec3f& p, float* q) {
  std::uint64_t mask = 0;
  const float* R = frames;
  const float* t = frames + 9 * m;
  const float* lo = frames + 12 * m;
  const float* hi = frames + 15 * m;
#if defined(__SSE2__)
  const __m128 px = _mm_set1_ps(p.x), py = _mm_set1_ps(p.y), pz = _mm_set1_ps(p.z);
  for (std::size_t k = 0; k < m; k += 4) {
    const __m128 dx = _mm_sub_ps(px, _mm_loadu_ps(t + k)), dy = _mm_sub_ps(py, _mm_loadu_ps(t + m + k)),
                 dz = _mm_sub_ps(pz, _mm_loadu_ps(t + 2 * m + k));
    __m128 in = _mm_set1_ps(0.f);
    for (std::size_t c = 0; c < 3; ++c) {
      // q_c = (R[c] dx + R[3 + c] dy) + R[6 + c] dz
      const __m128 qc = _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_loadu_ps(R + c * m + k), dx),
                                              _mm_mul_ps(_mm_loadu_ps(R + (3 + c) * m + k), dy)),
                                   _mm_mul_ps(_mm_loadu_ps(R + (6 + c) * m + k), dz));
      _mm_store_ps(q + c * m + k, qc);
      const __m128 ok = _mm_and_ps(_mm_cmpge_ps(qc, _mm_loadu_ps(lo + c * m + k)),
                                   _mm_cmple_ps(qc, _mm_loadu_ps(hi + c * m + k)));
      in = c == 0 ? ok : _mm_and_ps(in, ok);
    }
    mask |= std::uint64_t(_mm_movemask_ps(in)) << k;
  }
#else
  for (std::size_t k = 0; k < m; ++k) {
    const float dx = p.x - t[k], dy = p.y - t[m + k], dz = p.z - t[2 * m + k];
    bool in = true;
    for (std::size_t c = 0; c < 3; ++c) {
      const float qc = R[c * m + k] * dx + R[(3 + c) * m + k] * dy + R[(6 + c) * m + k] * dz;
      q[c * m + k] = qc;
      in = in & (qc >= lo[c * m + k]) & (qc <= hi[c * m + k]);
    }
    mask |= std::uint64_t(in) << k;
  }
#endif
  return mask;
}

}  // namespace

TapeSparseLayout Tape::sparse_layout() const {
  require(sparse_, "tape", "is not evaluated sparsely (2 to 63 leaves and a root node are needed)",
          "compose between 2 and 63 primitives");
  TapeSparseLayout l;
  l.leaves = leaves_.size();
  l.frame_stride = frame_stride_;
  l.frames = leaf_frames_.data();
  l.lca = lca_.data();
  l.nodes = sparse_nodes_.data();
  l.node_count = sparse_nodes_.size();
  l.leaf_records = leaves_.data();
  l.controllers = controllers_.data();
  l.grids = grids_.data();
  l.operator_count = grids_.size();
  return l;
}

FieldSample Tape::eval(const Vec3f& p) const {
  return sparse_ ? eval_sparse(p) : eval(p, nullptr, true);
}

void Tape::eval_batch(const Vec3f* points, std::size_t n, FieldSample* out, std::size_t grain) const {
  parallel_for(n, grain, [&](std::size_t begin, std::size_t end) {
    if (!sparse_) {
      for (std::size_t i = begin; i < end; ++i) out[i] = eval(points[i], nullptr, true);
      return;
    }
    // Blocks of points, in three passes: the leaves of every point; the result of every point
    // with at most one non-zero leaf (read without a branch: slot L of a row stays 0); then the
    // compositions of the other points, back to back.
    constexpr std::size_t kBlock = 32;
    const std::size_t L = leaves_.size(), row = L + 1;
    std::vector<FieldSample> samples(kBlock * row);
    std::uint64_t masks[kBlock];
    std::uint32_t pending[kBlock];
    for (std::size_t b0 = begin; b0 < end; b0 += kBlock) {
      const std::size_t count = std::min(kBlock, end - b0);
      for (std::size_t j = 0; j < count; ++j)
        masks[j] = eval_leaves(points[b0 + j], samples.data() + j * row);
      std::size_t np = 0;
      for (std::size_t j = 0; j < count; ++j) {
        const std::uint64_t leaves = masks[j];
        out[b0 + j] = samples[j * row + std::size_t(lowest_bit(leaves | (std::uint64_t(1) << L)))];
        pending[np] = std::uint32_t(j);
        np += (leaves & (leaves - 1)) != 0;
      }
      for (std::size_t i = 0; i < np; ++i) {
        const std::size_t j = pending[i];
        out[b0 + j] = compose_sparse(masks[j], samples.data() + j * row);
      }
    }
  });
}

std::uint64_t Tape::eval_leaves(const Vec3f& p, FieldSample* samples) const {
  // The point in every leaf's frame, and which leaves' local boxes contain it; only those are
  // evaluated, and only the ones with a non-zero value are kept (a leaf with value 0 is passed
  // over by every node above it, whatever its gradient, as by compose_node).
  const std::size_t m = frame_stride_;
  alignas(16) float q[3 * ((kSparseMaxLeaves + 3) / 4 * 4)];  // 3 rows of frame_stride_
  std::uint64_t pending = local_points(leaf_frames_.data(), m, p, q), nonzero = 0;
  while (pending) {
    const int k = lowest_bit(pending);
    pending &= pending - 1;
    const TapeLeaf& l = leaves_[std::size_t(k)];
    const Vec3f local{q[std::size_t(k)], q[m + std::size_t(k)], q[2 * m + std::size_t(k)]};
    FieldSample s =
        l.grid.nodes ? eval_grid_inside(l.grid, local) : fields_[std::size_t(l.field)]->eval(local);
    s.gradient = l.local_to_world.rotate(s.gradient);
    samples[k] = s;  // read only when non-zero (no branch: the outcome is data dependent)
    nonzero |= std::uint64_t(s.value != 0.f) << k;
  }
  return nonzero;
}

FieldSample Tape::eval_sparse(const Vec3f& p) const {
  alignas(FieldSample) unsigned char raw[kSparseMaxLeaves * sizeof(FieldSample)];
  FieldSample* samples = reinterpret_cast<FieldSample*>(raw);  // only non-zero leaves are read
  const std::uint64_t leaves = eval_leaves(p, samples);
  if (!leaves) return {};
  if (!(leaves & (leaves - 1))) return samples[lowest_bit(leaves)];  // passed through to the root
  return compose_sparse(leaves, samples);
}

FieldSample Tape::compose_sparse(std::uint64_t leaves, const FieldSample* samples) const {
  // `leaves` has two bits or more. The smallest subtree holding them all is rooted at the lowest
  // common ancestor of the leftmost and the rightmost one: its first child holds the leftmost
  // leaf, its second child the rightmost, so both operands are compositions of non-zero leaves.
  // Every node between passes its one non-zero operand through unchanged (compose_node's rule).
  const int a = lowest_bit(leaves), b = highest_bit(leaves);
  const SparseNode& node = sparse_nodes_[lca_[std::size_t(a) * leaves_.size() + std::size_t(b)]];
  const std::uint64_t first = leaves & ((std::uint64_t(1) << node.mid) - 1), second = leaves & ~first;
  const FieldSample fa = (first & (first - 1)) ? compose_sparse(first, samples) : samples[a];
  const FieldSample fb = (second & (second - 1)) ? compose_sparse(second, samples) : samples[b];
  const std::size_t o = std::size_t(node.op);
  return compose_node(node.kind, controllers_[o], grids_[o], fa, fb, nullptr);
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
