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
///
/// Evaluation reads the 4 × 4 stencil directly where it lies on the grid, through `ghost` at the
/// edges, or from a copy padded with the ghost nodes (`GridOperatorView::padded`, no edge cases).
/// Every path gives the same bits, and x86 hosts (SSE2) the same bits as the scalar device code
/// (the kernel: bicubic.h). A 16-bit copy of the padded samples in 8 × 8 tiles, each with its own
/// offset and step (`GridOperatorView::packed`: 2.1 bytes a sample), is decoded into the stencil
/// and evaluated by the same kernel; its samples lie within half their tile's step of the floats.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "isokit/core/hostdev.h"
#include "isokit/operators/bicubic.h"
#include "isokit/operators/operator.h"

namespace isokit::operators {

/// Plain-data view of a grid operator (host or device memory); evaluation is inline.
struct GridOperatorView {
  const float* data{nullptr};
  int nd{0};  ///< number of d slices (≥ 1)
  int nf{0};  ///< nodes per f axis (≥ 2)
  /// Optional: the same slices with one `ghost` node added on each side of both f axes,
  /// `padded[(k * (nf + 2) + i1 + 1) * (nf + 2) + i2 + 1] = ghost(k, i1, i2)` (see
  /// `padded_size`, `fill_padded`). When set, `eval` reads every stencil from it, with no edge
  /// cases; the results are the same bit for bit.
  const float* padded{nullptr};
  /// Optional, instead of `padded`: the padded copy stored as 16-bit integers in tiles of
  /// kPackTile × kPackTile samples of a slice, each tile with its own offset and step: sample `i`
  /// (row r, column c of slice k of the padded copy) is `o + step * packed[i]`, with
  /// `(o, step) = packed_tiles[2 t], packed_tiles[2 t + 1]`, `t = (k * T + r / kPackTile) * T +
  /// c / kPackTile`, `T = packed_tiles_per_row()` (`pack_padded`). A tile's step is its samples'
  /// range / 65534, so it is within half a step of the float. When set, `eval` reads every stencil
  /// from it (decoded, then the same kernel) and neither `data` nor `padded` is read.
  const std::int16_t* packed{nullptr};
  const float* packed_tiles{nullptr};

  static constexpr int kPackTile = 8;

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
  /// Number of floats of the padded copy: `nd (nf + 2)²`.
  ISOKIT_HOSTDEV std::size_t padded_size() const {
    return static_cast<std::size_t>(nd) * static_cast<std::size_t>(nf + 2) * static_cast<std::size_t>(nf + 2);
  }
  /// Writes the padded copy (`padded_size()` floats) to `out`.
  ISOKIT_HOSTDEV void fill_padded(float* out) const {
    for (int k = 0; k < nd; ++k)
      for (int i1 = -1; i1 <= nf; ++i1)
        for (int i2 = -1; i2 <= nf; ++i2)
          out[(static_cast<std::size_t>(k) * (nf + 2) + (i1 + 1)) * (nf + 2) + (i2 + 1)] = ghost(k, i1, i2);
  }

  /// Tiles per row (and per column) of a packed slice.
  ISOKIT_HOSTDEV int packed_tiles_per_row() const { return (nf + 2 + kPackTile - 1) / kPackTile; }
  /// Number of tiles of the packed copy: `nd T²` (2 floats each in `packed_tiles`).
  ISOKIT_HOSTDEV std::size_t packed_tile_count() const {
    const std::size_t t = static_cast<std::size_t>(packed_tiles_per_row());
    return static_cast<std::size_t>(nd) * t * t;
  }
  /// Quantises a padded copy (`padded_size()` floats at `padded_samples`) into `out`
  /// (`padded_size()` int16) and `tiles` (`2 packed_tile_count()` floats): per tile, the offset
  /// `(max + min) / 2` and the step `(max − min) / 65534` of its samples (1 for a constant tile),
  /// each sample `round((v − offset) / step)`. Host code (grid_operator.cpp).
  void pack_padded(const float* padded_samples, std::int16_t* out, float* tiles) const;
  /// Sample (k, r, c) of the packed copy (r, c: padded row and column), decoded.
  ISOKIT_HOSTDEV float unpack(int k, int r, int c) const {
    const int n = nf + 2, t = packed_tiles_per_row();
    const std::size_t tile = (static_cast<std::size_t>(k) * t + static_cast<std::size_t>(r / kPackTile)) * t +
                             static_cast<std::size_t>(c / kPackTile);
    const std::size_t i =
        (static_cast<std::size_t>(k) * static_cast<std::size_t>(n) + static_cast<std::size_t>(r)) *
            static_cast<std::size_t>(n) +
        static_cast<std::size_t>(c);
    return packed_tiles[2 * tile] + packed_tiles[2 * tile + 1] * float(packed[i]);
  }

