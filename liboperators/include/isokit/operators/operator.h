// SPDX-License-Identifier: MIT
/// \file
/// Binary composition operators `g(f1, f2; d)` on field values in [0, 1] (2013 §4.2, 2014 §4).
/// Every operator returns the composed value together with both partial derivatives, from
/// which the composed gradient is `dg1 ∇f1 + dg2 ∇f2`. The dependence of `d` on the gradient
/// angle is neglected in that gradient, as in both papers.
#pragma once

#include "isokit/core/hostdev.h"

namespace isokit::operators {

/// `g` with its partial derivatives `∂g/∂f1`, `∂g/∂f2`.
struct OpSample {
  float g{0};
  float dg1{0};
  float dg2{0};
};

/// Ricci's union, `g = max(f1, f2)` (2013 §4.2, the top-level composition of the pairs).
/// At ties (`f1 == f2`) the derivative picks the first operand, (1, 0): a valid one-sided
/// derivative that keeps the composed gradient the gradient of an actual operand.
ISOKIT_HOSTDEV inline OpSample union_max(float f1, float f2) {
  return f1 >= f2 ? OpSample{f1, 1.f, 0.f} : OpSample{f2, 0.f, 1.f};
}

}  // namespace isokit::operators
