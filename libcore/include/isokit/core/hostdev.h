// SPDX-License-Identifier: MIT
/// \file
/// Host/device portability: `ISOKIT_HOSTDEV` marks functions that compile both for the CPU and,
/// under nvcc, for CUDA devices. Headers using it hold plain data and inline math only.
#pragma once

#if defined(__CUDACC__)
#define ISOKIT_HOSTDEV __host__ __device__
#else
#define ISOKIT_HOSTDEV
#endif

#include <math.h>

namespace isokit {

/// Math that resolves to the C functions nvcc provides on the device (the std:: overloads are
/// constexpr host functions in libstdc++, which device code may not call).
ISOKIT_HOSTDEV inline float hd_sqrt(float x) {
  return ::sqrtf(x);
}
ISOKIT_HOSTDEV inline double hd_sqrt(double x) {
  return ::sqrt(x);
}
ISOKIT_HOSTDEV inline float hd_tan(float x) {
  return ::tanf(x);
}
ISOKIT_HOSTDEV inline float hd_abs(float x) {
  return ::fabsf(x);
}
ISOKIT_HOSTDEV inline double hd_abs(double x) {
  return ::fabs(x);
}

template <class T>
ISOKIT_HOSTDEV inline T hd_min(T a, T b) {
  return b < a ? b : a;
}
template <class T>
ISOKIT_HOSTDEV inline T hd_max(T a, T b) {
  return a < b ? b : a;
}
template <class T>
ISOKIT_HOSTDEV inline T hd_clamp(T x, T lo, T hi) {
  return hd_min(hd_max(x, lo), hi);
}

}  // namespace isokit
