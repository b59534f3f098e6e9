// SPDX-License-Identifier: MIT
#include "isokit/operators/grid_operator.h"

#include "isokit/core/error.h"

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

}  // namespace isokit::operators
