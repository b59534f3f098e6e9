// SPDX-License-Identifier: MIT
/// \file
/// Per-point field math shared by the CPU evaluators and the CUDA kernels (plain data, inline,
/// `ISOKIT_HOSTDEV`): the field sample, the 2013 remap `t_r`, the sphere and capsule primitives
/// and rigid placement. Templated on the scalar so tests can check the float code against the
/// same formulas in double. Sampled grids: grid_math.h.
///
/// \note Field convention (ARCHITECTURE.md): values in [0, 1], the surface is the 0.5 iso-level,
/// inside > 0.5, gradients point inward, and every field is exactly 0 outside its support.
#pragma once

#include "isokit/core/hostdev.h"
#include "isokit/core/math.h"

namespace isokit::implicit {

/// A field value with its gradient (always evaluated together).
template <class T>
struct FieldSampleT {
  T value{0};
  Vec3T<T> gradient{};
};
using FieldSample = FieldSampleT<float>;

/// The 2013 compact-support remap t_r (Implicit Skinning §4.1):
/// t_r(x) = 1 for x < -r, 0 for x > r, otherwise
/// -3/16 (x/r)^5 + 5/8 (x/r)^3 - 15/16 (x/r) + 1/2.
/// t_r(-r) = 1, t_r(0) = 1/2, t_r(r) = 0; t_r'(±r) = 0 (indeed t_r is C2 there).
/// Returns t_r(x) and writes t_r'(x) = -15/(16 r) (1 - (x/r)^2)^2 to `*derivative`.
template <class T>
ISOKIT_HOSTDEV inline T remap_tr(T x, T r, T* derivative) {
  if (x <= -r) {
    *derivative = T(0);
    return T(1);
  }
  if (x >= r) {
    *derivative = T(0);
    return T(0);
  }
  const T u = x / r;
  const T u2 = u * u;
  const T one_minus = T(1) - u2;
  *derivative = T(-15) / (T(16) * r) * one_minus * one_minus;
  return ((T(-3) / T(16) * u2 + T(5) / T(8)) * u2 - T(15) / T(16)) * u + T(0.5);
}

/// Compact field of a signed distance `dist` (negative inside) whose spatial gradient is
/// `dist_grad`: value t_r(dist) and gradient t_r'(dist) * dist_grad.
template <class T>
ISOKIT_HOSTDEV inline FieldSampleT<T> remap_distance(T dist, const Vec3T<T>& dist_grad, T r) {
  T dt = T(0);
  const T v = remap_tr(dist, r, &dt);
  return {v, dist_grad * dt};
}

/// Sphere of centre `center` and radius `radius`; the field falls from 1 to 0 over a shell of
/// half-width `support_width` around the surface (the `r` of t_r). Support radius:
/// radius + support_width.
template <class T>
struct SphereParamsT {
  Vec3T<T> center{};
  T radius{1};
  T support_width{1};
};

template <class T>
ISOKIT_HOSTDEV inline FieldSampleT<T> eval_sphere(const SphereParamsT<T>& s, const Vec3T<T>& p) {
  const Vec3T<T> d = p - s.center;
  const T len = norm(d);
  // At the centre the distance is not differentiable; t_r' vanishes there whenever
  // support_width <= radius, and the gradient is taken as 0 in any case.
  const Vec3T<T> dir = len > T(0) ? d / len : Vec3T<T>{};
  return remap_distance(len - s.radius, dir, s.support_width);
}

/// Capsule: all points within `radius` of the segment [a, b], remapped like the sphere.
template <class T>
struct CapsuleParamsT {
  Vec3T<T> a{};
  Vec3T<T> b{T(0), T(0), T(1)};
  T radius{T(0.5)};
  T support_width{T(0.5)};
};

/// Closest point to `p` on the segment [a, b] (a == b allowed).
template <class T>
ISOKIT_HOSTDEV inline Vec3T<T> closest_on_segment(const Vec3T<T>& a, const Vec3T<T>& b, const Vec3T<T>& p) {
  const Vec3T<T> ab = b - a;
  const T len2 = squared_norm(ab);
  if (len2 <= T(0)) return a;
  const T s = hd_clamp(dot(p - a, ab) / len2, T(0), T(1));
  return a + ab * s;
}

template <class T>
ISOKIT_HOSTDEV inline FieldSampleT<T> eval_capsule(const CapsuleParamsT<T>& c, const Vec3T<T>& p) {
  const Vec3T<T> d = p - closest_on_segment(c.a, c.b, p);
  const T len = norm(d);
  const Vec3T<T> dir = len > T(0) ? d / len : Vec3T<T>{};
  return remap_distance(len - c.radius, dir, c.support_width);
}

/// Field of a primitive placed by a rigid transform (local -> world): f(T^-1 x), R ∇f.
template <class T, class LocalEval>
ISOKIT_HOSTDEV inline FieldSampleT<T> eval_transformed(const Rigid3T<T>& xf, const Vec3T<T>& p,
                                                       const LocalEval& local) {
  FieldSampleT<T> s = local(xf.apply_inverse(p));
  s.gradient = xf.rotate(s.gradient);
  return s;
}

}  // namespace isokit::implicit
