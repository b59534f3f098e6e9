// SPDX-License-Identifier: MIT
// A small two-bone capsule rig built in the test (independent of the procedural module): a
// closed tube of radius 0.25 along +y from 0 to 2 with hemispherical caps, joints "Root" at y=0
// and "Bone1" at y=1, weights a smoothstep across the joint.
#pragma once

#include <cmath>

#include "isokit/core/math.h"
#include "isokit/skinning/rig.h"

namespace isokit::skinning::testing {

inline Rig capsule_rig(int rings = 40, int segments = 24, int cap_rings = 6) {
  const double R = 0.25, L = 2.0;
  Rig r;
  r.name = "test:capsule";
  std::vector<Eigen::Vector3d> v;
  // Profile: bottom pole, cap rings, tube rings, cap rings, top pole.
  std::vector<std::pair<double, double>> prof;  // (y, radius)
  for (int k = 1; k <= cap_rings; ++k) {
    const double a = -kPi / 2 + kPi / 2 * k / (cap_rings + 1.0);
    prof.push_back({R * std::sin(a), R * std::cos(a)});
  }
  for (int k = 0; k <= rings; ++k) prof.push_back({L * k / rings, R});
  for (int k = cap_rings; k >= 1; --k) {
    const double a = -kPi / 2 + kPi / 2 * k / (cap_rings + 1.0);
    prof.push_back({L - R * std::sin(a), R * std::cos(a)});
  }
  v.push_back({0, -R, 0});
  for (auto [y, rad] : prof)
    for (int s = 0; s < segments; ++s) {
      const double t = 2 * kPi * (s + 0.5 * (&prof.front() - &prof.front())) / segments;
      v.push_back({rad * std::cos(t), y, -rad * std::sin(t)});
    }
  v.push_back({0, L + R, 0});
  const int nr = static_cast<int>(prof.size());
  std::vector<std::array<int, 3>> t;
  for (int s = 0; s < segments; ++s) t.push_back({0, 1 + (s + 1) % segments, 1 + s});
  for (int k = 0; k + 1 < nr; ++k)
    for (int s = 0; s < segments; ++s) {
      const int a = 1 + k * segments + s, b = 1 + k * segments + (s + 1) % segments;
      t.push_back({a, b, b + segments});
      t.push_back({a, b + segments, a + segments});
    }
  const int top = static_cast<int>(v.size()) - 1, last = 1 + (nr - 1) * segments;
  for (int s = 0; s < segments; ++s) t.push_back({top, last + s, last + (s + 1) % segments});
  r.rest.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i)
    r.rest.row(static_cast<Eigen::Index>(i)) = v[i].cast<float>().transpose();
  r.triangles.resize(static_cast<Eigen::Index>(t.size()), 3);
  for (std::size_t i = 0; i < t.size(); ++i)
    r.triangles.row(static_cast<Eigen::Index>(i)) << t[i][0], t[i][1], t[i][2];
  Joint root{"Root", -1, Affine::Identity(), Affine::Identity()};
  Joint b1{"Bone1", 0, Affine(Eigen::Translation3d(0, 1, 0)), Affine(Eigen::Translation3d(0, -1, 0))};
  r.joints = {root, b1};
  r.weights.offsets.push_back(0);
  for (const auto& p : v) {
    const double x = std::clamp((p.y() - 0.8) / 0.4, 0.0, 1.0), w1 = x * x * (3 - 2 * x);
    if (w1 < 1) {
      r.weights.joints.push_back(0);
      r.weights.weights.push_back(static_cast<float>(1 - w1));
    }
    if (w1 > 0) {
      r.weights.joints.push_back(1);
      r.weights.weights.push_back(static_cast<float>(w1));
    }
    r.weights.offsets.push_back(static_cast<int>(r.weights.joints.size()));
  }
  return r;
}

/// `r` with one clip named `name`: Bone1 (joint 1) turned by `step` radians more about z at each
/// of `frames` frames.
inline Rig with_turn_clip(Rig r, int frames, double step, const std::string& name = "animation_0") {
  Clip clip{name, 30, {}, nullptr};
  for (int f = 0; f < frames; ++f) {
    std::vector<Affine> pose = rest_pose(r);
    pose[1] = pose[1] * Affine(Eigen::AngleAxisd(step * f, Eigen::Vector3d::UnitZ()));
    clip.local.push_back(pose);
  }
  r.clips = {clip};
  return r;
}

}  // namespace isokit::skinning::testing
