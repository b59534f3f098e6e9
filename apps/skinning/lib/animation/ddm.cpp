// SPDX-License-Identifier: MIT
// Direct Delta Mush (Le & Lewis 2019): the precomputation of Ω and the per-frame fit (ddm.h).
#include "isokit/skinning/ddm.h"

#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>

#include "isokit/core/error.h"
#include "isokit/core/parallel.h"
#include "isokit/core/rotation_fit.h"
#include "isokit/skinning/deform.h"

namespace isokit::skinning {

namespace {

using SpMat = Eigen::SparseMatrix<double>;

/// The 10 distinct entries of a symmetric 4×4 Ω = [[S, m], [mᵀ, w]]: xx xy xz yy yz zz x y z 1.
constexpr int kMoments = 10;
/// With v1, the κ-smoothed first moments per pair: x y z 1.
constexpr int kCentroid = 4;
/// Bones per block of right-hand sides (the block's solve is one dense multi-column solve).
constexpr int kBonesPerBlock = 8;

void moments(const Eigen::Vector3d& p, double w, double* out) {
  out[0] = w * p.x() * p.x();
  out[1] = w * p.x() * p.y();
  out[2] = w * p.x() * p.z();
  out[3] = w * p.y() * p.y();
  out[4] = w * p.y() * p.z();
  out[5] = w * p.z() * p.z();
  out[6] = w * p.x();
  out[7] = w * p.y();
  out[8] = w * p.z();
  out[9] = w;
}

/// `(I + λL) y = x` with L = I − D⁻¹A, solved in its SPD form `(D + λ(D − A)) y = D x`.
class ImplicitSmoother {
 public:
  ImplicitSmoother(const track::Triangles& tris, Eigen::Index n, double lambda) : degree_(n) {
    std::vector<Eigen::Triplet<double>> edges;
    edges.reserve(static_cast<std::size_t>(tris.rows()) * 6);
    for (Eigen::Index t = 0; t < tris.rows(); ++t)
      for (int c = 0; c < 3; ++c) {
        const int a = tris(t, c), b = tris(t, (c + 1) % 3);
        edges.emplace_back(a, b, 1.0);
        edges.emplace_back(b, a, 1.0);
      }
    SpMat adj(n, n);
    adj.setFromTriplets(edges.begin(), edges.end(), [](double, double) { return 1.0; });
    for (Eigen::Index i = 0; i < n; ++i) degree_[i] = std::max(1.0, adj.col(i).sum());
    SpMat lap = -lambda * adj;
    for (Eigen::Index i = 0; i < n; ++i) lap.coeffRef(i, i) += degree_[i] * (1.0 + lambda);
    solver_.compute(lap);
    require(solver_.info() == Eigen::Success, "ddm smoothing", "the smoothing matrix could not be factored",
            "check the mesh for non-finite positions");
  }
  /// `steps` smoothing steps applied to the columns of `x`, in place.
  void apply(Eigen::MatrixXd& x, int steps) const {
    for (int s = 0; s < steps; ++s) {
      const Eigen::MatrixXd rhs = degree_.asDiagonal() * x;  // not aliased with the solve's output
      x = solver_.solve(rhs);
    }
  }

