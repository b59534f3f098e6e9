// SPDX-License-Identifier: MIT
#include "isokit/implicit/hrbf.h"

#include <cmath>

#include <Eigen/Dense>

#include "isokit/core/error.h"

namespace isokit::implicit {

namespace {

bool finite(const Vec3d& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

std::string item(const std::string& name, std::size_t i) {
  return name + " sample " + std::to_string(i);
}

/// Greedy merge of samples closer than `radius` (first sample of a cluster is its seed).
std::vector<HrbfSample> merge_close(const std::vector<HrbfSample>& in, double radius,
                                    const std::string& name) {
  struct Cluster {
    Vec3d seed, sum_p, sum_n;
    int count;
  };
  std::vector<Cluster> clusters;
  for (const HrbfSample& s : in) {
    bool merged = false;
    for (Cluster& c : clusters) {
      if (norm(s.position - c.seed) <= radius) {
        c.sum_p += s.position;
        c.sum_n += s.normal;
        ++c.count;
        merged = true;
        break;
      }
    }
    if (!merged) clusters.push_back({s.position, s.position, s.normal, 1});
  }
  std::vector<HrbfSample> out;
  out.reserve(clusters.size());
  for (std::size_t i = 0; i < clusters.size(); ++i) {
    const Cluster& c = clusters[i];
    const double len = norm(c.sum_n);
    require(len > 0.5 * c.count,
            name + " samples near " + std::to_string(c.seed.x) + " " + std::to_string(c.seed.y) + " " +
                std::to_string(c.seed.z),
            "near-duplicate samples with opposite normals (a sheet thinner than the merge distance)",
            "remove the duplicated or folded geometry, or lower HrbfOptions::merge_distance");
    out.push_back({c.sum_p / double(c.count), c.sum_n / len});
  }
  return out;
}

/// The samples with unit normals (checked finite and non-zero), and their bounding box.
std::vector<HrbfSample> normalised_samples(const std::vector<HrbfSample>& samples, const std::string& name,
                                           Box3d& box) {
  std::vector<HrbfSample> clean;
  clean.reserve(samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const HrbfSample& s = samples[i];
    const double len = norm(s.normal);
    if (!finite(s.position) || !finite(s.normal) || !(len > 1e-12)) {  // messages built only here
      require(finite(s.position), item(name, i) + " position", "is not finite", "remove NaN/inf vertices");
      require(finite(s.normal), item(name, i) + " normal", "is not finite", "recompute the normals");
      require(false, item(name, i) + " normal", "has zero length", "give every sample a unit normal");
    }
    clean.push_back({s.position, s.normal / len});
    box.extend(s.position);
  }
  return clean;
}

/// The (4m + 4)² interpolation system at the normalised positions `y` (rows 4i..4i+3: `d(yi) = 0`,
/// `∇d(yi) = ni`; the last 4: the affine part's orthogonality conditions) and its right side.
void assemble_system(const std::vector<Vec3d>& y, const std::vector<HrbfSample>& samples, Eigen::MatrixXd& A,
                     Eigen::VectorXd& rhs) {
  const std::size_t m = y.size();
  const Eigen::Index n = Eigen::Index(4 * m + 4);
  A = Eigen::MatrixXd::Zero(n, n);
  rhs = Eigen::VectorXd::Zero(n);
  const Eigen::Index aff = Eigen::Index(4 * m);
  for (std::size_t i = 0; i < m; ++i) {
    const Eigen::Index ri = Eigen::Index(4 * i);
    for (std::size_t k = 0; k < m; ++k) {
      const Eigen::Index ck = Eigen::Index(4 * k);
      const Vec3d u = y[i] - y[k];
      const double r = norm(u);
      const double gphi[3] = {3 * r * u.x, 3 * r * u.y, 3 * r * u.z};
      A(ri, ck) = r * r * r;
      for (int a = 0; a < 3; ++a) {
        A(ri, ck + 1 + a) = gphi[a];
        A(ri + 1 + a, ck) = gphi[a];
        for (int b = 0; b < 3; ++b) {
          const double h = r > 0 ? 3 * (r * (a == b ? 1.0 : 0.0) + u[a] * u[b] / r) : 0.0;
          A(ri + 1 + a, ck + 1 + b) = h;
        }
      }
    }
    for (int a = 0; a < 3; ++a) {
      A(ri, aff + a) = y[i][a];
      A(ri + 1 + a, aff + a) = 1;
      rhs(ri + 1 + a) = samples[i].normal[a];
      // Orthogonality to the affine part: Σ λk yk − βk = 0 (rows aff..aff+2), Σ λk = 0 (row
      // aff+3). With d's `+ βk·∇φ` sign this cancels the |x|² far-field growth (the |x|³ term
      // cancels by Σ λk = 0), so d grows at most linearly away from the samples.
      A(aff + a, ri) = y[i][a];
      A(aff + a, ri + 1 + a) = -1;
    }
    A(ri, aff + 3) = 1;
    A(aff + 3, ri) = 1;
  }
}

}  // namespace

Hrbf::Hrbf(const std::vector<HrbfSample>& samples, const HrbfOptions& options, const std::string& name) {
  require(options.merge_distance >= 0 && std::isfinite(options.merge_distance), name + " merge_distance",
          "must be finite and >= 0", "use the default 1e-3");
  Box3d box;
  const std::vector<HrbfSample> clean = normalised_samples(samples, name, box);
  require(clean.size() >= 4, name, "needs at least 4 samples, got " + std::to_string(clean.size()),
          "give the part more surface or lower the culling distance");
  const double diag = norm(box.size());
  require(diag > 0, name, "all samples coincide", "give the part a surface with some extent");
  samples_ = merge_close(clean, options.merge_distance * diag, name);
  const std::size_t m = samples_.size();
  require(m >= 4, name, "needs at least 4 distinct samples after merging, got " + std::to_string(m),
          "give the part more surface or lower HrbfOptions::merge_distance");

  center_ = (box.lo + box.hi) * 0.5;
  scale_ = 0.5 * diag;
  std::vector<Vec3d> y(m);
  for (std::size_t i = 0; i < m; ++i) y[i] = (samples_[i].position - center_) / scale_;
  Eigen::MatrixXd A;
  Eigen::VectorXd rhs;
  assemble_system(y, samples_, A, rhs);
  // In-place factorisation (no copy of the 4m+4 square matrix); the interpolation residual is
  // checked below on the evaluated HRBF instead of by iterative refinement.
  const Eigen::PartialPivLU<Eigen::Ref<Eigen::MatrixXd>> lu(A);
  rcond_ = lu.rcond();
  require(rcond_ >= options.min_rcond, name,
          "the HRBF system is ill-conditioned (reciprocal condition " + format_number(rcond_) + ")",
          "remove near-duplicate or coplanar clusters of samples, or raise HrbfOptions::merge_distance");
  const Eigen::VectorXd x = lu.solve(rhs);
  require(x.allFinite(), name, "the HRBF solve produced non-finite coefficients", "check the samples");
  store_coefficients(y, x.data());

  residual_ = 0;
  for (const HrbfSample& s : samples_) {
    const FieldSampleT<double> e = distance(s.position);
    residual_ = std::max(residual_, std::abs(e.value) / diag);
    residual_ = std::max(residual_, norm(e.gradient - s.normal));
  }
  require(residual_ <= options.max_residual, name,
          "the HRBF does not interpolate its samples (residual " + format_number(residual_) + ")",
          "remove near-duplicate samples or raise HrbfOptions::merge_distance");
}

void Hrbf::store_coefficients(const std::vector<Vec3d>& y, const double* x) {
  // Struct of arrays padded to a multiple of kHrbfLanes with zero coefficients (they add 0).
  const std::size_t m = y.size();
  const std::size_t aff = 4 * m;
  const std::size_t mp = (m + kHrbfLanes - 1) / kHrbfLanes * kHrbfLanes;
  d_.assign(7 * mp, 0.0);
  for (std::size_t k = 0; k < m; ++k) {
    d_[k] = y[k].x;
    d_[mp + k] = y[k].y;
    d_[2 * mp + k] = y[k].z;
    d_[3 * mp + k] = x[4 * k];
    d_[4 * mp + k] = x[4 * k + 1];
    d_[5 * mp + k] = x[4 * k + 2];
    d_[6 * mp + k] = x[4 * k + 3];
  }
  for (std::size_t a = 0; a < 4; ++a) affine_[a] = x[aff + a];
  f_.assign(d_.begin(), d_.end());
}

HrbfViewT<double> Hrbf::view_d() const {
  const int m = int(d_.size() / 7);
  const double* p = d_.data();
  HrbfViewT<double> v{p,         p + m, p + 2 * m, p + 3 * m, p + 4 * m, p + 5 * m,
                      p + 6 * m, m,     {},        center_,   scale_};
  for (int a = 0; a < 4; ++a) v.affine[a] = affine_[a];
  return v;
}

HrbfViewT<float> Hrbf::view_f() const {
  const int m = int(d_.size() / 7);
  const float* p = f_.data();
  HrbfViewT<float> v{p,
                     p + m,
                     p + 2 * m,
                     p + 3 * m,
                     p + 4 * m,
                     p + 5 * m,
                     p + 6 * m,
                     m,
                     {},
                     {float(center_.x), float(center_.y), float(center_.z)},
                     float(scale_)};
  for (int a = 0; a < 4; ++a) v.affine[a] = float(affine_[a]);
  return v;
}

HrbfField::HrbfField(std::shared_ptr<const Hrbf> hrbf, double r, const Box3f& support_box)
    : hrbf_(std::move(hrbf)), r_(r), box_(support_box) {
  require(hrbf_ != nullptr, "HrbfField", "no HRBF given", "pass a fitted Hrbf");
  require(std::isfinite(r) && r > 0, "HrbfField r", "must be finite and > 0 (got " + format_number(r) + ")",
          "use the distance from the bone to the farthest sample");
  require(!box_.empty(), "HrbfField support box", "is empty", "pass a box around the samples grown by r");
  view_ = hrbf_->view_f();
  // The box must not cut the field: d >= r (f = 0) on a lattice over each face.
  constexpr int kLattice = 16;
  const HrbfViewT<double> hv = hrbf_->view_d();
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      for (int i = 0; i <= kLattice; ++i) {
        for (int j = 0; j <= kLattice; ++j) {
          Vec3d p{box_.lo.x, box_.lo.y, box_.lo.z};
          const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
          p[axis] = side ? box_.hi[axis] : box_.lo[axis];
          p[a1] = box_.lo[a1] + (box_.hi[a1] - box_.lo[a1]) * double(i) / kLattice;
          p[a2] = box_.lo[a2] + (box_.hi[a2] - box_.lo[a2]) * double(j) / kLattice;
          if (eval_hrbf_distance(hv, p).value >= r_) continue;  // (message built only on failure)
          require(false, "HrbfField support box",
                  "cuts the field (d < r on its face at " + format_number(p.x) + " " + format_number(p.y) +
                      " " + format_number(p.z) + ")",
                  "grow the box (PartFitOptions::support_margin) or check the samples");
        }
      }
    }
  }
}

FieldSample HrbfField::eval(const Vec3f& p) const {
  if (!box_.contains(p)) return {};
  const FieldSample d = eval_hrbf_distance(view_, p);
  return remap_distance(d.value, d.gradient, float(r_));
}

FieldSampleT<double> HrbfField::eval_d(const Vec3d& p) const {
  const Vec3f pf{float(p.x), float(p.y), float(p.z)};
  if (!box_.contains(pf)) return {};
  const FieldSampleT<double> d = hrbf_->distance(p);
  return remap_distance(d.value, d.gradient, r_);
}

}  // namespace isokit::implicit
