// SPDX-License-Identifier: MIT
// Optimized centers of rotation (Le & Hodgins 2016): the centers' precomputation and the
// per-frame skin (cor.h).
#include "isokit/skinning/cor.h"

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <limits>

#include "isokit/core/error.h"
#include "isokit/core/parallel.h"
#include "isokit/skinning/deform.h"

namespace isokit::skinning {

struct CorSkinning::Data {
  CorOptions options;
  SkinWeights weights;
  track::Positions rest_f;  ///< the rest mesh as given (the DQS fallback)
  std::vector<Eigen::Vector3d> rest, center;
  std::vector<std::uint8_t> has_center;
  int fallback{0};
  double seconds{0};
};

void check_cor_options(const CorOptions& o, const std::string& where) {
  require(std::isfinite(o.sigma) && o.sigma > 0 && o.sigma <= 10, where + ".sigma",
          "must be in (0, 10] (got " + format_number(o.sigma) + ")", "use 0.1 (the paper's value)");
}

CorFallback cor_fallback_from_string(const std::string& s, const std::string& where) {
  if (s == "lbs") return CorFallback::kLbs;
  if (s == "dqs") return CorFallback::kDqs;
  throw InputError(where + ": unknown fallback '" + s + "'; use lbs or dqs");
}

const char* to_string(CorFallback f) {
  return f == CorFallback::kDqs ? "dqs" : "lbs";
}

namespace {

/// A triangle's area, centroid and weights (the mean of its corners', sparse).
struct TriangleWeights {
  std::vector<double> area;
  std::vector<Eigen::Vector3d> centroid;
  SkinWeights weights;                    ///< CSR over triangles
  std::vector<std::vector<int>> by_bone;  ///< triangles with a weight on each bone
};

TriangleWeights triangle_weights(const std::vector<Eigen::Vector3d>& p, const track::Triangles& tris,
                                 const SkinWeights& w, int joints) {
  TriangleWeights tw;
  const Eigen::Index nt = tris.rows();
  tw.area.resize(static_cast<std::size_t>(nt));
  tw.centroid.resize(static_cast<std::size_t>(nt));
  tw.weights.offsets.push_back(0);
  tw.by_bone.resize(static_cast<std::size_t>(joints));
  std::vector<double> dense(static_cast<std::size_t>(joints), 0.0);
  std::vector<int> touched;
  for (Eigen::Index t = 0; t < nt; ++t) {
    const Eigen::Vector3d& a = p[tris(t, 0)];
    const Eigen::Vector3d& b = p[tris(t, 1)];
    const Eigen::Vector3d& c = p[tris(t, 2)];
    tw.area[t] = 0.5 * (b - a).cross(c - a).norm();
    tw.centroid[t] = (a + b + c) / 3.0;
    touched.clear();
    for (int corner = 0; corner < 3; ++corner) {
      const int v = tris(t, corner);
      for (int k = w.offsets[v]; k < w.offsets[v + 1]; ++k) {
        if (dense[w.joints[k]] == 0.0) touched.push_back(w.joints[k]);
        dense[w.joints[k]] += double(w.weights[k]) / 3.0;
      }
    }
    for (int j : touched) {
      tw.weights.joints.push_back(j);
      tw.weights.weights.push_back(static_cast<float>(dense[j]));
      tw.by_bone[static_cast<std::size_t>(j)].push_back(static_cast<int>(t));
      dense[j] = 0.0;
    }
    tw.weights.offsets.push_back(static_cast<int>(tw.weights.joints.size()));
  }
  return tw;
}

/// Σ_{j<k} w_pj w_pk w_tj w_tk exp(−(w_pj w_tk − w_pk w_tj)² / σ²) over the bones both carry
/// (`wp` the vertex's weights, dense; `pairs` scratch).
double similarity(const std::vector<double>& wp, const TriangleWeights& tw, int t, double sigma2,
                  std::vector<std::pair<double, double>>& pairs) {
  pairs.clear();
  for (int k = tw.weights.offsets[t]; k < tw.weights.offsets[t + 1]; ++k) {
    const double a = wp[static_cast<std::size_t>(tw.weights.joints[k])];
    if (a > 0) pairs.emplace_back(a, double(tw.weights.weights[k]));
  }
  double s = 0;
  for (std::size_t x = 0; x < pairs.size(); ++x)
    for (std::size_t y = x + 1; y < pairs.size(); ++y) {
      const double d = pairs[x].first * pairs[y].second - pairs[y].first * pairs[x].second;
      s += pairs[x].first * pairs[y].first * pairs[x].second * pairs[y].second * std::exp(-d * d / sigma2);
    }
  return s;
}

}  // namespace

CorSkinning::CorSkinning(const track::Positions& rest, const track::Triangles& triangles,
                         const SkinWeights& weights, const CorOptions& options, std::size_t grain)
    : d_(std::make_unique<Data>()) {
  const auto t0 = std::chrono::steady_clock::now();
  check_cor_options(options, "cor");
  const std::size_t n = static_cast<std::size_t>(rest.rows());
  require(weights.offsets.size() == n + 1, "cor", "the weights need one entry per vertex",
          "compute or load weights for this mesh");
  Data& d = *d_;
  d.options = options;
  d.weights = weights;
  d.rest_f = rest;
  int joints = 0;
  for (int j : weights.joints) joints = std::max(joints, j + 1);
  d.rest.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    d.rest[i] = rest.row(static_cast<Eigen::Index>(i)).cast<double>().transpose();
  const TriangleWeights tw = triangle_weights(d.rest, triangles, weights, joints);
  d.center = d.rest;
  d.has_center.assign(n, 0);
  const double sigma2 = options.sigma * options.sigma;
  parallel_for(n, grain, [&](std::size_t b, std::size_t e) {
    std::vector<double> wp(static_cast<std::size_t>(joints), 0.0);
    std::vector<std::size_t> seen(tw.area.size(), std::numeric_limits<std::size_t>::max());
    std::vector<std::pair<double, double>> pairs;
    for (std::size_t i = b; i < e; ++i) {
      if (weights.count(static_cast<int>(i)) < 2) continue;  // rigid with its bone
      for (int k = weights.offsets[i]; k < weights.offsets[i + 1]; ++k)
        wp[weights.joints[k]] = weights.weights[k];
      double den = 0;
      Eigen::Vector3d num = Eigen::Vector3d::Zero();
      for (int k = weights.offsets[i]; k < weights.offsets[i + 1]; ++k)
        for (int t : tw.by_bone[static_cast<std::size_t>(weights.joints[k])]) {
          if (seen[static_cast<std::size_t>(t)] == i) continue;
          seen[static_cast<std::size_t>(t)] = i;
          const double s = similarity(wp, tw, t, sigma2, pairs) * tw.area[static_cast<std::size_t>(t)];
          den += s;
          num += s * tw.centroid[static_cast<std::size_t>(t)];
        }
      for (int k = weights.offsets[i]; k < weights.offsets[i + 1]; ++k) wp[weights.joints[k]] = 0.0;
      if (den > 0 && std::isfinite(den)) {
        d.center[i] = num / den;
        d.has_center[i] = 1;
      }
    }
  });
  for (std::size_t i = 0; i < n; ++i)
    d.fallback += weights.count(static_cast<int>(i)) >= 2 && !d.has_center[i];
  d.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

CorSkinning::~CorSkinning() = default;

void CorSkinning::deform(const std::vector<Affine>& skin, track::Positions& out, std::size_t grain) const {
  const Data& d = *d_;
  const SkinWeights& w = d.weights;
  for (int j : w.joints)
    require(j >= 0 && j < static_cast<int>(skin.size()), "cor", "fewer skinning matrices than joints",
            "pass one skinning matrix per joint");
  const std::size_t n = d.rest.size();
  out.resize(static_cast<Eigen::Index>(n), 3);
  std::vector<Eigen::Matrix<double, 3, 4>> m(skin.size());
  std::vector<Eigen::Vector4d> q(skin.size());  // (w, x, y, z)
  for (std::size_t j = 0; j < skin.size(); ++j) {
    m[j] = skin[j].matrix().topRows<3>();
    const Eigen::Quaterniond r(Eigen::Matrix3d(rigid_part(skin[j]).linear()));
    q[j] = {r.w(), r.x(), r.y(), r.z()};
  }
  track::Positions dqs;
  if (d.options.fallback == CorFallback::kDqs && d.fallback > 0)
    dual_quaternion_blend(w, skin, d.rest_f, dqs, nullptr, grain);
  parallel_for(n, grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const Eigen::Vector4d pr(d.rest[i].x(), d.rest[i].y(), d.rest[i].z(), 1.0);
      if (!d.has_center[i]) {
        if (dqs.rows() > 0 && w.count(static_cast<int>(i)) >= 2) {
          out.row(static_cast<Eigen::Index>(i)) = dqs.row(static_cast<Eigen::Index>(i));
          continue;
        }
        Eigen::Vector3d u = Eigen::Vector3d::Zero();
        for (int k = w.offsets[i]; k < w.offsets[i + 1]; ++k)
          u += double(w.weights[k]) * (m[w.joints[k]] * pr);
        out.row(static_cast<Eigen::Index>(i)) = u.cast<float>().transpose();
        continue;
      }
      int pivot = w.offsets[i];
      for (int k = w.offsets[i]; k < w.offsets[i + 1]; ++k)
        if (w.weights[k] > w.weights[pivot]) pivot = k;
      const Eigen::Vector4d& ref = q[w.joints[pivot]];
      const Eigen::Vector4d pc(d.center[i].x(), d.center[i].y(), d.center[i].z(), 1.0);
      Eigen::Vector4d qb = Eigen::Vector4d::Zero();
      Eigen::Vector3d lc = Eigen::Vector3d::Zero();
      for (int k = w.offsets[i]; k < w.offsets[i + 1]; ++k) {
        const Eigen::Vector4d& qj = q[w.joints[k]];
        qb += (qj.dot(ref) < 0 ? -1.0 : 1.0) * double(w.weights[k]) * qj;
        lc += double(w.weights[k]) * (m[w.joints[k]] * pc);
      }
      qb.normalize();
      const Eigen::Matrix3d r = Eigen::Quaterniond(qb[0], qb[1], qb[2], qb[3]).toRotationMatrix();
      const Eigen::Vector3d u = r * (d.rest[i] - d.center[i]) + lc;
      out.row(static_cast<Eigen::Index>(i)) = u.cast<float>().transpose();
    }
  });
}

Eigen::Vector3d CorSkinning::center(int vertex) const {
  return d_->center[static_cast<std::size_t>(vertex)];
}
bool CorSkinning::has_center(int vertex) const {
  return d_->has_center[static_cast<std::size_t>(vertex)] != 0;
}
int CorSkinning::fallback_vertices() const {
  return d_->fallback;
}
double CorSkinning::precompute_seconds() const {
  return d_->seconds;
}
const CorOptions& CorSkinning::options() const {
  return d_->options;
}

}  // namespace isokit::skinning
