// SPDX-License-Identifier: MIT
// Procedural meshes and analytic fields for the tracker tests (and the tracker benchmark).
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "isokit/core/math.h"
#include "isokit/implicit/field.h"
#include "isokit/implicit/primitives.h"
#include "isokit/operators/biharmonic.h"
#include "isokit/operators/controller.h"
#include "isokit/operators/grid_operator.h"
#include "isokit/operators/spec.h"
#include "isokit/track/field.h"
#include "isokit/track/mesh.h"

namespace isokit::test {

struct Mesh {
  track::Positions V;
  track::Triangles F;
};

/// Closed capsule around the y axis from y = -half_length to +half_length (a sphere when
/// half_length == 0): `around` vertices per ring, `cylinder_segments` along the cylinder,
/// `cap_rings` rings per hemisphere. Triangles counter-clockwise seen from outside.
inline Mesh capsule_mesh(float radius, float half_length, int around, int cylinder_segments, int cap_rings) {
  struct Ring {
    float y, rho;
  };
  std::vector<Ring> rings;
  for (int k = 1; k < cap_rings; ++k) {
    const float phi = (kPiF / 2) * float(k) / float(cap_rings);
    rings.push_back({-half_length - radius * std::cos(phi), radius * std::sin(phi)});
  }
  const int cs = half_length > 0.f ? cylinder_segments : 0;
  for (int k = 0; k <= cs; ++k)
    rings.push_back({cs == 0 ? 0.f : -half_length + 2.f * half_length * float(k) / float(cs), radius});
  for (int k = cap_rings - 1; k >= 1; --k) {
    const float phi = (kPiF / 2) * float(k) / float(cap_rings);
    rings.push_back({half_length + radius * std::cos(phi), radius * std::sin(phi)});
  }
  const int nr = static_cast<int>(rings.size());
  Mesh m;
  m.V.resize(2 + nr * around, 3);
  m.V.row(0) << 0.f, -half_length - radius, 0.f;
  for (int k = 0; k < nr; ++k)
    for (int a = 0; a < around; ++a) {
      const float t = 2.f * kPiF * float(a) / float(around);
      m.V.row(1 + k * around + a) << rings[k].rho * std::cos(t), rings[k].y, rings[k].rho * std::sin(t);
    }
  const int top = 1 + nr * around;
  m.V.row(top) << 0.f, half_length + radius, 0.f;
  std::vector<int> f;
  auto idx = [&](int k, int a) { return 1 + k * around + (a % around); };
  for (int a = 0; a < around; ++a) f.insert(f.end(), {0, idx(0, a), idx(0, a + 1)});
  for (int k = 0; k + 1 < nr; ++k)
    for (int a = 0; a < around; ++a) {
      f.insert(f.end(), {idx(k, a), idx(k + 1, a), idx(k, a + 1)});
      f.insert(f.end(), {idx(k, a + 1), idx(k + 1, a), idx(k + 1, a + 1)});
    }
  for (int a = 0; a < around; ++a) f.insert(f.end(), {idx(nr - 1, a), top, idx(nr - 1, a + 1)});
  m.F.resize(static_cast<Eigen::Index>(f.size() / 3), 3);
  for (std::size_t i = 0; i < f.size(); ++i)
    m.F(static_cast<Eigen::Index>(i / 3), static_cast<Eigen::Index>(i % 3)) = f[i];
  return m;
}

/// A libimplicit field as a tracker field function.
inline track::FieldFunction as_function(std::shared_ptr<const implicit::Field> field) {
  return [field](const Vec3f* p, std::size_t n, float* v, Vec3f* g, std::uint8_t*) {
    for (std::size_t k = 0; k < n; ++k) {
      const implicit::FieldSample s = field->eval(p[k]);
      v[k] = s.value;
      g[k] = s.gradient;
    }
  };
}

/// Rotation by `angle` radians about the z axis.
inline Mat3f rot_z(float angle) {
  Mat3f r;
  const float c = std::cos(angle), s = std::sin(angle);
  r.m[0] = c, r.m[1] = -s, r.m[3] = s, r.m[4] = c;
  return r;
}

/// Two capsules meeting at the origin (bone 1 along -y, bone 2 along +y rotated by `angle`
/// about z, so its tip swings toward -x: the inner fold is on the -x side), composed by the
/// 2014 contact operator g_dc with the contact controller d(α), α = angle between gradients.
/// Reports contact where d > 0.05 and both operands are ≥ 0.48 (the contact part).
class ElbowField {
 public:
  ElbowField(float radius, float half_length, int operator_resolution)
      : radius_(radius), half_length_(half_length) {
    operators::OperatorSpec spec = operators::preset_spec("contact", operator_resolution);
    spec.slices = 16;
    operators::BiharmonicOptions opt;
    opt.tasks = 1;
    op_ = std::make_shared<operators::GridOperator>(operators::generate_operator(spec, opt));
    controller_ = operators::Controller::preset("contact").table();
    set_angle(0.f);
  }
  void set_angle(float angle) {
    c1_ = implicit::CapsuleParamsT<float>{{0, -half_length_, 0}, {0, 0, 0}, radius_, radius_};
    const Mat3f r = rot_z(angle);
    c2_ = implicit::CapsuleParamsT<float>{{0, 0, 0}, r * Vec3f{0, half_length_, 0}, radius_, radius_};
  }
  track::FieldFunction function() const {
    const auto op = op_;
    const auto ctl = controller_;
    const auto c1 = c1_, c2 = c2_;
    return [op, ctl, c1, c2](const Vec3f* p, std::size_t n, float* v, Vec3f* g, std::uint8_t* contact) {
      for (std::size_t k = 0; k < n; ++k) {
        const implicit::FieldSample a = implicit::eval_capsule(c1, p[k]);
        const implicit::FieldSample b = implicit::eval_capsule(c2, p[k]);
        const float na = norm(a.gradient), nb = norm(b.gradient);
        float alpha = 0.f;
        if (na > 0.f && nb > 0.f)
          alpha = std::acos(std::clamp(dot(a.gradient, b.gradient) / (na * nb), -1.f, 1.f));
        const float d = ctl(alpha);
        const operators::OpSample s = op->eval(a.value, b.value, d);
        v[k] = s.g;
        g[k] = a.gradient * s.dg1 + b.gradient * s.dg2;
        if (contact && d > 0.05f && a.value >= 0.48f && b.value >= 0.48f) contact[k] = 1;
      }
    };
  }

