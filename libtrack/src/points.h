// SPDX-License-Identifier: MIT
// Point buffers: the tracker and the projector work on flat `std::vector<Vec3f>` copies of the
// caller's `Positions` (not installed).
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "isokit/core/math.h"
#include "isokit/track/mesh.h"

namespace isokit::track::detail {

inline bool finite(const Vec3f& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

inline Vec3f row(const Positions& p, Eigen::Index i) {
  return {p(i, 0), p(i, 1), p(i, 2)};
}

/// Copies rows into a flat vector (throws InputError naming `what` and the vertex on NaN/inf).
std::vector<Vec3f> to_points(const Positions& p, const std::string& what);
void from_points(const std::vector<Vec3f>& pts, Positions& p);

/// `out[k] = v[order[k]]`.
template <class T>
std::vector<T> permuted(const std::vector<T>& v, const std::vector<int>& order) {
  std::vector<T> out(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) out[k] = v[std::size_t(order[k])];
  return out;
}

}  // namespace isokit::track::detail
