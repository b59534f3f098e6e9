// SPDX-License-Identifier: MIT
/// \file
/// Per-node composition math of the evaluators (plain data, `ISOKIT_HOSTDEV`, shared with CUDA).
///
/// A node combines its operands `a`, `b` (value + gradient) with `g(fa, fb; d)`,
/// `d = controller(α)`, `α = angle(∇fa, ∇fb)` (0 when a gradient vanishes), and gradient
/// `∂g/∂f1 ∇fa + ∂g/∂f2 ∇fb` (the dependence of `d` on `α` is neglected, as in both papers).
/// Two operands that are both exactly 0 give exactly 0 (compact support of every node).
#pragma once

#include <cmath>
#include <cstdint>

#include "isokit/core/hostdev.h"
#include "isokit/core/math.h"
#include "isokit/implicit/field_math.h"
#include "isokit/operators/analytic.h"
#include "isokit/operators/controller.h"
#include "isokit/operators/grid_operator.h"

namespace isokit::implicit {

/// Operator kinds (fixed numbers).
enum class OpKind : std::int32_t { Max = 0, SumBlend = 1, CleanUnion = 2, GradientBlend2013 = 3, Grid = 4 };

/// What happened at one node for one point.
struct NodeDiagnostics {
  float alpha{0};              ///< angle between the operand gradients (radians)
  float d{0};                  ///< controller value used
  float value{0};              ///< composed value
  std::uint8_t evaluated{0};   ///< 0: pruned (point outside the node's support box)
  std::uint8_t dominant{0};    ///< 1 or 2: operand with the larger ∂g/∂fi (0: both operands 0)
  std::uint8_t on_contact{0};  ///< both operands inside (> 0.5) with an active d > 0
};

/// acos on [-1, 1] (Abramowitz & Stegun 4.4.46: sqrt(1 - x) times a degree-7 polynomial, error
/// ≤ 2e-8 in exact arithmetic, ~1e-6 in float); 3-4x cheaper than `std::acos` on the host, far
/// below the controller tables' resolution (π / 255).
ISOKIT_HOSTDEV inline float fast_acos(float x) {
  const float ax = x < 0.f ? -x : x;
  const float p =
      ((((((-0.0012624911f * ax + 0.0066700901f) * ax - 0.0170881256f) * ax + 0.0308918810f) * ax -
         0.0501743046f) *
            ax +
        0.0889789874f) *
           ax -
       0.2145988016f) *
          ax +
      1.5707963050f;
  const float r = hd_sqrt(1.f - ax) * p;
  return x < 0.f ? kPiF - r : r;
}

ISOKIT_HOSTDEV inline bool node_needs_alpha(OpKind k) {
  return k == OpKind::GradientBlend2013 || k == OpKind::Grid;
}

/// Composes two operand samples. `grid` is used for OpKind::Grid only; `diag` may be null.
ISOKIT_HOSTDEV inline FieldSample compose_node(OpKind kind, const operators::ControllerTable& controller,
                                               const operators::GridOperatorView& grid, const FieldSample& a,
                                               const FieldSample& b, NodeDiagnostics* diag) {
  // An operand that is exactly 0 (outside its support) leaves the other one unchanged: the
  // boundary conditions g(f, 0) = f, g(0, f) = f of every operator, applied exactly (a grid
  // operator meets them to interpolation accuracy, checked when the node is made). Most points
  // lie inside one or two primitives, so most nodes take this path.
  if (a.value == 0.f || b.value == 0.f) {
    const bool first = b.value == 0.f;
    if (diag) *diag = NodeDiagnostics{0.f, 0.f, first ? a.value : b.value, 1, std::uint8_t(first ? 1 : 2), 0};
    if (a.value == 0.f && b.value == 0.f) {
      if (diag) diag->dominant = 0;
      return {};
    }
    return first ? a : b;
  }
  float alpha = 0.f, d = 0.f;
  if (diag || node_needs_alpha(kind)) {
    const float na = norm(a.gradient), nb = norm(b.gradient);
    if (na > 0.f && nb > 0.f) {
      float c = dot(a.gradient, b.gradient) / (na * nb);
      c = c < -1.f ? -1.f : (c > 1.f ? 1.f : c);
      alpha = fast_acos(c);
    }
    if (node_needs_alpha(kind)) d = controller(alpha);
  }
  operators::OpSample s;
  switch (kind) {
    case OpKind::SumBlend:
      s = operators::sum_blend(a.value, b.value);
      break;
    case OpKind::CleanUnion:
      s = operators::clean_union(a.value, b.value);
      break;
    case OpKind::GradientBlend2013:
      s = operators::gradient_blend_2013(a.value, b.value, d);
      break;
    case OpKind::Grid:
      s = grid.eval(a.value, b.value, d);
      break;
    case OpKind::Max:
    default:
      s = operators::union_max(a.value, b.value);
      break;
  }
  FieldSample r{s.g, a.gradient * s.dg1 + b.gradient * s.dg2};
  if (diag) {
    *diag = NodeDiagnostics{alpha,
                            d,
                            s.g,
                            1,
                            std::uint8_t(s.dg1 >= s.dg2 ? 1 : 2),
                            std::uint8_t(a.value > 0.5f && b.value > 0.5f && d > 0.f ? 1 : 0)};
  }
  return r;
}

}  // namespace isokit::implicit
