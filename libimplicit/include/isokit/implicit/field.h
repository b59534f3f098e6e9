// SPDX-License-Identifier: MIT
/// \file
/// The field interface every 3D field in isokit implements: value and gradient together, batch
/// evaluation over many points, and a support box outside which the field is exactly 0.
///
/// \note Convention: values in [0, 1], surface at 0.5, inside > 0.5, gradients point inward,
/// compact support (exactly 0, with a 0 gradient, outside `support()`).
#pragma once

#include <cstddef>
#include <memory>

#include <Eigen/Core>

#include "isokit/core/math.h"
#include "isokit/core/parallel.h"
#include "isokit/implicit/field_math.h"

namespace isokit::implicit {

/// `#P by 3` row-major float points (memory layout: x0 y0 z0 x1 y1 z1 ...).
using Points = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// A scalar field with compact support. Implementations are immutable after construction and
/// safe to evaluate from many threads at once.
class Field {
 public:
  virtual ~Field() = default;

  /// Value and gradient at `p`.
  virtual FieldSample eval(const Vec3f& p) const = 0;

  /// Bounding box of the support: the field is exactly 0 outside.
  virtual Box3f support() const = 0;

  /// Evaluates `n` points into `out` (same length), in parallel with the given grain size
  /// (0 = serial). Results do not depend on the grain size. The default loops over `eval`.
  virtual void eval_batch(const Vec3f* points, std::size_t n, FieldSample* out,
                          std::size_t grain = kDefaultGrain) const;

  /// Eigen convenience: `values` (#P) and `gradients` (#P by 3) are resized.
  void eval_batch(const Points& points, Eigen::VectorXf& values, Points& gradients,
                  std::size_t grain = kDefaultGrain) const;
};

using FieldPtr = std::shared_ptr<const Field>;

/// Another field placed by a rigid transform (local frame -> world): `f(T^-1 x)`, `R ∇f`.
/// \throw InputError if the transform is not finite or `R` is not a rotation (tolerance 1e-4).
class TransformedField final : public Field {
 public:
  TransformedField(FieldPtr local, const Rigid3f& local_to_world);

  FieldSample eval(const Vec3f& p) const override;
  Box3f support() const override;  ///< World box of the transformed local support box.

  const Rigid3f& transform() const { return xf_; }
  /// A copy with another transform (the local field is shared, nothing is rebuilt).
  TransformedField with_transform(const Rigid3f& local_to_world) const;

 private:
  FieldPtr local_;
  Rigid3f xf_;
};

/// Checks that `xf` is finite and `xf.R` is a rotation (orthonormal, det +1, to 1e-4).
/// \throw InputError naming `what` otherwise.
void validate_rigid(const Rigid3f& xf, const char* what);

/// World-space AABB of a box moved by a rigid transform.
Box3f transform_box(const Box3f& local, const Rigid3f& xf);

}  // namespace isokit::implicit
