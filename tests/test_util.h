// SPDX-License-Identifier: MIT
// Shared helpers for the property tests: seeded random inputs and finite differences.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

#include "isokit/core/math.h"

namespace isokit::test {

/// Deterministic random source for property tests (fixed seed per test case).
class Rng {
 public:
  explicit Rng(std::uint32_t seed) : gen_(seed) {}
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(gen_); }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(gen_); }
  Vec3d vec(double lo, double hi) { return {uniform(lo, hi), uniform(lo, hi), uniform(lo, hi)}; }
  Vec3d unit() {
    for (;;) {
      const Vec3d v = vec(-1, 1);
      const double n = norm(v);
      if (n > 0.1 && n <= 1) return v / n;
    }
  }
  /// Uniformly random rotation (normalised random quaternion).
  Mat3T<double> rotation() {
    std::normal_distribution<double> g;
    double w = g(gen_), x = g(gen_), y = g(gen_), z = g(gen_);
    const double n = std::sqrt(w * w + x * x + y * y + z * z);
    w /= n, x /= n, y /= n, z /= n;
    Mat3T<double> r;
    r.m[0] = 1 - 2 * (y * y + z * z), r.m[1] = 2 * (x * y - w * z), r.m[2] = 2 * (x * z + w * y);
    r.m[3] = 2 * (x * y + w * z), r.m[4] = 1 - 2 * (x * x + z * z), r.m[5] = 2 * (y * z - w * x);
    r.m[6] = 2 * (x * z - w * y), r.m[7] = 2 * (y * z + w * x), r.m[8] = 1 - 2 * (x * x + y * y);
    return r;
  }

 private:
  std::mt19937 gen_;
};

inline Vec3f to_float(const Vec3d& v) {
  return {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)};
}
inline Vec3d to_double(const Vec3f& v) {
  return {v.x, v.y, v.z};
}

/// Central-difference gradient of a scalar function of a point.
template <class F>
Vec3d central_gradient(const F& f, const Vec3d& p, double h) {
  Vec3d g;
  for (int a = 0; a < 3; ++a) {
    Vec3d lo = p, hi = p;
    lo[a] -= h;
    hi[a] += h;
    g[a] = (f(hi) - f(lo)) / (2 * h);
  }
  return g;
}

}  // namespace isokit::test
