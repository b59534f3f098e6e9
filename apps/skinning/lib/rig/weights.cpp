// SPDX-License-Identifier: MIT
#include "isokit/skinning/weights.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <utility>

#include <Eigen/SparseCore>

#include "isokit/core/error.h"

#ifdef ISOKIT_HAVE_CHOLMOD
#include <Eigen/CholmodSupport>
#else
#include <Eigen/SparseCholesky>
#endif

namespace isokit::skinning {
namespace {

using SpMat = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

constexpr double kMaxCot = 1e3;         // cotangent clamp (angles above ~0.06°)
constexpr double kTieTolerance = 1e-9;  // relative distance tolerance for shared nearest bones
constexpr double kMinDistanceRatio = 1e-4;
constexpr double kMassFloor = 1e-6;
constexpr int kBlock = 8;  // right-hand sides per solve call

/// The factorisation of the SPD heat matrix: CHOLMOD when available, else SimplicialLDLT.
class SpdSolver {
 public:
  explicit SpdSolver(const SpMat& a, const std::string& name) {
#ifdef ISOKIT_HAVE_CHOLMOD
    solver_.setMode(Eigen::CholmodAuto);
#endif
    solver_.compute(a);
    require(solver_.info() == Eigen::Success, name + ": heat weights",
            "the heat system is not positive definite",
            "check the mesh for degenerate or duplicated triangles");
  }
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const {
    return solver_.solve(b);
  }

