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
/// `box.lo + (i, j, k) * (box.hi - box.lo) / (n - 1)`, stored as 4 floats
/// (value, gx, gy, gz) at `nodes[4 * ((k * n + j) * n + i)]` (x fastest).
struct GridView {
  const float* nodes{nullptr};
  int n{0};
  Box3f box{};
};

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
  const float* base = g.nodes + (ci[2] * sz + ci[1] * sy + 4L * ci[0]);
  const long offset[8] = {0, 4, sy, sy + 4, sz, sz + 4, sz + sy, sz + sy + 4};
  float acc[4] = {0.f, 0.f, 0.f, 0.f};
  for (int corner = 0; corner < 8; ++corner) {
    const float w = wxy[corner & 3] * wz[corner >> 2];
    const float* node = base + offset[corner];
    for (int c = 0; c < 4; ++c) acc[c] += w * node[c];
  }
  return {acc[0], {acc[1], acc[2], acc[3]}};
}

ISOKIT_HOSTDEV inline FieldSample eval_grid_inside(const GridView& g, const Vec3f& p) {
#if defined(ISOKIT_FIELD_MATH_SSE2)
  // eval_grid_inside_scalar with x, y, z (and the four node floats) in the lanes of a register.
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
  const long sy = 4L * g.n, sz = sy * g.n;
  const float* b0 = g.nodes + (cz * sz + cy * sy + 4L * cx);
  const float* b1 = b0 + sz;
  __m128 sum = _mm_setzero_ps();
  sum = _mm_add_ps(sum, _mm_mul_ps(_mm_shuffle_ps(w0, w0, 0x00), _mm_loadu_ps(b0)));
  sum = _mm_add_ps(sum, _mm_mul_ps(_mm_shuffle_ps(w0, w0, 0x55), _mm_loadu_ps(b0 + 4)));
  sum = _mm_add_ps(sum, _mm_mul_ps(_mm_shuffle_ps(w0, w0, 0xaa), _mm_loadu_ps(b0 + sy)));
  sum = _mm_add_ps(sum, _mm_mul_ps(_mm_shuffle_ps(w0, w0, 0xff), _mm_loadu_ps(b0 + sy + 4)));
  sum = _mm_add_ps(sum, _mm_mul_ps(_mm_shuffle_ps(w1, w1, 0x00), _mm_loadu_ps(b1)));
  sum = _mm_add_ps(sum, _mm_mul_ps(_mm_shuffle_ps(w1, w1, 0x55), _mm_loadu_ps(b1 + 4)));
  sum = _mm_add_ps(sum, _mm_mul_ps(_mm_shuffle_ps(w1, w1, 0xaa), _mm_loadu_ps(b1 + sy)));
  sum = _mm_add_ps(sum, _mm_mul_ps(_mm_shuffle_ps(w1, w1, 0xff), _mm_loadu_ps(b1 + sy + 4)));
  alignas(16) float acc[4];
  _mm_store_ps(acc, sum);
  return {acc[0], {acc[1], acc[2], acc[3]}};
#else
  return eval_grid_inside_scalar(g, p);
#endif
}

}  // namespace isokit::implicit
