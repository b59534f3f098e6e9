// SPDX-License-Identifier: MIT
/// \file
/// Trilinear interpolation of a sampled grid of values and gradients (the 2013 paper's 32³
/// textures, §6), shared by the CPU evaluators and the CUDA kernels (plain data, inline,
/// `ISOKIT_HOSTDEV`): a scalar version (the device code) and an SSE2 one on x86 hosts that gives
/// the same bits.
///
/// \note Field convention (ARCHITECTURE.md): values in [0, 1], inside > 0.5, gradients point
/// inward, 0 outside the grid's box.
#pragma once

#include <cstddef>
#include <cstdint>

#include "isokit/core/hostdev.h"
#include "isokit/core/math.h"
#include "isokit/implicit/field_math.h"

// Host builds with SSE2 interpolate grids with the axes and a node's four floats in the lanes of
// a register: the scalar code's operations in the scalar code's order (the same bits).
#if defined(__SSE2__) && !defined(__CUDACC__)
#include <emmintrin.h>
#define ISOKIT_FIELD_MATH_SSE2 1
#endif

namespace isokit::implicit {

/// Read-only view of a sampled grid: `n^3` nodes spanning `box`, node (i, j, k) at
/// `box.lo + (i, j, k) * (box.hi - box.lo) / (n - 1)`, with 4 channels (value, gx, gy, gz) per
/// node at element `4 * ((k * n + j) * n + i)` (x fastest), in one of two storages:
/// - float32: `nodes`, 16 bytes per node;
/// - fixed16: `packed`, 8 bytes per node; a channel's value is its int16 times `scale[channel]`
///   (GridField quantises with one scale for the value and one shared by the three gradient
///   components, so the gradient's error does not depend on its direction).
/// Exactly one of `nodes` and `packed` is set in a valid view. Interpolation is linear, so the
/// fixed16 form interpolates the integers and scales the four sums once.
struct GridView {
  /// Cells per side of an occupancy brick (see `occupied`).
  static constexpr int kBrick = 4;

  const float* nodes{nullptr};
  int n{0};
  Box3f box{};
  const std::int16_t* packed{nullptr};
  float scale[4]{0.f, 0.f, 0.f, 0.f};
  /// Optional: one bit per brick of kBrick³ cells (`bricks` per axis, x fastest), clear when
  /// every node of the brick's cells stores the value 0 — a point in such a cell evaluates to
  /// the value 0 exactly (`grid_cell_occupied`). Null: not known.
  const std::uint64_t* occupied{nullptr};
  int bricks{0};