 private:
  Eigen::VectorXd degree_;
  Eigen::SimplicialLDLT<SpMat> solver_;
};

}  // namespace

/// Per vertex: its bones (CSR), the Ω moments of each, and the sums over its bones.
struct DirectDeltaMush::Data {
  DdmOptions options;
  Eigen::Vector3d shift{Eigen::Vector3d::Zero()};  ///< Ω is stored about the bounding box's centre
  std::vector<int> offsets{0};
  std::vector<int> bones;
  std::vector<double> omega;     ///< kMoments per pair
  std::vector<double> centroid;  ///< kCentroid per pair (v1)
  std::vector<double> rest;      ///< shifted rest positions, 3 per vertex
  std::vector<double> sums;      ///< Σ_j Ω_ij's p̄ (3) and s (1), then v1's κ sums (4): 8 per vertex
  std::vector<int> dominant;     ///< the bone of largest smoothed weight, per vertex
  int joints{0};
  double seconds{0};
};

void check_ddm_options(const DdmOptions& o, const std::string& where) {
  require(o.smoothing_steps >= 0 && o.smoothing_steps <= 100, where + ".smoothing_steps",
          "must be in [0, 100] (got " + std::to_string(o.smoothing_steps) + ")",
          "use 3 (0 = no smoothing: LBS)");
  require(std::isfinite(o.lambda) && o.lambda >= 0 && o.lambda <= 1000, where + ".lambda",
          "must be in [0, 1000] (got " + format_number(o.lambda) + ")", "use 3");
  require(std::isfinite(o.kappa) && o.kappa >= 0 && o.kappa <= 1000, where + ".kappa",
          "must be in [0, 1000] (got " + format_number(o.kappa) + ")", "use 1, or lambda's value for v0");
  require(std::isfinite(o.alpha) && o.alpha >= 0 && o.alpha <= 1, where + ".alpha",
          "must be in [0, 1] (got " + format_number(o.alpha) + ")", "use 0 (1 = LBS)");
  require(std::isfinite(o.prune) && o.prune >= 0 && o.prune < 0.5, where + ".prune",
          "must be in [0, 0.5) (got " + format_number(o.prune) + ")", "use 1e-3");
}

DdmVariant ddm_variant_from_string(const std::string& s, const std::string& where) {
  if (s == "v0") return DdmVariant::kV0;
  if (s == "v1") return DdmVariant::kV1;
  throw InputError(where + ": unknown variant '" + s + "'; use v0 or v1");
}

const char* to_string(DdmVariant v) {
  return v == DdmVariant::kV1 ? "v1" : "v0";
}

namespace {

/// Smoothed channels of a block of bones: `channels` per bone, from `fill(vertex, bone, out)`;
/// then `(1 − α) B^p X + α X`.
Eigen::MatrixXd smoothed_block(const ImplicitSmoother& sm, const DdmOptions& o, Eigen::Index n, int first,
                               int count, int channels,
                               const std::function<void(Eigen::Index, int, double*)>& fill) {
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(n, Eigen::Index(count) * channels);
  std::vector<double> row(static_cast<std::size_t>(channels));
  for (Eigen::Index i = 0; i < n; ++i)
    for (int b = 0; b < count; ++b) {
      fill(i, first + b, row.data());
      for (int c = 0; c < channels; ++c) x(i, Eigen::Index(b) * channels + c) = row[c];
    }
  Eigen::MatrixXd y = x;
  sm.apply(y, o.smoothing_steps);
  if (o.alpha > 0) y = (1.0 - o.alpha) * y + o.alpha * x;
  return y;
}

/// Per-vertex weight of each bone (dense row access into CSR weights).
double weight_of(const SkinWeights& w, Eigen::Index v, int joint) {
  for (int k = w.offsets[v]; k < w.offsets[v + 1]; ++k)
    if (w.joints[k] == joint) return double(w.weights[k]);
  return 0.0;
}

/// The total smoothed weight per vertex (pruning is relative to it).
Eigen::MatrixXd smoothed_total(const ImplicitSmoother& sm, const SkinWeights& weights, Eigen::Index n,
                               const DdmOptions& options) {
  Eigen::MatrixXd total(n, 1);
  for (Eigen::Index i = 0; i < n; ++i) {
    double s = 0;
    for (int k = weights.offsets[i]; k < weights.offsets[i + 1]; ++k) s += weights.weights[k];
    total(i, 0) = s;
  }
  const Eigen::MatrixXd total_x = total;
  sm.apply(total, options.smoothing_steps);
  if (options.alpha > 0) total = (1.0 - options.alpha) * total + options.alpha * total_x;
  return total;
}

/// One kept (vertex, bone) pair of Ω: its moments, then v1's κ-smoothed centroid moments.
struct Pair {
  int bone;
  double m[kMoments + kCentroid];
};

/// The pairs kept by the pruning rule, per block of bones (solved in parallel) and per vertex.
/// `rest`: the shifted rest positions, 3 per vertex; `sk`: v1's κ smoother, else null.
std::vector<std::vector<std::vector<Pair>>> kept_pairs(const ImplicitSmoother& sm, const ImplicitSmoother* sk,
                                                       const SkinWeights& weights, int joints,
                                                       const DdmOptions& options,
                                                       const Eigen::MatrixXd& total,
                                                       const std::vector<double>& rest) {
  const Eigen::Index n = total.rows();
  auto point = [&](Eigen::Index i) { return Eigen::Vector3d(rest.data() + i * 3); };
  const int blocks = (joints + kBonesPerBlock - 1) / kBonesPerBlock;
  std::vector<std::vector<std::vector<Pair>>> kept(static_cast<std::size_t>(blocks));
  parallel_for(static_cast<std::size_t>(blocks), 1, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b) {
      const int first = int(b) * kBonesPerBlock, count = std::min(kBonesPerBlock, joints - first);
      const Eigen::MatrixXd y = smoothed_block(
          sm, options, n, first, count, kMoments,
          [&](Eigen::Index i, int j, double* out) { moments(point(i), weight_of(weights, i, j), out); });
      Eigen::MatrixXd yk;
      if (sk)
        yk =
            smoothed_block(*sk, options, n, first, count, kCentroid, [&](Eigen::Index i, int j, double* out) {
              double m[kMoments];
              moments(point(i), weight_of(weights, i, j), m);
              std::copy(m + 6, m + 10, out);
            });
      auto& mine = kept[b];
      mine.resize(static_cast<std::size_t>(n));
      for (Eigen::Index i = 0; i < n; ++i)
        for (int c = 0; c < count; ++c) {
          const double mass = y(i, Eigen::Index(c) * kMoments + 9);
          if (!(mass > 0) || mass < options.prune * total(i, 0)) continue;
          Pair pr{first + c, {}};
          for (int k = 0; k < kMoments; ++k) pr.m[k] = y(i, Eigen::Index(c) * kMoments + k);
          for (int k = 0; k < kCentroid; ++k)
            pr.m[kMoments + k] = sk ? yk(i, Eigen::Index(c) * kCentroid + k) : 0.0;
          mine[static_cast<std::size_t>(i)].push_back(pr);
        }
    }
  });
  return kept;
}

}  // namespace

