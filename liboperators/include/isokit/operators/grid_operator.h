// SPDX-License-Identifier: MIT
/// \file
/// Grid operators: `g(f1, f2; d)` sampled on `(f1, f2, d) ∈ [0, 1]³` (2014 §4.2: 128³ grids).
/// Layout (also the .npy layout): `data[(k * nf + i1) * nf + i2] = g(i1 h, i2 h; k / (nd - 1))`,
/// `h = 1 / (nf - 1)`: `d` slowest, `f2` fastest.
///
/// Interpolation: Catmull-Rom (cubic Hermite with central-difference slopes) in `f1` and `f2`,
/// linear in `d`. Within a slice the interpolant is C¹, so `∂g/∂f1`, `∂g/∂f2` are continuous in
/// (f1, f2) — what Newton steps along `∂g/∂f1 ∇f1 + ∂g/∂f2 ∇f2` need; linear blending of two C¹
/// slices keeps them continuous in `d` too. At a node the derivative equals the central difference
/// of the grid values. Beyond the grid edges the samples are extrapolated linearly (ghost
/// `2 g[0] - g[1]`), so the derivative at an edge node is the one-sided difference. Inputs
/// outside [0, 1] are clamped. The `d` dependence is not differentiated (see operator.h).
#pragma once

#include <cstddef>
#include <vector>

#include "isokit/core/hostdev.h"
#include "isokit/operators/operator.h"

namespace isokit::operators {

/// Plain-data view of a grid operator (host or device memory); evaluation is inline.
struct GridOperatorView {
  const float* data{nullptr};
  int nd{0};  ///< number of d slices (≥ 1)
  int nf{0};  ///< nodes per f axis (≥ 2)

  ISOKIT_HOSTDEV float node(int k, int i1, int i2) const {
    return data[(static_cast<std::size_t>(k) * nf + i1) * nf + i2];
  }
  /// Sample with linear extrapolation one node beyond each edge (`g[-1] = 2 g[0] - g[1]`, per
  /// axis; corners extrapolate along both). No recursion (device code).
  ISOKIT_HOSTDEV float ghost(int k, int i1, int i2) const {
    int a1 = i1, b1 = i1, a2 = i2, b2 = i2;
    float w1 = 1.f, w2 = 1.f;  // weight of a; b gets (1 - w)
    if (i1 < 0) a1 = 0, b1 = 1, w1 = 2.f;
    if (i1 >= nf) a1 = nf - 1, b1 = nf - 2, w1 = 2.f;
    if (i2 < 0) a2 = 0, b2 = 1, w2 = 2.f;
    if (i2 >= nf) a2 = nf - 1, b2 = nf - 2, w2 = 2.f;
    float v = w1 * w2 * node(k, a1, a2);
    if (w2 != 1.f) v += w1 * (1.f - w2) * node(k, a1, b2);
    if (w1 != 1.f) v += (1.f - w1) * w2 * node(k, b1, a2);
    if (w1 != 1.f && w2 != 1.f) v += (1.f - w1) * (1.f - w2) * node(k, b1, b2);
    return v;
  }

  static ISOKIT_HOSTDEV void catmull_rom(float t, float w[4], float dw[4]) {
    const float t2 = t * t, t3 = t2 * t;
    w[0] = 0.5f * (-t3 + 2.f * t2 - t);
    w[1] = 0.5f * (3.f * t3 - 5.f * t2 + 2.f);
    w[2] = 0.5f * (-3.f * t3 + 4.f * t2 + t);
    w[3] = 0.5f * (t3 - t2);
    dw[0] = 0.5f * (-3.f * t2 + 4.f * t - 1.f);
    dw[1] = 0.5f * (9.f * t2 - 10.f * t);
    dw[2] = 0.5f * (-9.f * t2 + 8.f * t + 1.f);
    dw[3] = 0.5f * (3.f * t2 - 2.f * t);
  }

  /// Bicubic evaluation of slice `k`.
  ISOKIT_HOSTDEV OpSample eval_slice(int k, float f1, float f2) const {
    const float s = float(nf - 1);
    f1 = f1 < 0.f ? 0.f : (f1 > 1.f ? 1.f : f1);
    f2 = f2 < 0.f ? 0.f : (f2 > 1.f ? 1.f : f2);
    const float x1 = f1 * s, x2 = f2 * s;
    int i1 = int(x1), i2 = int(x2);
    i1 = i1 > nf - 2 ? nf - 2 : i1;
    i2 = i2 > nf - 2 ? nf - 2 : i2;
    float w1[4], dw1[4], w2[4], dw2[4];
    catmull_rom(x1 - float(i1), w1, dw1);
    catmull_rom(x2 - float(i2), w2, dw2);
    OpSample r;
    for (int a = 0; a < 4; ++a) {
      float row = 0.f, drow = 0.f;
      for (int b = 0; b < 4; ++b) {
        const float v = ghost(k, i1 - 1 + a, i2 - 1 + b);
        row += w2[b] * v;
        drow += dw2[b] * v;
      }
      r.g += w1[a] * row;
      r.dg1 += dw1[a] * row;
      r.dg2 += w1[a] * drow;
    }
    r.dg1 *= s;
    r.dg2 *= s;
    return r;
  }

  /// `g(f1, f2; d)` with `∂g/∂f1`, `∂g/∂f2` (linear in d between slices).
  ISOKIT_HOSTDEV OpSample eval(float f1, float f2, float d) const {
    if (nd == 1) return eval_slice(0, f1, f2);
    d = d < 0.f ? 0.f : (d > 1.f ? 1.f : d);
    const float z = d * float(nd - 1);
    int k = int(z);
    k = k > nd - 2 ? nd - 2 : k;
    const float w = z - float(k);
    const OpSample a = eval_slice(k, f1, f2);
    if (w == 0.f) return a;
    const OpSample b = eval_slice(k + 1, f1, f2);
    return OpSample{a.g + w * (b.g - a.g), a.dg1 + w * (b.dg1 - a.dg1), a.dg2 + w * (b.dg2 - a.dg2)};
  }
};

/// An owned grid operator. \throw isokit::InputError on bad sizes.
class GridOperator {
 public:
  GridOperator() = default;
  GridOperator(int nd, int nf, std::vector<float> data);

  int nd() const { return nd_; }
  int nf() const { return nf_; }
  const std::vector<float>& data() const { return data_; }
  std::vector<float>& data() { return data_; }
  GridOperatorView view() const { return GridOperatorView{data_.data(), nd_, nf_}; }
  OpSample eval(float f1, float f2, float d) const { return view().eval(f1, f2, d); }
  /// `d` of slice k.
  double slice_d(int k) const { return nd_ == 1 ? 0.0 : double(k) / (nd_ - 1); }
  /// Pointer to slice k (nf * nf values, f2 fastest).
  const float* slice(int k) const { return data_.data() + static_cast<std::size_t>(k) * nf_ * nf_; }

 private:
  int nd_{0}, nf_{0};
  std::vector<float> data_;
};

}  // namespace isokit::operators
