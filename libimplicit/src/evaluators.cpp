// SPDX-License-Identifier: MIT
// The evaluators of a program at a pose: the instruction loop (scalar), the sparse evaluation
// (SIMD frame test of every leaf, then the compositions of non-zero operands only), and batches.
#include "isokit/implicit/evaluators.h"

#include <algorithm>
#include <new>
#include <string>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "isokit/core/error.h"

namespace isokit::implicit {

namespace {

/// The lowest / highest set bit of a non-zero leaf mask.
int lowest_bit(LeafMask m) {
  const auto lo = std::uint64_t(m);
  return lo ? tape_detail::lowest_bit(lo) : 64 + tape_detail::lowest_bit(std::uint64_t(m >> 64));
}
int highest_bit(LeafMask m) {
  const auto hi = std::uint64_t(m >> 64);
  return hi ? 64 + tape_detail::highest_bit(hi) : tape_detail::highest_bit(std::uint64_t(m));
}

void require_fits(const Program& program, const Pose& pose) {
  if (pose.fits(program)) return;
  require(false, "pose", "was made for another program",
          "make the pose from the program it is evaluated with: Pose(program)");
}

/// Bit k set when leaf k's local box contains its local point `q_k = R_k^T (p - t_k)`, written to
/// q (3 rows of `m` floats). `frames`: see Pose::frames. The same operations, in the same order,
/// as `Rigid3f::apply_inverse` and `Box3f::contains` (the same bits).
/// Only the groups of four leaves with a bit in `candidates` are computed (the others' bits are
/// 0 and their rows of q left alone).
LeafMask local_points(const float* frames, std::size_t m, const Vec3f& p, float* q, LeafMask candidates) {
  LeafMask mask = 0;
  const float* R = frames;
  const float* t = frames + 9 * m;
  const float* lo = frames + 12 * m;
  const float* hi = frames + 15 * m;
#if defined(__SSE2__)
  const __m128 px = _mm_set1_ps(p.x), py = _mm_set1_ps(p.y), pz = _mm_set1_ps(p.z);
  for (std::size_t k = 0; k < m; k += 4) {
    if (!((candidates >> k) & 0xF)) continue;
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
    mask |= LeafMask(unsigned(_mm_movemask_ps(in))) << k;
  }
#else
  for (std::size_t k = 0; k < m; ++k) {
    if (!((candidates >> k) & 1)) continue;
    const float dx = p.x - t[k], dy = p.y - t[m + k], dz = p.z - t[2 * m + k];
    bool in = true;
    for (std::size_t c = 0; c < 3; ++c) {
      const float qc = R[c * m + k] * dx + R[(3 + c) * m + k] * dy + R[(6 + c) * m + k] * dz;
      q[c * m + k] = qc;
      in = in & (qc >= lo[c * m + k]) & (qc <= hi[c * m + k]);
    }
    mask |= LeafMask(in) << k;
  }
#endif
  return mask & candidates;  // a computed group's other lanes are not asked for
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// ScalarEvaluator

ScalarEvaluator::ScalarEvaluator(const Program& program, const Pose& pose) : program_(program), pose_(pose) {
  require_fits(program, pose);
  if (program.max_stack() > kLocalStack) heap_.resize(std::size_t(program.max_stack()));
}

FieldSample ScalarEvaluator::eval(const Vec3f& p, NodeDiagnostics* diag, bool prune) {
  // Value stack: left uninitialised (every slot is written before it is read).
  alignas(FieldSample) unsigned char raw[kLocalStack * sizeof(FieldSample)];
  FieldSample* st = heap_.empty() ? reinterpret_cast<FieldSample*>(raw) : heap_.data();
  const std::vector<TapeInstr>& instr = program_.instructions();
  const std::vector<Box3f>& box = pose_.boxes();
  const std::vector<TapeLeaf>& leaves = pose_.leaves();
  const std::vector<operators::ControllerTable>& controllers = pose_.controllers();
  const std::vector<operators::GridOperatorView>& grids = program_.grids();
  int sp = 0;
  const std::size_t n = instr.size();
  std::size_t i = 0;
  while (i < n) {
    const TapeInstr& in = instr[i];
    // Only a subtree's first instruction (always a leaf) is tested: an inner node whose box
    // excludes p was already skipped with the chain that starts at its first leaf.
    if (prune && in.leaf >= 0 && !box[i].contains(p)) {
      std::size_t j = i;
      while (instr[j].chain_parent >= 0 && !box[std::size_t(instr[j].chain_parent)].contains(p))
        j = std::size_t(instr[j].chain_parent);
      if (diag)
        for (std::size_t k = i; k <= j; ++k) diag[k] = NodeDiagnostics{};
      new (&st[sp++]) FieldSample{};
      i = j + 1;
      continue;
    }
    if (in.leaf >= 0) {
      const TapeLeaf& l = leaves[std::size_t(in.leaf)];
      const Vec3f q = l.local_to_world.apply_inverse(p);
      FieldSample s = l.grid.valid() ? eval_grid(l.grid, q) : program_.field(std::size_t(l.field)).eval(q);
      s.gradient = l.local_to_world.rotate(s.gradient);
      new (&st[sp++]) FieldSample(s);
      if (diag) diag[i] = NodeDiagnostics{0.f, 0.f, s.value, 1, 0, 0};
    } else {
      const FieldSample& b = st[sp - 1];
      FieldSample& a = st[sp - 2];
      --sp;
      if (diag || (a.value != 0.f && b.value != 0.f)) {
        const std::size_t o = std::size_t(in.op);
        a = compose_node(in.kind, controllers[o], grids[o], a, b, diag ? diag + i : nullptr);
      } else if (a.value == 0.f) {
        // compose_node's pass-through rule, inlined (the common case); two zeros give 0.
        a = b.value == 0.f ? FieldSample{} : b;
      }
    }
    ++i;
  }
  return st[0];
}

// ---------------------------------------------------------------------------------------------
// SparseEvaluator

SparseEvaluator::SparseEvaluator(const Program& program, const Pose& pose) : program_(program), pose_(pose) {
  // Made once per point by ProgramField::eval: no message is built unless it fails.
  if (!program.sparse())
    require(false, "program", "is not evaluated sparsely (2 to 127 leaves and a root node are needed)",
            "use a ScalarEvaluator or a BatchEvaluator");
  require_fits(program, pose);
}

FieldSample SparseEvaluator::eval(const Vec3f& p) const {
  alignas(FieldSample) unsigned char raw[Program::kSparseMaxLeaves * sizeof(FieldSample)];
  FieldSample* samples = reinterpret_cast<FieldSample*>(raw);  // only non-zero leaves are read
  const LeafMask leaves = eval_leaves(p, samples);
  if (!leaves) return {};
  if (!(leaves & (leaves - 1))) return samples[lowest_bit(leaves)];  // passed through to the root
  return compose(leaves, samples);
}

LeafMask SparseEvaluator::eval_leaves(const Vec3f& p, FieldSample* samples) const {
  return eval_slots(p, samples, ~LeafMask(0));
}

LeafMask SparseEvaluator::eval_slots(const Vec3f& p, FieldSample* samples, LeafMask candidates) const {
  alignas(16) float q[3 * ((Program::kSparseMaxLeaves + 3) / 4 * 4)];  // 3 rows of distinct_stride
  return eval_located(locate(p, q, candidates), q, samples);
}

LeafMask SparseEvaluator::locate(const Vec3f& p, float* q, LeafMask candidates) const {
  // The point in every candidate slot's frame (the distinct leaves: Pose::distinct_frames), and
  // which slots' local boxes contain it.
  return local_points(pose_.distinct_frames().data(), pose_.distinct_stride(), p, q, candidates);
}

LeafMask SparseEvaluator::eval_located(LeafMask inside, const float* q, FieldSample* samples) const {
  // `inside`: slots. Only the leaves containing the point are evaluated, and only the ones with
  // a non-zero value are kept (a leaf with value 0 is passed over by every node above it,
  // whatever its gradient, as by compose_node). A non-zero sample is copied to the leaves that
  // repeat its leaf (Pose::leaf_copies). Returns leaves.
  const std::size_t d = pose_.distinct_stride();
  const std::vector<TapeLeaf>& leaves = pose_.leaves();
  const std::int32_t* slot_leaf = pose_.distinct_leaf().data();
  const std::uint64_t* copies = pose_.leaf_copies().data();
  LeafMask nonzero = 0;
  while (inside) {
    const int slot = lowest_bit(inside);
    inside &= inside - 1;
    const auto k = std::size_t(slot_leaf[slot]);
    const TapeLeaf& l = leaves[k];
    const Vec3f local{q[std::size_t(slot)], q[d + std::size_t(slot)], q[2 * d + std::size_t(slot)]};
    FieldSample s;
    if (!l.grid.valid())
      s = program_.field(std::size_t(l.field)).eval(local);
    else if (!eval_grid_inside_occupied(l.grid, local, s))
      continue;  // an empty brick: its value is 0 there
    s.gradient = l.local_to_world.rotate(s.gradient);
    if (s.value == 0.f) continue;
    samples[k] = s;
    LeafMask same = LeafMask(1) << k | LeafMask(copies[2 * k]) | LeafMask(copies[2 * k + 1]) << 64;
    nonzero |= same;
    for (same &= same - 1; same; same &= same - 1) samples[lowest_bit(same)] = s;
  }
  return nonzero;
}

FieldSample SparseEvaluator::compose(LeafMask leaves, const FieldSample* samples) const {
  // `leaves` has two bits or more. The smallest subtree holding them all is rooted at the lowest
  // common ancestor of the leftmost and the rightmost one: its first child holds the leftmost
  // leaf, its second child the rightmost, so both operands are compositions of non-zero leaves.
  // Every node between passes its one non-zero operand through unchanged (compose_node's rule).
  const int a = lowest_bit(leaves), b = highest_bit(leaves);
  const std::size_t count = pose_.leaves().size();
  const TapeSparseNode& node =
      program_.sparse_nodes()[program_.lca()[std::size_t(a) * count + std::size_t(b)]];
  if (node.kind == OpKind::Max)
    return compose_max(leaves, samples, program_.lca()[std::size_t(a) * count + std::size_t(b)]);
  const LeafMask first = leaves & ((LeafMask(1) << node.mid) - 1), second = leaves & ~first;
  const FieldSample fa = (first & (first - 1)) ? compose(first, samples) : samples[a];
  const FieldSample fb = (second & (second - 1)) ? compose(second, samples) : samples[b];
  const std::size_t o = std::size_t(node.op);
  return compose_node(node.kind, pose_.controllers()[o], program_.grids()[o], fa, fb, nullptr);
}

namespace {

/// An operand of a run of max nodes: its leaves and an upper bound of its value.
struct MaxOperand {
  LeafMask leaves;
  float bound;
};

}  // namespace

FieldSample SparseEvaluator::compose_max(LeafMask leaves, const FieldSample* samples,
                                         std::size_t node) const {
  // The operands of the run of max nodes below `node` (Program::max_operands), left to right,
  // that hold some of `leaves`; the result is the leftmost non-zero operand of the largest value
  // (max keeps its first operand on a tie, and every node passes a zero operand over), else 0.
  // An operand's upper bound: a single leaf's value; a grid operator over two leaves, both
  // present: its cell's bound (Program::grid_bounds); else none.
  MaxOperand operands[Program::kSparseMaxLeaves + 1];
  int count = 0;
  const std::vector<MaxRunOperand>& run = program_.max_operands();
  const std::int32_t begin = program_.max_run_begin()[node], end = program_.max_run_begin()[node + 1];
  for (std::int32_t r = begin; r < end; ++r) {
    const MaxRunOperand& o = run[std::size_t(r)];
    const LeafMask m = leaves & (LeafMask(o.leaves[0]) | LeafMask(o.leaves[1]) << 64);
    if (!m) continue;
    float bound = INFINITY;
    if (o.grid_pair_op >= 0 && (m & (m - 1))) {
      const operators::GridOperatorView& g = program_.grids()[std::size_t(o.grid_pair_op)];
      int i1 = 0, i2 = 0;
      float t = 0.f;
      g.locate(samples[o.first_leaf].value, i1, t);
      g.locate(samples[o.first_leaf + 1].value, i2, t);
      bound = program_.grid_bounds()[std::size_t(o.grid_pair_op)]
                                    [std::size_t(i1) * std::size_t(g.nf - 1) + std::size_t(i2)];
    }
    operands[count++] = MaxOperand{m, bound};
  }
  // Single leaves first (their values are known): the best of them. Then the compositions, in
  // decreasing order of bound (an insertion sort: a run has a few dozen operands at most).
  FieldSample best;
  int best_index = -1;
  auto offer = [&](const FieldSample& s, int index) {
    if (s.value == 0.f) return;  // passed over by the max nodes above it (compose_node's rule)
    if (best_index < 0 || s.value > best.value || (s.value == best.value && index < best_index)) {
      best = s;
      best_index = index;
    }
  };
  int order[Program::kSparseMaxLeaves + 1];
  int composed = 0;
  for (int i = 0; i < count; ++i) {
    const LeafMask m = operands[i].leaves;
    if (!(m & (m - 1))) {
      offer(samples[lowest_bit(m)], i);
      continue;
    }
    int j = composed++;
    for (; j > 0 && operands[order[j - 1]].bound < operands[i].bound; --j) order[j] = order[j - 1];
    order[j] = i;
  }
  for (int j = 0; j < composed; ++j) {
    const MaxOperand& o = operands[order[j]];
    if (best_index >= 0 && o.bound < best.value) break;  // neither this one nor any after it wins
    offer(compose(o.leaves, samples), order[j]);
  }
  return best_index < 0 ? FieldSample{} : best;
}

// ---------------------------------------------------------------------------------------------
// BatchEvaluator

BatchEvaluator::BatchEvaluator(const Program& program, const Pose& pose, const BatchOptions& options)
    : program_(program), pose_(pose), options_(options), scalar_(program, pose) {
  if (program.sparse()) samples_.resize(kBlock * (program.leaves().size() + 1));
}

void BatchEvaluator::eval(const Vec3f* points, std::size_t n, FieldSample* out) {
  if (!program_.sparse()) {
    for (std::size_t i = 0; i < n; ++i) out[i] = scalar_.eval(points[i], nullptr, true);
    return;
  }
  for (std::size_t b0 = 0; b0 < n; b0 += kBlock) eval_block(points + b0, std::min(kBlock, n - b0), out + b0);
}

void BatchEvaluator::eval(const Vec3f* points, std::size_t n, float* values, Vec3f* gradients) {
  block_.resize(kBlock);
  for (std::size_t b0 = 0; b0 < n; b0 += kBlock) {
    const std::size_t count = std::min(kBlock, n - b0);
    eval(points + b0, count, block_.data());
    for (std::size_t j = 0; j < count; ++j) {
      values[b0 + j] = block_[j].value;
      gradients[b0 + j] = block_[j].gradient;
    }
  }
}

namespace {

/// The box of the points, NaN coordinates skipped (empty when there is none).
Box3f points_box(const Vec3f* points, std::size_t n) {
  Box3f b;
  b.lo = Vec3f{INFINITY, INFINITY, INFINITY};
  b.hi = Vec3f{-INFINITY, -INFINITY, -INFINITY};
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      const float v = points[i][c];
      b.lo[c] = v < b.lo[c] ? v : b.lo[c];
      b.hi[c] = v > b.hi[c] ? v : b.hi[c];
    }
  return b;
}

}  // namespace

LeafMask BatchEvaluator::block_candidates(const Vec3f* points, std::size_t count) const {
  // Slots (Pose::distinct_leaf) whose world box meets the box of the points.
  const std::size_t d = pose_.distinct_stride();
  if (!options_.cull) return ~LeafMask(0);
  const Box3f b = points_box(points, count);
  const float* boxes = pose_.distinct_boxes().data();
  LeafMask mask = 0;
  for (std::size_t k = 0; k < d; ++k) {
    bool meets = true;
    for (std::size_t c = 0; c < 3; ++c)
      meets = meets & (boxes[c * d + k] <= b.hi[int(c)]) & (boxes[(3 + c) * d + k] >= b.lo[int(c)]);
    mask |= LeafMask(meets) << k;
  }
  return mask;
}

void BatchEvaluator::eval_block(const Vec3f* points, std::size_t count, FieldSample* out) {
  // Three passes: the leaves of every point; the result of every point with at most one
  // non-zero leaf (read without a branch: slot L of a row stays 0); then the compositions of
  // the other points, back to back.
  const SparseEvaluator sparse(program_, pose_);
  const std::size_t L = program_.leaves().size(), row = L + 1;
  LeafMask masks[kBlock];
  std::uint32_t pending[kBlock];
  const LeafMask candidates = block_candidates(points, count);
  for (std::size_t j = 0; j < count; ++j)
    masks[j] = candidates ? sparse.eval_slots(points[j], samples_.data() + j * row, candidates) : 0;
  std::size_t np = 0;
  for (std::size_t j = 0; j < count; ++j) {
    const LeafMask leaves = masks[j];
    out[j] = samples_[j * row + std::size_t(lowest_bit(leaves | (LeafMask(1) << L)))];
    pending[np] = std::uint32_t(j);
    np += (leaves & (leaves - 1)) != 0;
  }
  for (std::size_t i = 0; i < np; ++i) {
    const std::size_t j = pending[i];
    out[j] = sparse.compose(masks[j], samples_.data() + j * row);
  }
}

}  // namespace isokit::implicit
