// SPDX-License-Identifier: MIT
/// \file
/// Hermite RBF primitives (2013 §4.1): a distance-like function
/// `d(x) = Σ λk φ(|x − vk|) + βk·∇φ(x − vk) + a·x + b`, `φ(r) = r³`, fitted to points `vk` with
/// unit normals `nk` by solving `d(vk) = 0`, `∇d(vk) = nk` (plus the orthogonality conditions
/// `Σ λk = 0`, `Σ λk vk − βk = 0` of the affine part, Macêdo et al. 2011), in double precision.
/// `HrbfField` turns it into a compact field `t_r(d)`.
///
/// \note Field convention: values in [0, 1], inside > 0.5 (d < 0 inside since the normals point
/// outward), gradients point inward, exactly 0 outside `support()`.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "isokit/core/math.h"
#include "isokit/implicit/field.h"

namespace isokit::implicit {

/// A point with its outward unit normal.
struct HrbfSample {
  Vec3d position{};
  Vec3d normal{};
};

/// Safeguards of the fit (none is in the papers, which assume clean samples).
struct HrbfOptions {
  /// Samples closer than `merge_distance` × (sample bounding-box diagonal) are merged into one
  /// (mean position, normalised mean normal); >= 0, default 1e-3. Normals that cancel when
  /// merged throw.
  double merge_distance = 1e-3;
  /// Fits whose estimated reciprocal condition number (1-norm, LU) is below this throw.
  /// Default 1e-13.
  double min_rcond = 1e-13;
  /// Fits whose interpolation residual (value, or gradient minus normal; relative to the
  /// bounding-box diagonal / to 1) exceeds this throw: never a silent garbage field. Default 1e-6.
  double max_residual = 1e-6;
};

/// Partial sums in the HRBF evaluation (see eval_hrbf_distance).
inline constexpr int kHrbfLanes = 8;

/// Plain-data view of a fitted HRBF in its normalised frame (`y = (x − center) / scale`):
/// `d(x) = scale · dn(y)`, `∇d(x) = ∇dn(y)`. Arrays hold `m` entries each (struct of arrays; `m`
/// a multiple of `kHrbfLanes`, padded with zero coefficients, which add exactly 0).
template <class T>
struct HrbfViewT {
  const T* cx{nullptr};
  const T* cy{nullptr};
  const T* cz{nullptr};
  const T* lambda{nullptr};
  const T* bx{nullptr};
  const T* by{nullptr};
  const T* bz{nullptr};
  int m{0};
  T affine[4]{};  ///< a (3), b
  Vec3T<T> center{};
  T scale{1};
};

/// `d(x)` and `∇d(x)` (not remapped). Host/device, no allocation. The sum runs in
/// `kHrbfLanes` interleaved partial sums (branch-free, so the host compiler vectorises it);
/// the order is fixed, so results are deterministic.
template <class T>
ISOKIT_HOSTDEV inline FieldSampleT<T> eval_hrbf_distance(const HrbfViewT<T>& h, const Vec3T<T>& x) {
  const Vec3T<T> y = (x - h.center) / h.scale;
  T v[kHrbfLanes], gx[kHrbfLanes], gy[kHrbfLanes], gz[kHrbfLanes];
  for (int l = 0; l < kHrbfLanes; ++l) v[l] = gx[l] = gy[l] = gz[l] = T(0);
  // Tiny offset so that u = 0 (x on a centre) gives q = 0 without a branch (bu = 0 there).
  const T tiny = sizeof(T) == 4 ? T(1e-30) : T(1e-200);
  for (int k0 = 0; k0 < h.m; k0 += kHrbfLanes) {
    for (int l = 0; l < kHrbfLanes; ++l) {
      const int k = k0 + l;
      const T ux = y.x - h.cx[k], uy = y.y - h.cy[k], uz = y.z - h.cz[k];
      const T r2 = ux * ux + uy * uy + uz * uz;
      const T r = hd_sqrt(r2);
      const T bu = h.bx[k] * ux + h.by[k] * uy + h.bz[k] * uz;
      // φ = r³, ∇φ = 3 r u, Hφ = 3 (r I + u uᵀ / r) (0 at r = 0).
      v[l] += h.lambda[k] * r2 * r + T(3) * r * bu;
      const T s = T(3) * h.lambda[k] * r;
      const T q = T(3) * bu * r / (r2 + tiny);
      gx[l] += (s + q) * ux + T(3) * r * h.bx[k];
      gy[l] += (s + q) * uy + T(3) * r * h.by[k];
      gz[l] += (s + q) * uz + T(3) * r * h.bz[k];
    }
  }
  T sv = h.affine[0] * y.x + h.affine[1] * y.y + h.affine[2] * y.z + h.affine[3];
  T sx = h.affine[0], sy = h.affine[1], sz = h.affine[2];
  for (int l = 0; l < kHrbfLanes; ++l) sv += v[l], sx += gx[l], sy += gy[l], sz += gz[l];
  return {sv * h.scale, {sx, sy, sz}};
}

/// A fitted HRBF (coefficients in double and float). Immutable.
class Hrbf {
 public:
  /// Fits the samples. \throw InputError (naming `name`) for fewer than 4 samples after merging,
  /// non-finite positions, zero-length normals, cancelling merged normals, an ill-conditioned
  /// system or an interpolation residual above `options.max_residual`.
  explicit Hrbf(const std::vector<HrbfSample>& samples, const HrbfOptions& options = {},
                const std::string& name = "HRBF");

  FieldSampleT<double> distance(const Vec3d& x) const { return eval_hrbf_distance(view_d(), x); }
  FieldSample distance(const Vec3f& x) const { return eval_hrbf_distance(view_f(), x); }

  /// The samples actually interpolated (after merging).
  const std::vector<HrbfSample>& samples() const { return samples_; }
  double rcond() const { return rcond_; }
  /// Largest interpolation residual measured after the solve.
  double residual() const { return residual_; }

  HrbfViewT<double> view_d() const;
  HrbfViewT<float> view_f() const;

 private:
  /// The solution `x` (4m + 4: λk, βk per sample, then the affine part) at the normalised
  /// positions `y`, as padded arrays in double and float.
  void store_coefficients(const std::vector<Vec3d>& y, const double* x);

  std::vector<HrbfSample> samples_;
  std::vector<double> d_;  // 7 m: cx cy cz lambda bx by bz
  std::vector<float> f_;
  double affine_[4]{};
  Vec3d center_{};
  double scale_{1};
  double rcond_{0}, residual_{0};
};

/// Compact field `t_r(d(x))` of an HRBF, exactly 0 outside `support_box`.
/// \throw InputError if `r` is not positive and finite, the box is empty, or `d < r` is found on
/// the faces of the box (a 16² lattice per face): the box would cut the field.
class HrbfField final : public Field {
 public:
  HrbfField(std::shared_ptr<const Hrbf> hrbf, double r, const Box3f& support_box);

  FieldSample eval(const Vec3f& p) const override;
  Box3f support() const override { return box_; }
  FieldSampleT<double> eval_d(const Vec3d& p) const;  ///< double precision, for tests and fitting
  const Hrbf& hrbf() const { return *hrbf_; }
  double r() const { return r_; }

 private:
  std::shared_ptr<const Hrbf> hrbf_;
  HrbfViewT<float> view_;
  double r_;
  Box3f box_;
};

}  // namespace isokit::implicit