 private:
#ifdef ISOKIT_HAVE_CHOLMOD
  mutable Eigen::CholmodDecomposition<SpMat, Eigen::Lower> solver_;
#else
  Eigen::SimplicialLDLT<SpMat, Eigen::Lower> solver_;
#endif
};

double corner_cot(const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
  const double s = u.cross(v).norm();
  const double c = u.dot(v);
  if (!(s > 0)) return c > 0 ? kMaxCot : 0.0;
  return std::clamp(c / s, 0.0, kMaxCot);
}

}  // namespace

double segment_distance(const Eigen::Vector3d& p, const Segment& s) {
  const Eigen::Vector3d ab = s.b - s.a;
  const double len2 = ab.squaredNorm();
  if (!(len2 > 0)) return (p - s.a).norm();
  const double t = std::clamp((p - s.a).dot(ab) / len2, 0.0, 1.0);
  return (p - (s.a + t * ab)).norm();
}

std::vector<std::vector<Segment>> joint_segments(const Rig& rig, double leaf_fraction) {
  require(leaf_fraction > 0 && std::isfinite(leaf_fraction), rig.name + ": joint segments",
          "leaf_fraction must be > 0", "pass e.g. 0.5");
  const std::vector<Eigen::Vector3d> pos = rest_joint_positions(rig);
  const std::size_t nj = pos.size();
  double extent = 0;
  for (const auto& p : pos)
    for (const auto& q : pos) extent = std::max(extent, (p - q).norm());
  const double tiny = 1e-9 * std::max(extent, 1e-12);
  std::vector<std::vector<Segment>> seg(nj);
  for (std::size_t c = 0; c < nj; ++c) {
    const int p = rig.joints[c].parent;
    if (p >= 0 && (pos[c] - pos[static_cast<std::size_t>(p)]).norm() > tiny)
      seg[static_cast<std::size_t>(p)].push_back({pos[static_cast<std::size_t>(p)], pos[c]});
  }
  for (std::size_t j = 0; j < nj; ++j) {
    if (!seg[j].empty()) continue;
    int a = rig.joints[j].parent;
    while (a >= 0 && (pos[j] - pos[static_cast<std::size_t>(a)]).norm() <= tiny) a = rig.joints[a].parent;
    if (a < 0) {
      seg[j].push_back({pos[j], pos[j]});
      continue;
    }
    const Eigen::Vector3d bone = pos[j] - pos[static_cast<std::size_t>(a)];
    seg[j].push_back({pos[j], pos[j] + leaf_fraction * bone});
  }
  return seg;
}

namespace {

/// A bone segment with the joint it belongs to.
using Bone = std::pair<int, Segment>;

/// Per-vertex (joint, weight) candidates gathered from the solves.
using Candidates = std::vector<std::vector<std::pair<int, float>>>;

/// Rejects empty meshes, bad options, non-finite positions and out-of-range indices.
void check_inputs(const track::Positions& rest, const track::Triangles& tris,
                  const HeatWeightOptions& options) {
  const std::string& name = options.name;
  const int nv = static_cast<int>(rest.rows());
  const int nf = static_cast<int>(tris.rows());
  require(nv > 0, name + ": heat weights", "the mesh has no vertices", "give a triangle mesh");
  require(nf > 0, name + ": heat weights", "the mesh has no triangles",
          "give a triangle mesh (heat weights diffuse over triangles)");
  require(options.heat_constant > 0 && std::isfinite(options.heat_constant), name + ": heat weights",
          "heat_constant must be > 0 (got " + format_number(options.heat_constant) + ")",
          "use the default 1");
  require(options.min_weight >= 0 && options.min_weight < 1, name + ": heat weights",
          "min_weight must lie in [0, 1) (got " + format_number(options.min_weight) + ")", "use e.g. 0.01");
  for (int v = 0; v < nv; ++v)
    require(rest.row(v).allFinite(), name + ": vertex " + std::to_string(v), "position is not finite",
            "fix or remove the vertex");
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k)
      require(tris(f, k) >= 0 && tris(f, k) < nv, name + ": triangle " + std::to_string(f),
              "vertex index out of range (got " + std::to_string(tris(f, k)) + ")",
              "indices must lie in [0, " + std::to_string(nv) + ")");
}

/// The bone segments of the joints not in `options.excluded_joints`, in joint order.
std::vector<Bone> active_bones(const std::vector<std::vector<Segment>>& segments_per_joint,
                               const HeatWeightOptions& options) {
  const std::string& name = options.name;
  const int nj = static_cast<int>(segments_per_joint.size());
  std::vector<char> excluded(static_cast<std::size_t>(nj), 0);
  for (int j : options.excluded_joints) {
    require(j >= 0 && j < nj, name + ": heat weights",
            "excluded joint " + std::to_string(j) + " does not exist",
            "exclude joints in [0, " + std::to_string(nj) + ")");
    excluded[static_cast<std::size_t>(j)] = 1;
  }
  std::vector<Bone> bones;
  for (int j = 0; j < nj; ++j) {
    if (excluded[static_cast<std::size_t>(j)]) continue;
    for (const Segment& s : segments_per_joint[static_cast<std::size_t>(j)]) {
      require(s.a.allFinite() && s.b.allFinite(), name + ": bone segment of joint " + std::to_string(j),
              "is not finite", "fix the joint positions");
      bones.emplace_back(j, s);
    }
  }
  require(!bones.empty(), name + ": heat weights", "no joint has a bone segment",
          "give at least one joint that is not excluded a segment");
  return bones;
}

/// Step 1's result: the heat `H_ii` and the joints defining `p` (CSR) per vertex.
struct NearestBones {
  std::vector<double> heat;  ///< `H_ii = c / max(d_i, ε)²`
  std::vector<int> offsets;  ///< vertex i's nearest joints are `joints[offsets[i] .. offsets[i+1])`
  std::vector<int> joints;   ///< ascending per vertex; `p_j(i) = 1/k` for each of these k
};

/// Step 1 (Baran & Popović 2007 §4): the nearest bone(s) of every vertex (ties within a relative
/// 1e-9 shared) and the heat `H_ii = c / max(d_i, ε)²`, ε = 1e-4 × bounding-box diagonal.
NearestBones nearest_bones(const track::Positions& rest, const std::vector<Bone>& bones,
                           double heat_constant) {
  const int nv = static_cast<int>(rest.rows());
  const Eigen::Vector3d lo = rest.colwise().minCoeff().cast<double>().transpose();
  const Eigen::Vector3d hi = rest.colwise().maxCoeff().cast<double>().transpose();
  const double eps = kMinDistanceRatio * std::max((hi - lo).norm(), 1e-12);
  NearestBones out;
  out.heat.resize(static_cast<std::size_t>(nv));
  out.offsets.assign(static_cast<std::size_t>(nv) + 1, 0);
  std::vector<int>& near_joints = out.joints;
  std::vector<double> dist(bones.size());
  for (int v = 0; v < nv; ++v) {
    const Eigen::Vector3d p = rest.row(v).cast<double>().transpose();
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t b = 0; b < bones.size(); ++b) {
      dist[b] = segment_distance(p, bones[b].second);
      best = std::min(best, dist[b]);
    }
    const std::size_t first = near_joints.size();
    for (std::size_t b = 0; b < bones.size(); ++b)
      if (dist[b] <= best * (1 + kTieTolerance) + 1e-300 &&
          std::find(near_joints.begin() + static_cast<std::ptrdiff_t>(first), near_joints.end(),
                    bones[b].first) == near_joints.end())
        near_joints.push_back(bones[b].first);
    std::sort(near_joints.begin() + static_cast<std::ptrdiff_t>(first), near_joints.end());
    out.offsets[static_cast<std::size_t>(v) + 1] = static_cast<int>(near_joints.size());
    const double d = std::max(best, eps);
    out.heat[static_cast<std::size_t>(v)] = heat_constant / (d * d);
  }
  return out;
}

