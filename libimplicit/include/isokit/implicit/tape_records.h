// SPDX-License-Identifier: MIT
/// \file
/// The plain-data records of a compiled `Program` and its `Pose` that device code reads too (no
/// Eigen, no STL containers: this header compiles under nvcc).
#pragma once

#include <cstddef>
#include <cstdint>

#include "isokit/core/math.h"
#include "isokit/implicit/field_math.h"
#include "isokit/implicit/grid_math.h"
#include "isokit/implicit/node_eval.h"

namespace isokit::implicit {

/// A leaf: which field, where. Grid leaves carry their plain `GridView` and are evaluated
/// inline (`grid.valid()`); other fields go through `Field::eval`.
struct TapeLeaf {
  Rigid3f local_to_world{};
  std::int32_t field{-1};
  std::int32_t id{-1};
  GridView grid{};
};

/// Inner node of the sparse evaluation: operator, and the first leaf under its second child
/// (leaves are numbered in post-order, so each subtree holds a range of them).
struct TapeSparseNode {
  OpKind kind{OpKind::Max};
  std::int32_t op{-1};
  std::int32_t mid{0};
};

/// The sparse evaluator's records as flat arrays (what a device copy needs: the CUDA backend
/// uploads them and re-targets the pointers). From `sparse_layout(program, pose)` (pose.h) the
/// pointers are into the program (structure, grid operators) and the pose (frames, posed leaf
/// records, controllers), valid while both live unchanged.
struct TapeSparseLayout {
  std::size_t leaves{0};
  std::size_t frame_stride{0};       ///< leaves padded to a multiple of 4
  const float* frames{nullptr};      ///< 18 rows of frame_stride: R (9, row-major), t (3), box lo (3), hi (3)
  const std::uint8_t* lca{nullptr};  ///< lca[a * leaves + b], a < b: index into nodes
  const TapeSparseNode* nodes{nullptr};
  std::size_t node_count{0};
  const TapeLeaf* leaf_records{nullptr};
  const operators::ControllerTable* controllers{nullptr};  ///< indexed by TapeSparseNode::op
  const operators::GridOperatorView* grids{nullptr};       ///< indexed by TapeSparseNode::op
  std::size_t operator_count{0};
};

namespace tape_detail {

ISOKIT_HOSTDEV inline int lowest_bit(std::uint64_t m) {
#if defined(__CUDA_ARCH__)
  return __ffsll(static_cast<long long>(m)) - 1;
#elif defined(__GNUC__)
  return __builtin_ctzll(m);
#else
  int i = 0;
  while (!(m & 1)) m >>= 1, ++i;
  return i;
#endif
}
ISOKIT_HOSTDEV inline int highest_bit(std::uint64_t m) {
#if defined(__CUDA_ARCH__)
  return 63 - __clzll(static_cast<long long>(m));
#elif defined(__GNUC__)
  return 63 - __builtin_clzll(m);
#else
  int i = 0;
  while (m >>= 1) ++i;
  return i;
#endif
}

/// `SparseEvaluator::compose` over a layout: `leaves` has two bits or more.
ISOKIT_HOSTDEV inline FieldSample compose(const TapeSparseLayout& t, std::uint64_t leaves,
                                          const FieldSample* s) {
  const int a = lowest_bit(leaves), b = highest_bit(leaves);
  const TapeSparseNode node = t.nodes[t.lca[std::size_t(a) * t.leaves + std::size_t(b)]];
  const std::uint64_t first = leaves & ((std::uint64_t(1) << node.mid) - 1), second = leaves & ~first;
  const FieldSample fa = (first & (first - 1)) ? compose(t, first, s) : s[a];
  const FieldSample fb = (second & (second - 1)) ? compose(t, second, s) : s[b];
  const std::size_t o = std::size_t(node.op);
  return compose_node(node.kind, t.controllers[o], t.grids[o], fa, fb, nullptr);
}

}  // namespace tape_detail

/// The sparse evaluation of a program of grid leaves from its layout, one point: the point in
/// every leaf's frame (the operations and order of the vectorised frame test), the leaves whose
/// local box contains it (trilinear grid), the composition of the non-zero ones. The same bits
/// as `SparseEvaluator::eval` on the host (tested); the CUDA kernel runs it per thread.
ISOKIT_HOSTDEV inline FieldSample eval_sparse_layout(const TapeSparseLayout& t, const Vec3f& p) {
  FieldSample s[63];
  std::uint64_t nonzero = 0;
  const std::size_t m = t.frame_stride;
  const float* R = t.frames;
  const float* tr = t.frames + 9 * m;
  const float* lo = t.frames + 12 * m;
  const float* hi = t.frames + 15 * m;
  for (std::size_t k = 0; k < t.leaves; ++k) {
    const float dx = p.x - tr[k], dy = p.y - tr[m + k], dz = p.z - tr[2 * m + k];
    float q[3];
    bool in = true;
    for (std::size_t c = 0; c < 3; ++c) {
      q[c] = R[c * m + k] * dx + R[(3 + c) * m + k] * dy + R[(6 + c) * m + k] * dz;
      in = in & (q[c] >= lo[c * m + k]) & (q[c] <= hi[c * m + k]);
    }
    if (!in) continue;
    const TapeLeaf& l = t.leaf_records[k];
    FieldSample f = eval_grid_inside_scalar(l.grid, Vec3f{q[0], q[1], q[2]});
    f.gradient = l.local_to_world.rotate(f.gradient);
    s[k] = f;
    nonzero |= std::uint64_t(f.value != 0.f) << k;
  }
  if (!nonzero) return FieldSample{};
  if (!(nonzero & (nonzero - 1))) return s[tape_detail::lowest_bit(nonzero)];
  return tape_detail::compose(t, nonzero, s);
}

}  // namespace isokit::implicit
