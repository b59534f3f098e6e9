// SPDX-License-Identifier: MIT
#include "isokit/skinning/deform.h"

#include <cmath>

#include "isokit/core/error.h"
#include "isokit/core/parallel.h"
#include "isokit/core/rotation_fit.h"

namespace isokit::skinning {

Affine rigid_part(const Affine& a) {
  Affine r = Affine::Identity();
  r.linear() = procrustes_rotation(a.linear());
  r.translation() = a.translation();
  return r;
}

Eigen::Matrix3d stretch_part(const Affine& a) {
  return rigid_part(a).linear().transpose() * a.linear();
}

Rigid3f to_rigid3f(const Affine& a) {
  const Affine r = rigid_part(a);
  Rigid3f x;
  for (int i = 0; i < 3; ++i) {
    for (int c = 0; c < 3; ++c) x.R.m[i * 3 + c] = static_cast<float>(r.linear()(i, c));
  }
  x.t = {static_cast<float>(r.translation().x()), static_cast<float>(r.translation().y()),
         static_cast<float>(r.translation().z())};
  return x;
}

Affine to_affine(const Rigid3d& x) {
  Affine a = Affine::Identity();
  for (int i = 0; i < 3; ++i)
    for (int c = 0; c < 3; ++c) a.linear()(i, c) = x.R.m[i * 3 + c];
  a.translation() = Eigen::Vector3d(x.t.x, x.t.y, x.t.z);
  return a;
}

double rotation_angle(const Affine& a) {
  const Eigen::AngleAxisd aa(Eigen::Matrix3d(rigid_part(a).linear()));
  return std::abs(aa.angle());
}

namespace {

void check_sizes(const SkinWeights& w, const std::vector<Affine>& skin, const track::Positions& rest) {
  require(!w.empty() && static_cast<Eigen::Index>(w.offsets.size()) == rest.rows() + 1, "skinning weights",
          "need one entry per vertex", "compute or load weights for this mesh");
  for (int j : w.joints)
    require(j >= 0 && j < static_cast<int>(skin.size()), "skinning weights", "joint index out of range",
            "pass one skinning matrix per joint");
}

struct Dq {
  Eigen::Vector4d r;  // (w, x, y, z) real part
  Eigen::Vector4d d;  // dual part
};

Eigen::Vector4d qmul(const Eigen::Vector4d& a, const Eigen::Vector4d& b) {
  return {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
          a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
          a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
          a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
}

Dq to_dq(const Affine& a) {
  const Affine r = rigid_part(a);
  const Eigen::Quaterniond q(Eigen::Matrix3d(r.linear()));
  Dq out;
  out.r = {q.w(), q.x(), q.y(), q.z()};
  const Eigen::Vector3d t = r.translation();
  out.d = 0.5 * qmul({0, t.x(), t.y(), t.z()}, out.r);
  return out;
}

}  // namespace

void linear_blend(const SkinWeights& w, const std::vector<Affine>& skin, const track::Positions& rest,
                  track::Positions& out, std::size_t grain) {
  check_sizes(w, skin, rest);
  out.resize(rest.rows(), 3);
  std::vector<Eigen::Matrix<double, 3, 4>> m(skin.size());
  for (std::size_t j = 0; j < skin.size(); ++j) m[j] = skin[j].matrix().topRows<3>();
  parallel_for(static_cast<std::size_t>(rest.rows()), grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v) {
      const Eigen::Vector4d p(rest(v, 0), rest(v, 1), rest(v, 2), 1.0);
      Eigen::Vector3d q = Eigen::Vector3d::Zero();
      for (int k = w.offsets[v]; k < w.offsets[v + 1]; ++k) q += double(w.weights[k]) * (m[w.joints[k]] * p);
      out.row(static_cast<Eigen::Index>(v)) = q.cast<float>().transpose();
    }
  });
}

void dual_quaternion_blend(const SkinWeights& w, const std::vector<Affine>& skin,
                           const track::Positions& rest, track::Positions& out, std::vector<Mat3f>* rotations,
                           std::size_t grain) {
  check_sizes(w, skin, rest);
  out.resize(rest.rows(), 3);
  if (rotations) rotations->resize(static_cast<std::size_t>(rest.rows()));
  std::vector<Dq> dq(skin.size());
  for (std::size_t j = 0; j < skin.size(); ++j) dq[j] = to_dq(skin[j]);
  // The stretches (scale keys), kept only when some matrix has one.
  std::vector<Eigen::Matrix3d> stretch(skin.size());
  bool stretched = false;
  for (std::size_t j = 0; j < skin.size(); ++j) {
    stretch[j] = stretch_part(skin[j]);
    stretched =
        stretched || (stretch[j] - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > kStretchTolerance;
  }
  parallel_for(static_cast<std::size_t>(rest.rows()), grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v) {
      // Pivot: the largest weight (antipodality reference).
      int pivot = w.offsets[v];
      for (int k = w.offsets[v]; k < w.offsets[v + 1]; ++k)
        if (w.weights[k] > w.weights[pivot]) pivot = k;
      const Eigen::Vector4d ref = dq[w.joints[pivot]].r;
      Eigen::Vector4d r = Eigen::Vector4d::Zero(), d = Eigen::Vector4d::Zero();
      for (int k = w.offsets[v]; k < w.offsets[v + 1]; ++k) {
        const Dq& q = dq[w.joints[k]];
        const double s = (q.r.dot(ref) < 0 ? -1.0 : 1.0) * w.weights[k];
        r += s * q.r;
        d += s * q.d;
      }
      const double n = r.norm();
      r /= n;
      d /= n;
      // Translation t = 2 d r*, rotation from r.
      const Eigen::Vector4d rc(r[0], -r[1], -r[2], -r[3]);
      const Eigen::Vector4d tq = 2.0 * qmul(d, rc);
      const Eigen::Matrix3d rot = Eigen::Quaterniond(r[0], r[1], r[2], r[3]).toRotationMatrix();
      Eigen::Vector3d p(rest(v, 0), rest(v, 1), rest(v, 2));
      Eigen::Matrix3d linear = rot;
      if (stretched) {
        Eigen::Matrix3d blend = Eigen::Matrix3d::Zero();
        for (int k = w.offsets[v]; k < w.offsets[v + 1]; ++k)
          blend += double(w.weights[k]) * stretch[w.joints[k]];
        p = blend * p;
        linear = rot * blend;
      }
      const Eigen::Vector3d q = rot * p + Eigen::Vector3d(tq[1], tq[2], tq[3]);
      out.row(static_cast<Eigen::Index>(v)) = q.cast<float>().transpose();
      if (rotations) {
        Mat3f& R = (*rotations)[v];
        for (int i = 0; i < 3; ++i)
          for (int c = 0; c < 3; ++c) R.m[i * 3 + c] = static_cast<float>(linear(i, c));
      }
    }
  });
}

}  // namespace isokit::skinning
