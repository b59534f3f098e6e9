// SPDX-License-Identifier: MIT
/// \file
/// Analytic compact-support primitives: signed distance to a sphere or a capsule (segment),
/// remapped by the 2013 `t_r` (Implicit Skinning §4.1) so that the field is 1 deep inside,
/// 0.5 on the surface, and exactly 0 beyond `support_width` outside the surface.
/// Place them anywhere with `TransformedField`.
///
/// \note Inside > 0.5; gradient points inward; support box = shape grown by `support_width`.
#pragma once

#include "isokit/implicit/field.h"

namespace isokit::implicit {

/// \throw InputError if the centre is not finite, or radius / support_width are not finite
/// and > 0.
class SphereField final : public Field {
 public:
  /// `support_width` is the `r` of t_r; the default (0 -> `radius`) makes the field reach 1
  /// exactly at the centre only, as the 2013 paper sets r for HRBF parts.
  SphereField(const Vec3f& center, float radius, float support_width = 0.f);

  FieldSample eval(const Vec3f& p) const override { return eval_sphere(params_, p); }
  Box3f support() const override;
  const SphereParamsT<float>& params() const { return params_; }

 private:
  SphereParamsT<float> params_;
};

/// Capsule around the segment [a, b] (a == b gives a sphere).
/// \throw InputError if endpoints are not finite, or radius / support_width are not finite
/// and > 0.
class CapsuleField final : public Field {
 public:
  /// `support_width` 0 -> `radius` (field 1 on the segment only).
  CapsuleField(const Vec3f& a, const Vec3f& b, float radius, float support_width = 0.f);

  FieldSample eval(const Vec3f& p) const override { return eval_capsule(params_, p); }
  Box3f support() const override;
  const CapsuleParamsT<float>& params() const { return params_; }

 private:
  CapsuleParamsT<float> params_;
};

}  // namespace isokit::implicit
