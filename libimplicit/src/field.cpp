// SPDX-License-Identifier: MIT
#include "isokit/implicit/field.h"

#include <cmath>
#include <string>
#include <utility>

#include "isokit/core/error.h"

namespace isokit::implicit {

void Field::eval_batch(const Vec3f* points, std::size_t n, FieldSample* out, std::size_t grain) const {
  parallel_for(n, grain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) out[i] = eval(points[i]);
  });
}

void Field::eval_batch(const Points& points, Eigen::VectorXf& values, Points& gradients,
                       std::size_t grain) const {
  const auto n = static_cast<std::size_t>(points.rows());
  values.resize(points.rows());
  gradients.resize(points.rows(), 3);
  const auto* p = reinterpret_cast<const Vec3f*>(points.data());
  parallel_for(n, grain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const FieldSample s = eval(p[i]);
      values[static_cast<Eigen::Index>(i)] = s.value;
      gradients.row(static_cast<Eigen::Index>(i)) << s.gradient.x, s.gradient.y, s.gradient.z;
    }
  });
}

void validate_rigid(const Rigid3f& xf, const char* what) {
  bool finite = true;
  for (float v : xf.R.m) finite = finite && std::isfinite(v);
  for (int i = 0; i < 3; ++i) finite = finite && std::isfinite(xf.t[i]);
  require(finite, what, "transform has non-finite entries", "pass a finite rotation and translation");
  const Mat3f rtr = xf.R.transpose() * xf.R;
  float err = 0.f;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) err = std::max(err, std::abs(rtr(i, j) - (i == j ? 1.f : 0.f)));
  const Vec3f c0{xf.R(0, 0), xf.R(1, 0), xf.R(2, 0)}, c1{xf.R(0, 1), xf.R(1, 1), xf.R(2, 1)},
      c2{xf.R(0, 2), xf.R(1, 2), xf.R(2, 2)};
  const float det = dot(cross(c0, c1), c2);
  require(
      err <= 1e-4f && det > 0.f, what,
      "transform is not rigid (|R^T R - I| = " + format_number(err) + ", det R = " + format_number(det) + ")",
      "use an orthonormal rotation matrix with determinant +1 (no scale, no mirror)");
}

Box3f transform_box(const Box3f& local, const Rigid3f& xf) {
  Box3f out;
  if (local.empty()) return out;
  for (int c = 0; c < 8; ++c) {
    const Vec3f corner{(c & 1) ? local.hi.x : local.lo.x, (c & 2) ? local.hi.y : local.lo.y,
                       (c & 4) ? local.hi.z : local.lo.z};
    out.extend(xf.apply(corner));
  }
  return out;
}

TransformedField::TransformedField(FieldPtr local, const Rigid3f& local_to_world)
    : local_(std::move(local)), xf_(local_to_world) {
  require(local_ != nullptr, "TransformedField", "local field is null", "pass a field");
  validate_rigid(xf_, "TransformedField transform");
}

FieldSample TransformedField::eval(const Vec3f& p) const {
  return eval_transformed(xf_, p, [this](const Vec3f& q) { return local_->eval(q); });
}

Box3f TransformedField::support() const {
  return transform_box(local_->support(), xf_);
}

TransformedField TransformedField::with_transform(const Rigid3f& local_to_world) const {
  return TransformedField(local_, local_to_world);
}

}  // namespace isokit::implicit