  ISOKIT_HOSTDEV bool valid() const { return nodes != nullptr || packed != nullptr; }
  /// Bytes of node data: 16 (float32) or 8 (fixed16) per node.
  ISOKIT_HOSTDEV std::size_t node_bytes() const {
    const std::size_t count = std::size_t(n) * std::size_t(n) * std::size_t(n);
    return count * (packed ? 4 * sizeof(std::int16_t) : 4 * sizeof(float));
  }
};

/// False when the cell `eval_grid_inside` reads for `p` (in the box) has only nodes of value 0,
/// so that its value there is exactly 0 (its gradient need not be); true when it may not be or
/// the grid has no occupancy bits. The cell is found with `eval_grid_inside_scalar`'s arithmetic.
ISOKIT_HOSTDEV inline bool grid_cell_occupied(const GridView& g, const Vec3f& p) {
  if (!g.occupied) return true;
  const float q[3] = {p.x, p.y, p.z}, lo[3] = {g.box.lo.x, g.box.lo.y, g.box.lo.z},
              hi[3] = {g.box.hi.x, g.box.hi.y, g.box.hi.z};
  long brick = 0, stride = 1;
  for (int a = 0; a < 3; ++a) {
    const float s = (q[a] - lo[a]) / (hi[a] - lo[a]) * float(g.n - 1);
    int c = int(s);
    c = c > 0 ? c : 0;
    c = c > g.n - 2 ? g.n - 2 : c;
    brick += stride * (c / GridView::kBrick);
    stride *= g.bricks;
  }
  return (g.occupied[brick >> 6] >> (brick & 63)) & 1u;
}

/// `eval_grid` for a point in the box (`g.box.contains(p)`); defined below.
ISOKIT_HOSTDEV inline FieldSample eval_grid_inside(const GridView& g, const Vec3f& p);

/// Trilinear interpolation of the stored value and of the stored gradient. Outside the box the
/// field is 0 with a 0 gradient (the box contains the sampled field's support).
ISOKIT_HOSTDEV inline FieldSample eval_grid(const GridView& g, const Vec3f& p) {
  // One test for the whole box (no early exits per axis: the outcome is data dependent).
  const bool inside = (p.x >= g.box.lo.x) & (p.x <= g.box.hi.x) & (p.y >= g.box.lo.y) & (p.y <= g.box.hi.y) &
                      (p.z >= g.box.lo.z) & (p.z <= g.box.hi.z);
  if (!inside) return {};
  return eval_grid_inside(g, p);
}

/// `eval_grid` for a point in the box (`g.box.contains(p)`), plain scalar code (the device
/// code; `eval_grid_inside` gives the same bits on every host).
ISOKIT_HOSTDEV inline FieldSample eval_grid_inside_scalar(const GridView& g, const Vec3f& p) {
  const int last = g.n - 2;
  const float q[3] = {p.x, p.y, p.z}, lo[3] = {g.box.lo.x, g.box.lo.y, g.box.lo.z},
              hi[3] = {g.box.hi.x, g.box.hi.y, g.box.hi.z};
  float omf[3], f[3];  // 1 - f, f: position in the cell
  int ci[3];
  for (int a = 0; a < 3; ++a) {
    const float s = (q[a] - lo[a]) / (hi[a] - lo[a]) * float(g.n - 1);
    int c = int(s);
    c = c > 0 ? c : 0;
    c = c > last ? last : c;
    ci[a] = c;
    float t = s - float(c);
    t = t > 0.f ? t : 0.f;
    t = t < 1.f ? t : 1.f;
    f[a] = t;
    omf[a] = 1.f - t;
  }
  // Corner 0..7 = x + 2 y + 4 z has the weight (omf or f)_x (omf or f)_y (omf or f)_z, the x-y
  // products shared by both z layers.
  const float wxy[4] = {omf[0] * omf[1], f[0] * omf[1], omf[0] * f[1], f[0] * f[1]};
  const float wz[2] = {omf[2], f[2]};
  const long sy = 4L * g.n, sz = sy * g.n;
  const long first = ci[2] * sz + ci[1] * sy + 4L * ci[0];
  const long offset[8] = {0, 4, sy, sy + 4, sz, sz + 4, sz + sy, sz + sy + 4};
  float acc[4] = {0.f, 0.f, 0.f, 0.f};
  if (g.packed) {
    for (int corner = 0; corner < 8; ++corner) {
      const float w = wxy[corner & 3] * wz[corner >> 2];
      const std::int16_t* node = g.packed + first + offset[corner];
      for (int c = 0; c < 4; ++c) acc[c] += w * float(node[c]);
    }
    return {acc[0] * g.scale[0], {acc[1] * g.scale[1], acc[2] * g.scale[2], acc[3] * g.scale[3]}};
  }
  for (int corner = 0; corner < 8; ++corner) {
    const float w = wxy[corner & 3] * wz[corner >> 2];
    const float* node = g.nodes + first + offset[corner];
    for (int c = 0; c < 4; ++c) acc[c] += w * node[c];
  }
  return {acc[0], {acc[1], acc[2], acc[3]}};
}

#if defined(ISOKIT_FIELD_MATH_SSE2)
namespace grid_detail {

/// Four int16 channels (the low 8 bytes of `x`, `high` false; the high 8 bytes, true) as floats.
inline __m128 widen(__m128i x, bool high) {
  const __m128i z = _mm_setzero_si128();
  const __m128i wide = high ? _mm_unpackhi_epi16(z, x) : _mm_unpacklo_epi16(z, x);
  return _mm_cvtepi32_ps(_mm_srai_epi32(wide, 16));  // sign-extended: int16 << 16 >> 16
}

}  // namespace grid_detail
#endif

#if defined(ISOKIT_FIELD_MATH_SSE2)
namespace grid_detail {

/// eval_grid_inside_scalar with x, y, z (and the four node channels) in the lanes of a register,
/// written to `out`. With `kSkipEmpty`, returns false without reading a node when the cell's
/// brick is empty (`grid_cell_occupied`: the value there is 0).
template <bool kSkipEmpty>
inline bool eval_cell(const GridView& g, const Vec3f& p, FieldSample& out) {
  // eval_grid_inside_scalar with x, y, z (and the four node channels) in the lanes of a register.
  const __m128 lo = _mm_setr_ps(g.box.lo.x, g.box.lo.y, g.box.lo.z, 0.f);
  const __m128 hi = _mm_setr_ps(g.box.hi.x, g.box.hi.y, g.box.hi.z, 1.f);
  const __m128 s = _mm_mul_ps(_mm_div_ps(_mm_sub_ps(_mm_setr_ps(p.x, p.y, p.z, 0.f), lo), _mm_sub_ps(hi, lo)),
                              _mm_set1_ps(float(g.n - 1)));
  __m128i c = _mm_cvttps_epi32(s);
  c = _mm_and_si128(c, _mm_cmpgt_epi32(c, _mm_setzero_si128()));
  const __m128i last = _mm_set1_epi32(g.n - 2), over = _mm_cmpgt_epi32(c, last);
  c = _mm_or_si128(_mm_and_si128(over, last), _mm_andnot_si128(over, c));
  const __m128 f =
      _mm_min_ps(_mm_max_ps(_mm_sub_ps(s, _mm_cvtepi32_ps(c)), _mm_setzero_ps()), _mm_set1_ps(1.f));
  const __m128 omf = _mm_sub_ps(_mm_set1_ps(1.f), f);
  const __m128 u = _mm_unpacklo_ps(omf, f);  // omf.x f.x omf.y f.y
  const __m128 wxy = _mm_mul_ps(_mm_shuffle_ps(u, u, 0x44), _mm_shuffle_ps(u, u, 0xfa));
  const __m128 w0 = _mm_mul_ps(wxy, _mm_shuffle_ps(omf, omf, 0xaa)),
               w1 = _mm_mul_ps(wxy, _mm_shuffle_ps(f, f, 0xaa));
  const int cx = _mm_cvtsi128_si32(c), cy = _mm_cvtsi128_si32(_mm_shuffle_epi32(c, 0x55)),
            cz = _mm_cvtsi128_si32(_mm_shuffle_epi32(c, 0xaa));
  if (kSkipEmpty && g.occupied) {
    const long brick =
        (long(cz / GridView::kBrick) * g.bricks + cy / GridView::kBrick) * g.bricks + cx / GridView::kBrick;
    if (!((g.occupied[brick >> 6] >> (brick & 63)) & 1u)) return false;
  }
  const long sy = 4L * g.n, sz = sy * g.n;
  const long first = cz * sz + cy * sy + 4L * cx;
  // Corner order 0..7 as the scalar code: (x, x+1) of row (y, z), (y+1, z), (y, z+1), (y+1, z+1).
  const long row[4] = {0, sy, sz, sz + sy};
  const __m128 wl[4] = {_mm_shuffle_ps(w0, w0, 0x00), _mm_shuffle_ps(w0, w0, 0xaa),
                        _mm_shuffle_ps(w1, w1, 0x00), _mm_shuffle_ps(w1, w1, 0xaa)};
  const __m128 wr[4] = {_mm_shuffle_ps(w0, w0, 0x55), _mm_shuffle_ps(w0, w0, 0xff),
                        _mm_shuffle_ps(w1, w1, 0x55), _mm_shuffle_ps(w1, w1, 0xff)};
  __m128 sum = _mm_setzero_ps();
  alignas(16) float acc[4];
  if (g.packed) {
    // Two x-neighbours' eight int16 in one load.
    const std::int16_t* b = g.packed + first;
    for (int r = 0; r < 4; ++r) {
      const __m128i pair = _mm_loadu_si128(reinterpret_cast<const __m128i*>(b + row[r]));
      sum = _mm_add_ps(sum, _mm_mul_ps(wl[r], grid_detail::widen(pair, false)));
      sum = _mm_add_ps(sum, _mm_mul_ps(wr[r], grid_detail::widen(pair, true)));
    }
    _mm_store_ps(acc, _mm_mul_ps(sum, _mm_loadu_ps(g.scale)));
  } else {
    const float* b = g.nodes + first;
    for (int r = 0; r < 4; ++r) {
      sum = _mm_add_ps(sum, _mm_mul_ps(wl[r], _mm_loadu_ps(b + row[r])));
      sum = _mm_add_ps(sum, _mm_mul_ps(wr[r], _mm_loadu_ps(b + row[r] + 4)));
    }
    _mm_store_ps(acc, sum);
  }
  out = {acc[0], {acc[1], acc[2], acc[3]}};
  return true;
}

}  // namespace grid_detail
#endif

ISOKIT_HOSTDEV inline FieldSample eval_grid_inside(const GridView& g, const Vec3f& p) {
#if defined(ISOKIT_FIELD_MATH_SSE2)
  FieldSample out;
  grid_detail::eval_cell<false>(g, p, out);
  return out;
#else
  return eval_grid_inside_scalar(g, p);
#endif
}

/// `eval_grid_inside` where the cell's brick may hold a non-zero value (`grid_cell_occupied`):
/// false, `out` untouched, where it holds only zeros.
ISOKIT_HOSTDEV inline bool eval_grid_inside_occupied(const GridView& g, const Vec3f& p, FieldSample& out) {
#if defined(ISOKIT_FIELD_MATH_SSE2)
  return grid_detail::eval_cell<true>(g, p, out);
#else
  if (!grid_cell_occupied(g, p)) return false;
  out = eval_grid_inside_scalar(g, p);
  return true;
#endif
}

}  // namespace isokit::implicit