/// Step 2, the operators: the triplets of `−L` (cotangent Laplacian, every corner cotangent
/// clamped to [0, 1e3]) over all vertices, and the lumped (area/3) mass added into `mass`.
std::vector<Eigen::Triplet<double, int>> cotangent_laplacian(const track::Positions& rest,
                                                             const track::Triangles& tris,
                                                             std::vector<double>& mass) {
  const int nf = static_cast<int>(tris.rows());
  std::vector<Eigen::Triplet<double, int>> trip;
  trip.reserve(static_cast<std::size_t>(nf) * 9);
  for (int f = 0; f < nf; ++f) {
    const int idx[3] = {tris(f, 0), tris(f, 1), tris(f, 2)};
    const Eigen::Vector3d x[3] = {rest.row(idx[0]).cast<double>().transpose(),
                                  rest.row(idx[1]).cast<double>().transpose(),
                                  rest.row(idx[2]).cast<double>().transpose()};
    const double area = 0.5 * (x[1] - x[0]).cross(x[2] - x[0]).norm();
    for (int k = 0; k < 3; ++k) {
      mass[static_cast<std::size_t>(idx[k])] += area / 3;
      const int i = idx[(k + 1) % 3], j = idx[(k + 2) % 3];
      if (i == j) continue;
      const double w = 0.5 * corner_cot(x[(k + 1) % 3] - x[k], x[(k + 2) % 3] - x[k]);
      trip.emplace_back(i, j, -w);
      trip.emplace_back(j, i, -w);
      trip.emplace_back(i, i, w);
      trip.emplace_back(j, j, w);
    }
  }
  return trip;
}

/// Step 2's result: the system `(−L + M H) w_j = M H p_j` over the vertices used by a triangle.
struct HeatSystem {
  std::vector<double> mass;  ///< lumped mass per vertex, floored at 1e-6 × the mean where used
  std::vector<char> used;    ///< per vertex: used by a triangle
  std::vector<int> row;      ///< per vertex: its row in the system (-1: unused, left out)
  int n{0};                  ///< rows
  SpMat a;                   ///< `−L + M H`, symmetric positive definite
};