DirectDeltaMush::DirectDeltaMush(const track::Positions& rest, const track::Triangles& triangles,
                                 const SkinWeights& weights, int joints, const DdmOptions& options)
    : d_(std::make_unique<Data>()) {
  const auto t0 = std::chrono::steady_clock::now();
  check_ddm_options(options, "ddm");
  const Eigen::Index n = rest.rows();
  require(static_cast<Eigen::Index>(weights.offsets.size()) == n + 1, "ddm",
          "the weights need one entry per vertex", "compute or load weights for this mesh");
  Data& d = *d_;
  d.options = options;
  d.joints = joints;
  const Eigen::MatrixXd p = rest.cast<double>();
  d.shift = 0.5 * (p.colwise().minCoeff() + p.colwise().maxCoeff()).transpose();
  d.rest.resize(static_cast<std::size_t>(n) * 3);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) d.rest[static_cast<std::size_t>(i * 3 + c)] = p(i, c) - d.shift[c];

  const ImplicitSmoother sm(triangles, n, options.lambda);
  std::unique_ptr<ImplicitSmoother> sk;
  if (options.variant == DdmVariant::kV1)
    sk = std::make_unique<ImplicitSmoother>(triangles, n, options.kappa);
  const auto kept =
      kept_pairs(sm, sk.get(), weights, joints, options, smoothed_total(sm, weights, n, options), d.rest);

  // Flatten into CSR, with the per-vertex sums and the dominant bone.
  d.sums.assign(static_cast<std::size_t>(n) * 8, 0.0);
  d.dominant.assign(static_cast<std::size_t>(n), 0);
  for (Eigen::Index i = 0; i < n; ++i) {
    double best = -1;
    for (auto& block : kept)
      for (const Pair& pr : block[static_cast<std::size_t>(i)]) {
        d.bones.push_back(pr.bone);
        d.omega.insert(d.omega.end(), pr.m, pr.m + kMoments);
        if (sk) d.centroid.insert(d.centroid.end(), pr.m + kMoments, pr.m + kMoments + kCentroid);
        double* s = &d.sums[static_cast<std::size_t>(i) * 8];
        for (int k = 0; k < 4; ++k) s[k] += pr.m[6 + k];
        for (int k = 0; k < 4; ++k) s[4 + k] += pr.m[kMoments + k];
        if (pr.m[9] > best) best = pr.m[9], d.dominant[static_cast<std::size_t>(i)] = pr.bone;
      }
    d.offsets.push_back(static_cast<int>(d.bones.size()));
  }
  d.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