  /// Cell `i` (in [0, nf - 2]) and position `t` in it of `f`, clamped to [0, 1].
  ISOKIT_HOSTDEV void locate(float f, int& i, float& t) const {
    f = f > 0.f ? (f < 1.f ? f : 1.f) : 0.f;  // NaN: 0 (never an index out of the grid)
    const float x = f * float(nf - 1);
    i = int(x);
    i = i > nf - 2 ? nf - 2 : i;
    t = x - float(i);
  }

  /// Bicubic evaluation of slice `k`.
  ISOKIT_HOSTDEV OpSample eval_slice(int k, float f1, float f2) const {
    return eval_at(k, 0.f, f1, f2, true);
  }

  /// `g(f1, f2; d)` with `∂g/∂f1`, `∂g/∂f2` (linear in d between slices). The two slices'
  /// 4 × 4 stencils are blended in `d` first, then one bicubic is evaluated (the same
  /// interpolant: both steps are linear in the samples). Stencils are read from `padded` when
  /// set, else directly when all 16 nodes are on the grid, else through `ghost`.
  ISOKIT_HOSTDEV OpSample eval(float f1, float f2, float d) const {
    int k = 0;
    float w = 0.f;
    locate_d(d, k, w);
    return eval_at(k, w, f1, f2, true);
  }

  /// `eval` with every stencil value read through `ghost` (the edge path everywhere): the same
  /// result bit for bit; kept as the reference for tests.
  ISOKIT_HOSTDEV OpSample eval_ghosted(float f1, float f2, float d) const {
    int k = 0;
    float w = 0.f;
    locate_d(d, k, w);
    return eval_at(k, w, f1, f2, false);
  }

 private:
  ISOKIT_HOSTDEV void locate_d(float d, int& k, float& w) const {
    if (nd == 1) return;
    d = d > 0.f ? (d < 1.f ? d : 1.f) : 0.f;  // NaN: 0
    const float z = d * float(nd - 1);
    k = int(z);
    k = k > nd - 2 ? nd - 2 : k;
    w = z - float(k);
  }

  /// Slices k and k + 1 blended with weight `w` (slice k + 1 is not read when w == 0).
  ISOKIT_HOSTDEV OpSample eval_at(int k, float w, float f1, float f2, bool direct) const {
    int i1 = 0, i2 = 0;
    float t1 = 0.f, t2 = 0.f;
    locate(f1, i1, t1);
    locate(f2, i2, t2);
    const float s = float(nf - 1);
    if (direct && packed) {
      float v[32];  // slice k's stencil rows, then slice k + 1's (read only when w != 0)
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) v[4 * a + b] = unpack(k, i1 + a, i2 + b);
      if (w != 0.f)
        for (int a = 0; a < 4; ++a)
          for (int b = 0; b < 4; ++b) v[16 + 4 * a + b] = unpack(k + 1, i1 + a, i2 + b);
      return bicubic(v, 4, 16, w, t1, t2, s);
    }
    if (direct && padded) {
      const std::ptrdiff_t n = nf + 2;
      return bicubic(padded + (k * n + i1) * n + i2, n, n * n, w, t1, t2, s);
    }
    if (direct && i1 >= 1 && i2 >= 1 && i1 <= nf - 3 && i2 <= nf - 3) {
      const std::ptrdiff_t n = nf;
      return bicubic(data + (k * n + i1 - 1) * n + i2 - 1, n, n * n, w, t1, t2, s);
    }
    float v[16];  // the stencil, blended in d
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        const float x = ghost(k, i1 - 1 + a, i2 - 1 + b);
        v[4 * a + b] = w == 0.f ? x : x + w * (ghost(k + 1, i1 - 1 + a, i2 - 1 + b) - x);
      }
    return bicubic(v, 4, 0, 0.f, t1, t2, s);
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

/// Samples an operator given by its value `g(f1, f2, d)` onto an `nd × nf × nf` grid (the layout
/// above), slices in parallel: how the 2013 paper stores its analytic operators (§6: 128³
/// textures). \throw isokit::InputError on bad sizes or a non-finite sample.
GridOperator sample_operator(const std::function<float(float f1, float f2, float d)>& g, int nf, int nd);

/// The 2013 gradient-based blend (analytic.h, `gradient_blend_2013`) sampled by `sample_operator`.
GridOperator sampled_gradient_blend_2013(int nf, int nd);

}  // namespace isokit::operators
