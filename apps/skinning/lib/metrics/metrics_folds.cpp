// SPDX-License-Identifier: MIT
// Folds measured on the skin alone (folds.h).
#include "isokit/skinning/folds.h"

#include <algorithm>
#include <map>
#include <string>

#include "isokit/core/error.h"
#include "isokit/core/parallel.h"
#include "isokit/skinning/deform.h"
#include "metrics/metrics_check.h"

namespace isokit::skinning {
namespace {

Eigen::Vector3d corner(const track::Positions& p, int v) {
  return p.row(v).cast<double>().transpose();
}

/// Unit normal of triangle f, or zero when it has no area.
Eigen::Vector3d unit_normal(const track::Positions& p, const track::Triangles& t, Eigen::Index f) {
  const Eigen::Vector3d a = corner(p, t(f, 0));
  const Eigen::Vector3d n = (corner(p, t(f, 1)) - a).cross(corner(p, t(f, 2)) - a);
  const double len = n.norm();
  return len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

/// The rotation quaternion of each matrix's rigid part, as (w, x, y, z).
std::vector<Eigen::Vector4d> rotation_quaternions(const std::vector<Affine>& skin) {
  std::vector<Eigen::Vector4d> q(skin.size());
  for (std::size_t j = 0; j < skin.size(); ++j) {
    const Eigen::Quaterniond r(Eigen::Matrix3d(rigid_part(skin[j]).linear()));
    q[j] = {r.w(), r.x(), r.y(), r.z()};
  }
  return q;
}

void check_weights(const SkinWeights& w, Eigen::Index vertices, std::size_t joints) {
  require(!w.empty() && static_cast<Eigen::Index>(w.offsets.size()) == vertices + 1, "FoldCounter: weights",
          "need one entry per vertex (" + std::to_string(vertices) + ")",
          "pass the rig's skin weights for this mesh");
  for (int j : w.joints)
    require(
        j >= 0 && static_cast<std::size_t>(j) < joints, "FoldCounter: weights",
        "joint index " + std::to_string(j) + " outside the " + std::to_string(joints) + " skinning matrices",
        "pass one skinning matrix per joint");
}

}  // namespace

FoldCounter::FoldCounter(const track::Positions& rest, const track::Triangles& triangles,
                         const SkinWeights& weights, const std::vector<Affine>& rest_skin, std::size_t grain)
    : triangles_(triangles), joints_(rest_skin.size()), grain_(grain) {
  detail::check_triangles(triangles_, rest.rows(), "FoldCounter");
  check_weights(weights, rest.rows(), joints_);
  const Eigen::Index nf = triangles_.rows();
  rest_normals_.resize(static_cast<std::size_t>(nf));
  pivot_.resize(static_cast<std::size_t>(nf));
  blend_.offsets.assign(1, 0);
  std::map<int, float> sum;  // joint -> summed weight of the three corners
  for (Eigen::Index f = 0; f < nf; ++f) {
    rest_normals_[static_cast<std::size_t>(f)] = unit_normal(rest, triangles_, f);
    sum.clear();
    for (int c = 0; c < 3; ++c) {
      const int v = triangles_(f, c);
      for (int k = weights.offsets[v]; k < weights.offsets[v + 1]; ++k)
        sum[weights.joints[static_cast<std::size_t>(k)]] +=
            weights.weights[static_cast<std::size_t>(k)] / 3.0f;
    }
    int pivot = sum.empty() ? -1 : sum.begin()->first;
    for (const auto& [j, w] : sum) {
      blend_.joints.push_back(j);
      blend_.weights.push_back(w);
      if (w > sum[pivot]) pivot = j;
    }
    blend_.offsets.push_back(static_cast<int>(blend_.joints.size()));
    pivot_[static_cast<std::size_t>(f)] = pivot;
  }
  rest_folded_ = folded(rest, rest_skin);
}

std::vector<std::uint8_t> FoldCounter::folded(const track::Positions& posed,
                                              const std::vector<Affine>& skin) const {
  require(
      skin.size() == joints_, "FoldCounter::folded",
      std::to_string(skin.size()) + " skinning matrices for a rig of " + std::to_string(joints_) + " joints",
      "pass skinning_matrices(rig, pose)");
  detail::check_triangles(triangles_, posed.rows(), "FoldCounter::folded");
  const std::vector<Eigen::Vector4d> q = rotation_quaternions(skin);
  const std::size_t nf = rest_normals_.size();
  std::vector<std::uint8_t> out(nf, 0);
  parallel_for(nf, grain_, [&](std::size_t b, std::size_t e) {
    for (std::size_t f = b; f < e; ++f) {
      const Eigen::Vector3d& n0 = rest_normals_[f];
      if (n0.isZero() || pivot_[f] < 0) continue;
      // The dual-quaternion blend's rotation at the triangle (its real part, normalised).
      const Eigen::Vector4d& ref = q[static_cast<std::size_t>(pivot_[f])];
      Eigen::Vector4d r = Eigen::Vector4d::Zero();
      for (int k = blend_.offsets[f]; k < blend_.offsets[f + 1]; ++k) {
        const Eigen::Vector4d& qj = q[static_cast<std::size_t>(blend_.joints[static_cast<std::size_t>(k)])];
        r += (qj.dot(ref) < 0 ? -1.0 : 1.0) * double(blend_.weights[static_cast<std::size_t>(k)]) * qj;
      }
      if (r.norm() == 0) continue;
      r.normalize();
      const Eigen::Vector3d carried = Eigen::Quaterniond(r[0], r[1], r[2], r[3]) * n0;
      const Eigen::Vector3d n1 = unit_normal(posed, triangles_, static_cast<Eigen::Index>(f));
      out[f] = n1.dot(carried) < 0 ? 1 : 0;
    }
  });
  return out;
}

FoldCounter::Count FoldCounter::count(const std::vector<std::uint8_t>& flags) const {
  Count c;
  for (std::size_t f = 0; f < flags.size() && f < rest_folded_.size(); ++f) {
    c.folded += flags[f] ? 1 : 0;
    c.folded_new += flags[f] && !rest_folded_[f] ? 1 : 0;
  }
  return c;
}

}  // namespace isokit::skinning
