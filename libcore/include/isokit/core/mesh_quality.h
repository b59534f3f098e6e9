// SPDX-License-Identifier: MIT
/// \file
/// Mesh-quality primitives shared by the tracker (float, on its hot path) and the skinning
/// metrics (QUALITY.md): the triangle normal, the inverted-triangle test and the bounding-box
/// diagonal. Templated on the scalar so that each caller keeps its own precision; every function
/// is one fixed sequence of operations, so a caller gets the same bits as the formula written out.
///
/// \note Field convention: inside > 0.5, gradients point inward, triangles counter-clockwise seen
/// from outside — a correct triangle's normal points along `-∇f`.
#pragma once

#include <cstddef>

#include "isokit/core/math.h"

namespace isokit {

/// The (unnormalised) normal `(b - a) x (c - a)` of the triangle (a, b, c): outward for a
/// counter-clockwise triangle seen from outside; twice the area long.
template <class T>
ISOKIT_HOSTDEV inline Vec3T<T> triangle_normal(const Vec3T<T>& a, const Vec3T<T>& b, const Vec3T<T>& c) {
  return cross(b - a, c - a);
}

/// The centroid `(a + b + c) / 3`, where the inverted-triangle test evaluates the field.
template <class T>
ISOKIT_HOSTDEV inline Vec3T<T> triangle_centroid(const Vec3T<T>& a, const Vec3T<T>& b, const Vec3T<T>& c) {
  return (a + b + c) / T(3);
}

/// QUALITY.md's inverted triangle: its `normal` points along `+∇f` (`gradient`, taken at the
/// centroid), i.e. `normal · gradient > 0`. A zero gradient (outside the field's support) is not
/// inverted.
template <class T>
ISOKIT_HOSTDEV inline bool is_inverted(const Vec3T<T>& normal, const Vec3T<T>& gradient) {
  return dot(normal, gradient) > T(0);
}

/// Length of the diagonal of a box; 0 for an empty box.
template <class T>
ISOKIT_HOSTDEV inline T box_diagonal(const Box3T<T>& box) {
  return box.empty() ? T(0) : norm(box.size());
}

/// Length of the diagonal of the bounding box of `count` points given by `point(k)` (a callable
/// returning `Vec3T<T>`, for points stored in any layout); 0 without points.
template <class T, class PointAt>
T bbox_diagonal(std::size_t count, PointAt&& point) {
  Box3T<T> box;
  for (std::size_t k = 0; k < count; ++k) box.extend(point(k));
  return box_diagonal(box);
}

/// Length of the diagonal of the bounding box of `points[0, count)`; 0 without points.
template <class T>
T bbox_diagonal(const Vec3T<T>* points, std::size_t count) {
  return bbox_diagonal<T>(count, [points](std::size_t k) { return points[k]; });
}

}  // namespace isokit
