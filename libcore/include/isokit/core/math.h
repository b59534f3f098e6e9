// SPDX-License-Identifier: MIT
/// \file
/// Plain-data 3D math shared by the CPU code and the CUDA kernels: vectors, boxes, 3x3 matrices
/// and rigid transforms. Templated on the scalar so that tests can run the same formulas in
/// double precision; the hot paths use the `float` aliases.
#pragma once

#include "isokit/core/hostdev.h"

namespace isokit {

/// π, the one definition the project uses (double and float).
inline constexpr double kPi = 3.14159265358979323846;
inline constexpr float kPiF = 3.14159265358979323846f;

template <class T>
struct Vec3T {
  T x{0}, y{0}, z{0};

  ISOKIT_HOSTDEV T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  ISOKIT_HOSTDEV T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  ISOKIT_HOSTDEV Vec3T operator+(const Vec3T& o) const { return {x + o.x, y + o.y, z + o.z}; }
  ISOKIT_HOSTDEV Vec3T operator-(const Vec3T& o) const { return {x - o.x, y - o.y, z - o.z}; }
  ISOKIT_HOSTDEV Vec3T operator-() const { return {-x, -y, -z}; }
  ISOKIT_HOSTDEV Vec3T operator*(T s) const { return {x * s, y * s, z * s}; }
  ISOKIT_HOSTDEV Vec3T operator/(T s) const { return {x / s, y / s, z / s}; }
  ISOKIT_HOSTDEV Vec3T& operator+=(const Vec3T& o) {
    x += o.x;
    y += o.y;
    z += o.z;
    return *this;
  }
  ISOKIT_HOSTDEV bool operator==(const Vec3T& o) const { return x == o.x && y == o.y && z == o.z; }
  ISOKIT_HOSTDEV bool operator!=(const Vec3T& o) const { return !(*this == o); }
};

template <class T>
ISOKIT_HOSTDEV inline Vec3T<T> operator*(T s, const Vec3T<T>& v) {
  return v * s;
}
template <class T>
ISOKIT_HOSTDEV inline T dot(const Vec3T<T>& a, const Vec3T<T>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <class T>
ISOKIT_HOSTDEV inline Vec3T<T> cross(const Vec3T<T>& a, const Vec3T<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class T>
ISOKIT_HOSTDEV inline T squared_norm(const Vec3T<T>& a) {
  return dot(a, a);
}
template <class T>
ISOKIT_HOSTDEV inline T norm(const Vec3T<T>& a) {
  return hd_sqrt(dot(a, a));
}

/// Axis-aligned box; empty when any `hi < lo`. A default-constructed box is empty.
template <class T>
struct Box3T {
  Vec3T<T> lo{T(1), T(1), T(1)};
  Vec3T<T> hi{T(0), T(0), T(0)};

  ISOKIT_HOSTDEV bool empty() const { return hi.x < lo.x || hi.y < lo.y || hi.z < lo.z; }
  ISOKIT_HOSTDEV bool contains(const Vec3T<T>& p) const {
    return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
  }
  ISOKIT_HOSTDEV bool contains(const Box3T& b) const {
    return b.empty() || (contains(b.lo) && contains(b.hi));
  }
  ISOKIT_HOSTDEV void extend(const Vec3T<T>& p) {
    if (empty()) {
      lo = hi = p;
      return;
    }
    lo = {hd_min(lo.x, p.x), hd_min(lo.y, p.y), hd_min(lo.z, p.z)};
    hi = {hd_max(hi.x, p.x), hd_max(hi.y, p.y), hd_max(hi.z, p.z)};
  }
  ISOKIT_HOSTDEV Vec3T<T> size() const { return hi - lo; }
};

/// Row-major 3x3 matrix.
template <class T>
struct Mat3T {
  T m[9]{T(1), T(0), T(0), T(0), T(1), T(0), T(0), T(0), T(1)};

  ISOKIT_HOSTDEV T operator()(int r, int c) const { return m[3 * r + c]; }
  ISOKIT_HOSTDEV T& operator()(int r, int c) { return m[3 * r + c]; }
  ISOKIT_HOSTDEV Vec3T<T> operator*(const Vec3T<T>& v) const {
    return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[3] * v.x + m[4] * v.y + m[5] * v.z,
            m[6] * v.x + m[7] * v.y + m[8] * v.z};
  }
  /// `transpose() * v` without forming the transpose.
  ISOKIT_HOSTDEV Vec3T<T> transpose_mul(const Vec3T<T>& v) const {
    return {m[0] * v.x + m[3] * v.y + m[6] * v.z, m[1] * v.x + m[4] * v.y + m[7] * v.z,
            m[2] * v.x + m[5] * v.y + m[8] * v.z};
  }
  ISOKIT_HOSTDEV Mat3T operator*(const Mat3T& o) const {
    Mat3T r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        r.m[3 * i + j] = m[3 * i] * o.m[j] + m[3 * i + 1] * o.m[3 + j] + m[3 * i + 2] * o.m[6 + j];
    return r;
  }
  ISOKIT_HOSTDEV Mat3T transpose() const {
    Mat3T r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r.m[3 * i + j] = m[3 * j + i];
    return r;
  }
};

/// Rigid transform `x -> R x + t` (R a rotation). Maps a primitive's local frame to the world.
template <class T>
struct Rigid3T {
  Mat3T<T> R{};
  Vec3T<T> t{};

  ISOKIT_HOSTDEV Vec3T<T> apply(const Vec3T<T>& p) const { return R * p + t; }
  ISOKIT_HOSTDEV Vec3T<T> apply_inverse(const Vec3T<T>& p) const { return R.transpose_mul(p - t); }
  ISOKIT_HOSTDEV Vec3T<T> rotate(const Vec3T<T>& v) const { return R * v; }
  ISOKIT_HOSTDEV Vec3T<T> rotate_inverse(const Vec3T<T>& v) const { return R.transpose_mul(v); }
  ISOKIT_HOSTDEV Rigid3T operator*(const Rigid3T& o) const { return {R * o.R, R * o.t + t}; }
};

using Vec3f = Vec3T<float>;
using Vec3d = Vec3T<double>;
using Box3f = Box3T<float>;
using Box3d = Box3T<double>;
using Mat3f = Mat3T<float>;
using Rigid3f = Rigid3T<float>;
using Rigid3d = Rigid3T<double>;

}  // namespace isokit