/// Step 2 (Baran & Popović 2007 §4): the symmetric system `−L + M H` of the used vertices, with
/// masses floored at 1e-6 × the mean so vertices of zero-area triangles keep it definite.
HeatSystem heat_system(const track::Positions& rest, const track::Triangles& tris,
                       const std::vector<double>& heat) {
  const int nv = static_cast<int>(rest.rows());
  const int nf = static_cast<int>(tris.rows());
  HeatSystem s;
  s.mass.assign(static_cast<std::size_t>(nv), 0.0);
  std::vector<double>& mass = s.mass;
  std::vector<Eigen::Triplet<double, int>> trip = cotangent_laplacian(rest, tris, mass);
  // Vertices used by no triangle are left out of the system (their weights are p).
  s.used.assign(static_cast<std::size_t>(nv), 0);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) s.used[static_cast<std::size_t>(tris(f, k))] = 1;
  s.row.assign(static_cast<std::size_t>(nv), -1);
  int n = 0;
  double mean_mass = 0;
  for (int v = 0; v < nv; ++v)
    if (s.used[static_cast<std::size_t>(v)]) {
      s.row[static_cast<std::size_t>(v)] = n++;
      mean_mass += mass[static_cast<std::size_t>(v)];
    }
  mean_mass /= n;
  for (auto& t : trip) t = Eigen::Triplet<double, int>(s.row[t.row()], s.row[t.col()], t.value());
  for (int v = 0; v < nv; ++v)
    if (s.used[static_cast<std::size_t>(v)]) {
      double& m = mass[static_cast<std::size_t>(v)];
      m = std::max(m, kMassFloor * std::max(mean_mass, 1e-300));
      trip.emplace_back(s.row[static_cast<std::size_t>(v)], s.row[static_cast<std::size_t>(v)],
                        m * heat[static_cast<std::size_t>(v)]);
    }
  s.n = n;
  s.a.resize(n, n);
  s.a.setFromTriplets(trip.begin(), trip.end());
  return s;
}

/// The joints nearest to some vertex, ascending (the others get w = 0 without a solve).
std::vector<int> joints_to_solve(const NearestBones& near, int nj) {
  std::vector<int> solve_joints;
  std::vector<char> seen(static_cast<std::size_t>(nj), 0);
  for (int j : near.joints) seen[static_cast<std::size_t>(j)] = 1;
  for (int j = 0; j < nj; ++j)
    if (seen[static_cast<std::size_t>(j)]) solve_joints.push_back(j);
  return solve_joints;
}

/// The right-hand sides `M H p_j` of the joints `solve_joints[start .. start + cols)`.
Eigen::MatrixXd block_rhs(const HeatSystem& s, const NearestBones& near, const std::vector<int>& solve_joints,
                          int start, int cols) {
  const int nv = static_cast<int>(s.row.size());
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(s.n, cols);
  for (int v = 0; v < nv; ++v) {
    const int r = s.row[static_cast<std::size_t>(v)];
    if (r < 0) continue;
    const int k0 = near.offsets[static_cast<std::size_t>(v)],
              k1 = near.offsets[static_cast<std::size_t>(v) + 1];
    for (int k = k0; k < k1; ++k) {
      const int j = near.joints[static_cast<std::size_t>(k)];
      for (int c = 0; c < cols; ++c)
        if (solve_joints[static_cast<std::size_t>(start + c)] == j)
          rhs(r, c) =
              s.mass[static_cast<std::size_t>(v)] * near.heat[static_cast<std::size_t>(v)] / (k1 - k0);
    }
  }
  return rhs;
}

