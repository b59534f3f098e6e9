// SPDX-License-Identifier: MIT
/// \file
/// The interpolation kernel of grid operators (grid_operator.h): Catmull-Rom weights and the
/// bicubic of one 4 × 4 stencil, optionally blended in `d` between two slices, with both partial
/// derivatives. Plain inline float math (`ISOKIT_HOSTDEV`) shared with the CUDA kernels. Host
/// builds with SSE2 evaluate the bicubic four lanes at a time, with the scalar code's operations in
/// the scalar code's order: the same results bit for bit as `bicubic_scalar` (the device code).
#pragma once

#include <cstddef>

#include "isokit/core/hostdev.h"
#include "isokit/operators/operator.h"

#if defined(__SSE2__) && !defined(__CUDACC__)
#include <emmintrin.h>
#define ISOKIT_GRID_OPERATOR_SSE2 1
#endif

namespace isokit::operators {

/// Catmull-Rom weights `w` of the four stencil nodes at `t` ∈ [0, 1] and their derivatives
/// `dw` (Horner form; exact at t = 0 and t = 1).
ISOKIT_HOSTDEV inline void catmull_rom(float t, float w[4], float dw[4]) {
  // w = ((a t + b) t + c) t + d, dw = (3a t + 2b) t + c per node (detail::catmull_rom4 does the
  // same operations lane by lane).
  w[0] = ((-0.5f * t + 1.f) * t + -0.5f) * t + 0.f;
  w[1] = ((1.5f * t + -2.5f) * t + 0.f) * t + 1.f;
  w[2] = ((-1.5f * t + 2.f) * t + 0.5f) * t + 0.f;
  w[3] = ((0.5f * t + -0.5f) * t + 0.f) * t + 0.f;
  dw[0] = (-1.5f * t + 2.f) * t + -0.5f;
  dw[1] = (4.5f * t + -5.f) * t + 0.f;
  dw[2] = (-4.5f * t + 4.f) * t + 0.5f;
  dw[3] = (1.5f * t + -1.f) * t + 0.f;
}

#if defined(ISOKIT_GRID_OPERATOR_SSE2)
namespace detail {

/// ((x0 + x1) + x2) + x3, the scalar code's order.
inline float sum4(__m128 x) {
  alignas(16) float v[4];
  _mm_store_ps(v, x);
  return ((v[0] + v[1]) + v[2]) + v[3];
}
/// `catmull_rom`, the four weights in one register each (the same operations per lane).
inline void catmull_rom4(float t, __m128& w, __m128& dw) {
  const __m128 x = _mm_set1_ps(t);
  w = _mm_mul_ps(x, _mm_setr_ps(-0.5f, 1.5f, -1.5f, 0.5f));
  w = _mm_mul_ps(_mm_add_ps(w, _mm_setr_ps(1.f, -2.5f, 2.f, -0.5f)), x);
  w = _mm_mul_ps(_mm_add_ps(w, _mm_setr_ps(-0.5f, 0.f, 0.5f, 0.f)), x);
  w = _mm_add_ps(w, _mm_setr_ps(0.f, 1.f, 0.f, 0.f));
  dw = _mm_mul_ps(x, _mm_setr_ps(-1.5f, 4.5f, -4.5f, 1.5f));
  dw = _mm_mul_ps(_mm_add_ps(dw, _mm_setr_ps(2.f, -5.f, 4.f, -1.f)), x);
  dw = _mm_add_ps(dw, _mm_setr_ps(-0.5f, 0.f, 0.5f, 0.f));
}

}  // namespace detail
#endif

/// `bicubic` in plain scalar code (the device code; `bicubic` gives the same bits on every
/// host).
ISOKIT_HOSTDEV inline OpSample bicubic_scalar(const float* p, std::ptrdiff_t stride, std::ptrdiff_t slice,
                                              float w, float t1, float t2, float s) {
  float w1[4], dw1[4], w2[4], dw2[4];
  catmull_rom(t1, w1, dw1);
  catmull_rom(t2, w2, dw2);
  float v[16];  // v[4 a + b]
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) {
      const float x = p[a * stride + b];
      v[4 * a + b] = w == 0.f ? x : x + w * (p[slice + a * stride + b] - x);
    }
  float c[4], e[4];
  for (int b = 0; b < 4; ++b) {
    c[b] = w1[0] * v[b] + w1[1] * v[4 + b] + w1[2] * v[8 + b] + w1[3] * v[12 + b];
    e[b] = dw1[0] * v[b] + dw1[1] * v[4 + b] + dw1[2] * v[8 + b] + dw1[3] * v[12 + b];
  }
  OpSample r;
  r.g = w2[0] * c[0] + w2[1] * c[1] + w2[2] * c[2] + w2[3] * c[3];
  r.dg1 = (w2[0] * e[0] + w2[1] * e[1] + w2[2] * e[2] + w2[3] * e[3]) * s;
  r.dg2 = (dw2[0] * c[0] + dw2[1] * c[1] + dw2[2] * c[2] + dw2[3] * c[3]) * s;
  return r;
}

/// Bicubic of the stencil rows `p + a * stride` (a = 0..3, along f1; 4 values each, along
/// f2), blended with weight `w` towards the rows `slice` floats further (not read when
/// `w == 0`); `s = nf - 1` scales the derivatives. Sums run along f1 first, then along f2.
ISOKIT_HOSTDEV inline OpSample bicubic(const float* p, std::ptrdiff_t stride, std::ptrdiff_t slice, float w,
                                       float t1, float t2, float s) {
#if defined(ISOKIT_GRID_OPERATOR_SSE2)
  __m128 w1, dw1, w2, dw2;
  detail::catmull_rom4(t1, w1, dw1);
  detail::catmull_rom4(t2, w2, dw2);
  __m128 row[4];
  for (int a = 0; a < 4; ++a) {
    const __m128 x = _mm_loadu_ps(p + a * stride);
    row[a] =
        w == 0.f
            ? x
            : _mm_add_ps(x, _mm_mul_ps(_mm_set1_ps(w), _mm_sub_ps(_mm_loadu_ps(p + slice + a * stride), x)));
  }
  __m128 c = _mm_mul_ps(_mm_shuffle_ps(w1, w1, 0x00), row[0]);
  __m128 e = _mm_mul_ps(_mm_shuffle_ps(dw1, dw1, 0x00), row[0]);
  c = _mm_add_ps(c, _mm_mul_ps(_mm_shuffle_ps(w1, w1, 0x55), row[1]));
  e = _mm_add_ps(e, _mm_mul_ps(_mm_shuffle_ps(dw1, dw1, 0x55), row[1]));
  c = _mm_add_ps(c, _mm_mul_ps(_mm_shuffle_ps(w1, w1, 0xaa), row[2]));
  e = _mm_add_ps(e, _mm_mul_ps(_mm_shuffle_ps(dw1, dw1, 0xaa), row[2]));
  c = _mm_add_ps(c, _mm_mul_ps(_mm_shuffle_ps(w1, w1, 0xff), row[3]));
  e = _mm_add_ps(e, _mm_mul_ps(_mm_shuffle_ps(dw1, dw1, 0xff), row[3]));
  OpSample r;
  r.g = detail::sum4(_mm_mul_ps(w2, c));
  r.dg1 = detail::sum4(_mm_mul_ps(w2, e)) * s;
  r.dg2 = detail::sum4(_mm_mul_ps(dw2, c)) * s;
  return r;
#else
  return bicubic_scalar(p, stride, slice, w, t1, t2, s);
#endif
}

}  // namespace isokit::operators
