// SPDX-License-Identifier: MIT
#include "isokit/operators/grid_operator.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "isokit/core/error.h"
#include "isokit/core/parallel.h"
#include "isokit/operators/analytic.h"

namespace isokit::operators {

GridOperator::GridOperator(int nd, int nf, std::vector<float> data)
    : nd_(nd), nf_(nf), data_(std::move(data)) {
  require(nd >= 1 && nf >= 2, "grid operator shape",
          "needs nd >= 1 and nf >= 2 (got nd = " + std::to_string(nd) + ", nf = " + std::to_string(nf) + ")",
          "generate a grid with at least two nodes per f axis");
  require(data_.size() == static_cast<std::size_t>(nd) * nf * nf, "grid operator data",
          "size " + std::to_string(data_.size()) + " does not match nd * nf * nf",
          "pass nd * nf * nf values");
}

void GridOperatorView::pack_padded(const float* padded_samples, std::int16_t* out, float* tiles) const {
  const int n = nf + 2, t = packed_tiles_per_row();
  for (int k = 0; k < nd; ++k)
    for (int tr = 0; tr < t; ++tr)
      for (int tc = 0; tc < t; ++tc) {
        const int r0 = tr * kPackTile, c0 = tc * kPackTile;
        const int r1 = std::min(r0 + kPackTile, n), c1 = std::min(c0 + kPackTile, n);
        auto at = [&](int r, int c) {
          return (std::size_t(k) * std::size_t(n) + std::size_t(r)) * std::size_t(n) + std::size_t(c);
        };
        float lo = padded_samples[at(r0, c0)], hi = lo;
        for (int r = r0; r < r1; ++r)
          for (int c = c0; c < c1; ++c)
            lo = std::min(lo, padded_samples[at(r, c)]), hi = std::max(hi, padded_samples[at(r, c)]);
        const float offset = 0.5f * (hi + lo), step = hi > lo ? (hi - lo) / 65534.f : 1.f;
        const std::size_t tile =
            (std::size_t(k) * std::size_t(t) + std::size_t(tr)) * std::size_t(t) + std::size_t(tc);
        tiles[2 * tile] = offset;
        tiles[2 * tile + 1] = step;
        for (int r = r0; r < r1; ++r)
          for (int c = c0; c < c1; ++c)
            out[at(r, c)] = std::int16_t(
                std::clamp(std::lround((padded_samples[at(r, c)] - offset) / step), -32767L, 32767L));
      }
}

GridOperator sample_operator(const std::function<float(float, float, float)>& g, int nf, int nd) {
  require(nd >= 1 && nf >= 2, "sampled operator shape",
          "needs nd >= 1 and nf >= 2 (got nd = " + std::to_string(nd) + ", nf = " + std::to_string(nf) + ")",
          "sample at least two nodes per f axis");
  const std::size_t slice = static_cast<std::size_t>(nf) * static_cast<std::size_t>(nf);
  std::vector<float> data(static_cast<std::size_t>(nd) * slice);
  const float h = 1.f / float(nf - 1);
  parallel_for(static_cast<std::size_t>(nd), 1, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) {
      const float d = nd == 1 ? 0.f : float(k) / float(nd - 1);
      for (int i1 = 0; i1 < nf; ++i1)
        for (int i2 = 0; i2 < nf; ++i2)
          data[k * slice + static_cast<std::size_t>(i1) * nf + i2] = g(float(i1) * h, float(i2) * h, d);
    }
  });
  for (std::size_t i = 0; i < data.size(); ++i)
    require(std::isfinite(data[i]), "sampled operator node " + std::to_string(i), "is not finite",
            "sample an operator that is finite on [0, 1]³");
  return GridOperator(nd, nf, std::move(data));
}

GridOperator sampled_gradient_blend_2013(int nf, int nd) {
  return sample_operator([](float f1, float f2, float d) { return gradient_blend_2013(f1, f2, d).g; }, nf,
                         nd);
}

}  // namespace isokit::operators