DirectDeltaMush::~DirectDeltaMush() = default;

void DirectDeltaMush::deform(const std::vector<Affine>& skin, track::Positions& out,
                             std::size_t grain) const {
  const Data& d = *d_;
  require(static_cast<int>(skin.size()) >= d.joints, "ddm", "fewer skinning matrices than joints",
          "pass one skinning matrix per joint");
  const std::size_t n = d.dominant.size();
  out.resize(static_cast<Eigen::Index>(n), 3);
  // Each matrix acting on the shifted coordinates; its rotation as a quaternion (the fit's start).
  std::vector<Eigen::Matrix3d> lin(skin.size());
  std::vector<Eigen::Vector3d> tr(skin.size());
  std::vector<Eigen::Quaterniond> rot(skin.size());
  for (std::size_t j = 0; j < skin.size(); ++j) {
    lin[j] = skin[j].linear();
    tr[j] = skin[j].linear() * d.shift + skin[j].translation();
    rot[j] = Eigen::Quaterniond(Eigen::Matrix3d(rigid_part(skin[j]).linear()));
  }
  const bool v1 = d.options.variant == DdmVariant::kV1;
  parallel_for(n, grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      Eigen::Matrix3d qh = Eigen::Matrix3d::Zero();
      Eigen::Vector3d q = Eigen::Vector3d::Zero(), qk = Eigen::Vector3d::Zero();
      for (int k = d.offsets[i]; k < d.offsets[i + 1]; ++k) {
        const int j = d.bones[static_cast<std::size_t>(k)];
        const double* o = &d.omega[static_cast<std::size_t>(k) * kMoments];
        Eigen::Matrix3d s;
        s << o[0], o[1], o[2], o[1], o[3], o[4], o[2], o[4], o[5];
        const Eigen::Vector3d m(o[6], o[7], o[8]);
        qh.noalias() += lin[j] * s;
        qh.noalias() += tr[j] * m.transpose();
        q.noalias() += lin[j] * m + tr[j] * o[9];
        if (v1) {
          const double* c = &d.centroid[static_cast<std::size_t>(k) * kCentroid];
          qk.noalias() += lin[j] * Eigen::Vector3d(c[0], c[1], c[2]) + tr[j] * c[3];
        }
      }
      const double* s = &d.sums[i * 8];
      const Eigen::Vector3d pbar(s[0], s[1], s[2]);
      const double mass = s[3] > 0 ? s[3] : 1.0;
      const Eigen::Matrix3d cov = qh - q * pbar.transpose() / mass;
      const Eigen::Matrix3d r = best_rotation(cov, rot[static_cast<std::size_t>(d.dominant[i])]);
      Eigen::Vector3d t = q / mass - r * pbar / mass;
      if (v1 && s[7] > 0) t = qk / s[7] - r * Eigen::Vector3d(s[4], s[5], s[6]) / s[7];
      const Eigen::Vector3d u = r * Eigen::Vector3d(&d.rest[i * 3]) + t;
      out.row(static_cast<Eigen::Index>(i)) = u.cast<float>().transpose();
    }
  });
}

Eigen::Matrix4d DirectDeltaMush::omega(int vertex, int joint) const {
  const Data& d = *d_;
  Eigen::Matrix4d om = Eigen::Matrix4d::Zero();
  for (int k = d.offsets[vertex]; k < d.offsets[vertex + 1]; ++k) {
    if (d.bones[static_cast<std::size_t>(k)] != joint) continue;
    const double* o = &d.omega[static_cast<std::size_t>(k) * kMoments];
    om << o[0], o[1], o[2], o[6], o[1], o[3], o[4], o[7], o[2], o[4], o[5], o[8], o[6], o[7], o[8], o[9];
  }
  // Back to the rest coordinates: p̃ = T p̃' with T the shift, so Ω = T Ω' Tᵀ.
  Eigen::Matrix4d tm = Eigen::Matrix4d::Identity();
  tm.block<3, 1>(0, 3) = d.shift;
  return tm * om * tm.transpose();
}

std::size_t DirectDeltaMush::stored_pairs() const {
  return d_->bones.size();
}
double DirectDeltaMush::precompute_seconds() const {
  return d_->seconds;
}
const DdmOptions& DirectDeltaMush::options() const {
  return d_->options;
}

}  // namespace isokit::skinning
