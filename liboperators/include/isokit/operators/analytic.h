// SPDX-License-Identifier: MIT
/// \file
/// Analytic binary operators on field values in [0, 1] (inside > 0.5), with their partial
/// derivatives. `union_max` is in operator.h. All are ISOKIT_HOSTDEV inline (plain float math)
/// so CUDA kernels share them.
///
/// The arc-blend family (clean union, the 2013 gradient-based blend) follows Gourmel et al. 2013
/// as restated in the 2013 paper's Appendix A: the iso-curve of level `C` is the union's L-shape
/// `max(f1, f2) = C` whose corner is replaced by a circle arc of centre `(k(C), k(C))` and radius
/// `C - k(C)`, tangent to both straight parts. Where `min(f1, f2) < k(max(f1, f2))` the point is on
/// a straight part and `g = max`. Otherwise `g` is the smallest level `C ≥ max(f1, f2)` whose arc
/// passes through the point (bracketed scan + bisection), and its derivatives follow from the
/// implicit function theorem.
#pragma once

#include <cmath>

#include "isokit/core/hostdev.h"
#include "isokit/core/math.h"
#include "isokit/operators/operator.h"

namespace isokit::operators {

/// Sum blend clamped to the field range: `g = min(f1 + f2, 1)` (2013 §4.2 "smooth blending").
ISOKIT_HOSTDEV inline OpSample sum_blend(float f1, float f2) {
  const float s = f1 + f2;
  return s < 1.f ? OpSample{s, 1.f, 1.f} : OpSample{1.f, 0.f, 0.f};
}

namespace detail {

/// k(C) and dk/dC of the arc blends. `kind` 0: clean union, 1: the 2013 Appendix A blend with
/// `tan_theta` = tan θ.
ISOKIT_HOSTDEV inline void arc_center(int kind, float tan_theta, float c, float* k, float* dk) {
  if (kind == 0) {  // clean union: k = 2 C² below 0.5 (k(0.5) = 0.5: sharp union at the surface)
    *k = 2.f * c * c;
    *dk = 4.f * c;
  } else if (c <= 0.5f) {  // 2013 Appendix A, outside part
    *k = tan_theta * c;
    *dk = tan_theta;
  } else {  // 2013 Appendix A, inside part: reaches k = C (union) at C = 0.7
    *k = 0.5f * (7.f - 5.f * tan_theta) * c + 1.75f * (tan_theta - 1.f);
    *dk = 0.5f * (7.f - 5.f * tan_theta);
  }
}

ISOKIT_HOSTDEV inline float arc_residual(int kind, float tan_theta, float f1, float f2, float c) {
  float k, dk;
  arc_center(kind, tan_theta, c, &k, &dk);
  return hd_sqrt((f1 - k) * (f1 - k) + (f2 - k) * (f2 - k)) - (c - k);
}

/// The arc blend, union beyond `c_max` (where k(c_max) = c_max).
ISOKIT_HOSTDEV inline OpSample arc_blend(int kind, float tan_theta, float c_max, float f1, float f2) {
  const OpSample u = union_max(f1, f2);
  const float fmax = u.g, fmin = f1 < f2 ? f1 : f2;
  if (fmax >= c_max || fmax <= 0.f) return u;
  float k, dk;
  arc_center(kind, tan_theta, fmax, &k, &dk);
  if (fmin < k) return u;
  // First sign change of the residual on [fmax, c_max], then bisection.
  constexpr int kScan = 64;
  float lo = fmax, hi = -1.f;
  for (int s = 1; s <= kScan; ++s) {
    const float c = fmax + (c_max - fmax) * float(s) / float(kScan);
    if (arc_residual(kind, tan_theta, f1, f2, c) <= 0.f) {
      hi = c;
      break;
    }
    lo = c;
  }
  if (hi < 0.f) return u;  // no arc through the point: union (measure-zero corner region)
  for (int it = 0; it < 40; ++it) {
    const float mid = 0.5f * (lo + hi);
    if (arc_residual(kind, tan_theta, f1, f2, mid) > 0.f)
      lo = mid;
    else
      hi = mid;
  }
  const float c = 0.5f * (lo + hi);
  arc_center(kind, tan_theta, c, &k, &dk);
  const float a = f1 - k, b = f2 - k;
  const float r = hd_sqrt(a * a + b * b);
  if (!(r > 0.f)) return u;
  // G(f1, f2, C) = r - (C - k) = 0  =>  dC/dfi = -G_fi / G_C.
  const float g_c = -(a + b) * dk / r - 1.f + dk;
  if (!(hd_abs(g_c) > 1e-12f)) return u;
  return OpSample{c, -(a / r) / g_c, -(b / r) / g_c};
}

}  // namespace detail

/// Clean union for compact fields: the exact union on the 0.5 level and inside
/// (`max(f1, f2) ≥ 0.5`), with outside iso-curves rounded by arcs of centre `k(C) = 2 C²`
/// (radius `C (1 - 2C)`, largest at C = 0.25, zero at 0 and 0.5). Keeps `g(f, 0) = f`,
/// `g(0, f) = f`, `g(1, f) = 1`. isokit's definition (2014 §4.1 cites Pasko 1995 / Bernhardt 2010
/// for the idea; their formulas are for unbounded fields and break these boundary properties).
ISOKIT_HOSTDEV inline OpSample clean_union(float f1, float f2) {
  return detail::arc_blend(0, 0.f, 0.5f, f1, f2);
}

/// The 2013 paper's gradient-based blend (Appendix A) for blend amount `d ∈ [0, 1]`:
/// `θ = (π/4)(1 - d)` (θ_u = π/4 is the union, θ_b = 0 the full blend). Union beyond 0.7.
/// Interpretation (documented in docs/operators.md): the appendix selects the branch of `k_θ` by
/// `f_i, f_j ≤ 0.5`; isokit selects it by the level `C ≤ 0.5`, which makes `g` continuous (the two
/// branches agree at C = 0.5, `k = 0.5 tan θ`).
ISOKIT_HOSTDEV inline OpSample gradient_blend_2013(float f1, float f2, float d) {
  const float dd = d < 0.f ? 0.f : (d > 1.f ? 1.f : d);
  const float tan_theta = hd_tan(kPiF / 4.f * (1.f - dd));
  return detail::arc_blend(1, tan_theta, 0.7f, f1, f2);
}

}  // namespace isokit::operators