/// Step 2, the solves: `w_j` for every joint nearest somewhere, `kBlock` joints per solve with
/// the one factorisation; weights above 1e-7 become candidates. Vertices left out of the system
/// get `p` as their candidates.
Candidates solve_weights(const SpdSolver& solver, const HeatSystem& s, const NearestBones& near, int nj,
                         const HeatWeightOptions& options) {
  const int nv = static_cast<int>(s.row.size());
  const std::vector<int> solve_joints = joints_to_solve(near, nj);
  Candidates acc(static_cast<std::size_t>(nv));
  for (int v = 0; v < nv; ++v)
    if (!s.used[static_cast<std::size_t>(v)]) {
      const int k0 = near.offsets[static_cast<std::size_t>(v)],
                k1 = near.offsets[static_cast<std::size_t>(v) + 1];
      for (int k = k0; k < k1; ++k)
        acc[static_cast<std::size_t>(v)].emplace_back(near.joints[static_cast<std::size_t>(k)],
                                                      1.0f / static_cast<float>(k1 - k0));
    }
  const int total = static_cast<int>(solve_joints.size());
  for (int start = 0; start < total; start += kBlock) {
    const int cols = std::min(kBlock, total - start);
    const Eigen::MatrixXd w = solver.solve(block_rhs(s, near, solve_joints, start, cols));
    for (int v = 0; v < nv; ++v) {
      const int r = s.row[static_cast<std::size_t>(v)];
      if (r < 0) continue;
      for (int c = 0; c < cols; ++c) {
        const double x = w(r, c);
        require(std::isfinite(x), options.name + ": heat weights of vertex " + std::to_string(v),
                "are not finite", "check the mesh for degenerate triangles");
        if (x > 1e-7)
          acc[static_cast<std::size_t>(v)].emplace_back(solve_joints[static_cast<std::size_t>(start + c)],
                                                        static_cast<float>(x));
      }
    }
    if (options.progress) options.progress(start + cols, total);
  }
  return acc;
}

/// Step 3: per vertex, clamp, drop the weights below `min_weight` of the vertex's sum (always
/// keep the largest) and renormalise; joints ascending.
SkinWeights prune_and_normalise(Candidates& acc, const NearestBones& near, float min_weight) {
  const int nv = static_cast<int>(acc.size());
  SkinWeights out;
  out.offsets.reserve(static_cast<std::size_t>(nv) + 1);
  out.offsets.push_back(0);
  for (int v = 0; v < nv; ++v) {
    auto& list = acc[static_cast<std::size_t>(v)];
    std::sort(list.begin(), list.end());
    double sum = 0;
    float best = -1;
    int best_j = -1;
    for (const auto& [j, x] : list) {
      sum += x;
      if (x > best) {
        best = x;
        best_j = j;
      }
    }
    if (!(sum > 0)) {
      // Underflow far from every bone (cannot happen with H > 0 everywhere): nearest bone.
      best_j = near.joints[static_cast<std::size_t>(near.offsets[static_cast<std::size_t>(v)])];
      list.assign(1, {best_j, 1.0f});
      sum = 1;
    }
    double kept = 0;
    for (const auto& [j, x] : list)
      if (x >= min_weight * sum || j == best_j) kept += x;
    for (const auto& [j, x] : list)
      if (x >= min_weight * sum || j == best_j) {
        out.joints.push_back(j);
        out.weights.push_back(static_cast<float>(x / kept));
      }
    out.offsets.push_back(static_cast<int>(out.joints.size()));
    list.clear();
    list.shrink_to_fit();
  }
  return out;
}

}  // namespace

SkinWeights heat_weights(const track::Positions& rest, const track::Triangles& tris,
                         const std::vector<std::vector<Segment>>& segments_per_joint,
                         const HeatWeightOptions& options) {
  check_inputs(rest, tris, options);
  const std::vector<Bone> bones = active_bones(segments_per_joint, options);
  const NearestBones near = nearest_bones(rest, bones, options.heat_constant);  // step 1
  const HeatSystem system = heat_system(rest, tris, near.heat);                 // step 2
  const SpdSolver solver(system.a, options.name);
  Candidates acc = solve_weights(solver, system, near, static_cast<int>(segments_per_joint.size()), options);
  return prune_and_normalise(acc, near, options.min_weight);  // step 3
}

SkinWeights heat_weights(const Rig& rig, HeatWeightOptions options) {
  options.name = rig.name;
  return heat_weights(rig.rest, rig.triangles, joint_segments(rig), options);
}

}  // namespace isokit::skinning