 private:
  float radius_, half_length_;
  std::shared_ptr<operators::GridOperator> op_;
  operators::ControllerTable controller_;
  implicit::CapsuleParamsT<float> c1_, c2_;
};

inline float max_distance(const track::Positions& a, const track::Positions& b) {
  return (a - b).rowwise().norm().maxCoeff();
}

inline float diagonal(const track::Positions& v) {
  return (v.colwise().maxCoeff() - v.colwise().minCoeff()).norm();
}

/// Two-bone limb along y, jointed at the origin about z (the tracker tests' elbow drivers): the
/// rest vertices above y = 0 belong to the upper bone.
struct ZLimb {
  /// Per vertex: the rotation by `angle` about z, blended from 0 below y = -0.3 to 1 above
  /// y = 0.3 (smoothstep), as skinning weights across the joint would.
  static std::vector<Mat3f> rotations(const track::Positions& rest, float angle) {
    std::vector<Mat3f> r(static_cast<std::size_t>(rest.rows()));
    for (Eigen::Index i = 0; i < rest.rows(); ++i) {
      const float t = std::clamp((rest(i, 1) + 0.3f) / 0.6f, 0.f, 1.f);
      r[static_cast<std::size_t>(i)] = rot_z(angle * t * t * (3.f - 2.f * t));
    }
    return r;
  }
  /// Stage 1 of a step: the upper bone's vertices of `P` turn rigidly by `delta` about z.
  static void turn_upper(const track::Positions& rest, float delta, track::Positions& P) {
    const Mat3f d = rot_z(delta);
    for (Eigen::Index i = 0; i < P.rows(); ++i)
      if (rest(i, 1) > 0.f) {
        const Vec3f q = d * Vec3f{P(i, 0), P(i, 1), P(i, 2)};
        P.row(i) << q.x, q.y, q.z;
      }
  }
};

}  // namespace isokit::test
