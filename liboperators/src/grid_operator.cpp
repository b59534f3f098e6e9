// SPDX-License-Identifier: MIT
#include "isokit/operators/grid_operator.h"

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
