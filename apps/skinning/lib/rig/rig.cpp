// SPDX-License-Identifier: MIT
#include "isokit/skinning/rig.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "isokit/core/error.h"

namespace isokit::skinning {

int Rig::joint_index(const std::string& joint_name) const {
  for (std::size_t j = 0; j < joints.size(); ++j)
    if (joints[j].name == joint_name) return static_cast<int>(j);
  return -1;
}

std::vector<Affine> rest_pose(const Rig& rig) {
  std::vector<Affine> local(rig.joints.size());
  for (std::size_t j = 0; j < rig.joints.size(); ++j) local[j] = rig.joints[j].rest_local;
  return local;
}

std::vector<Affine> world_transforms(const Rig& rig, const std::vector<Affine>& local) {
  require(
      local.size() == rig.joints.size(), rig.name + ": pose", "one local transform per joint",
      "pass " + std::to_string(rig.joints.size()) + " transforms (got " + std::to_string(local.size()) + ")");
  std::vector<Affine> world(local.size());
  for (std::size_t j = 0; j < local.size(); ++j) {
    const int p = rig.joints[j].parent;
    world[j] = p < 0 ? local[j] : Affine(world[static_cast<std::size_t>(p)] * local[j]);
  }
  return world;
}

std::vector<Affine> skinning_matrices(const Rig& rig, const std::vector<Affine>& local) {
  std::vector<Affine> m = world_transforms(rig, local);
  for (std::size_t j = 0; j < m.size(); ++j) m[j] = m[j] * rig.joints[j].inverse_bind;
  return m;
}

std::vector<Eigen::Vector3d> rest_joint_positions(const Rig& rig) {
  std::vector<Affine> world = world_transforms(rig, rest_pose(rig));
  std::vector<Eigen::Vector3d> p(world.size());
  for (std::size_t j = 0; j < world.size(); ++j) p[j] = world[j].translation();
  return p;
}

namespace {
bool finite(const Affine& a) {
  return a.matrix().allFinite();
}
}  // namespace

void validate(const Rig& rig) {
  const std::string& n = rig.name;
  const int nv = static_cast<int>(rig.rest.rows());
  require(nv > 0, n + ": mesh", "has no vertices", "give a rig with a skinned triangle mesh");
  require(rig.triangles.rows() > 0, n + ": mesh", "has no triangles",
          "give a rig with a skinned triangle mesh");
  require(rig.rest.allFinite(), n + ": mesh", "vertex positions are not finite", "fix the vertex positions");
  for (Eigen::Index f = 0; f < rig.triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int v = rig.triangles(f, k);
      require(v >= 0 && v < nv, n + ": triangle " + std::to_string(f), "vertex index out of range",
              "indices must lie in [0, " + std::to_string(nv) + ")");
    }
  require(!rig.joints.empty(), n + ": skeleton", "has no joints", "give a rig with a skeleton");
  for (std::size_t j = 0; j < rig.joints.size(); ++j) {
    const Joint& jt = rig.joints[j];
    const std::string what = n + ": joint " + std::to_string(j) + " '" + jt.name + "'";
    require(jt.parent < static_cast<int>(j) && jt.parent >= -1, what, "parent must come before the joint",
            "store joints parents first (got parent " + std::to_string(jt.parent) + ")");
    require(finite(jt.rest_local) && finite(jt.inverse_bind), what, "transform is not finite",
            "fix the joint's rest transform / inverse bind matrix");
    const double det = jt.inverse_bind.linear().determinant();
    require(std::abs(det) > 1e-12, what, "inverse bind matrix is singular", "fix the inverse bind matrix");
  }
  if (!rig.weights.empty()) {
    const SkinWeights& w = rig.weights;
    require(static_cast<int>(w.offsets.size()) == nv + 1, n + ": weights", "need one entry per vertex",
            "offsets must have #V + 1 entries");
    require(w.joints.size() == w.weights.size() && static_cast<int>(w.joints.size()) == w.offsets.back(),
            n + ": weights", "array sizes disagree",
            "joints and weights must both have offsets.back() entries");
    for (int v = 0; v < nv; ++v) {
      require(w.offsets[v] <= w.offsets[v + 1], n + ": weights of vertex " + std::to_string(v),
              "offsets decrease", "offsets must be non-decreasing");
      double sum = 0;
      for (int k = w.offsets[v]; k < w.offsets[v + 1]; ++k) {
        const int j = w.joints[k];
        require(j >= 0 && j < static_cast<int>(rig.joints.size()),
                n + ": weights of vertex " + std::to_string(v), "joint index out of range",
                "weights must name existing joints");
        require(std::isfinite(w.weights[k]) && w.weights[k] >= 0,
                n + ": weights of vertex " + std::to_string(v), "weight is negative or not finite",
                "weights must be finite and >= 0");
        sum += w.weights[k];
      }
      require(std::abs(sum - 1.0) <= 1e-3, n + ": weights of vertex " + std::to_string(v),
              "do not sum to 1 (sum " + format_number(sum) + ")", "normalise the weights");
    }
  }
  if (!rig.relax_mask.empty()) {
    require(
        static_cast<int>(rig.relax_mask.size()) == nv, n + ": relaxation mask",
        "has " + std::to_string(rig.relax_mask.size()) + " values for " + std::to_string(nv) + " vertices",
        "give one value per vertex, or none");
    for (std::size_t v = 0; v < rig.relax_mask.size(); ++v)
      require(rig.relax_mask[v] >= 0.f && rig.relax_mask[v] <= 1.f,
              n + ": relaxation mask of vertex " + std::to_string(v),
              "is outside [0, 1] (" + format_number(rig.relax_mask[v]) + ")", "use 0 (rigid) .. 1 (tracked)");
  }
  for (const Clip& c : rig.clips) {
    require(c.fps > 0 && std::isfinite(c.fps), n + ": clip '" + c.name + "'", "fps must be > 0",
            "fix the clip");
    for (std::size_t f = 0; f < c.local.size(); ++f) {
      require(c.local[f].size() == rig.joints.size(),
              n + ": clip '" + c.name + "' frame " + std::to_string(f), "needs one transform per joint",
              "resample the clip");
      for (const Affine& a : c.local[f])
        require(finite(a), n + ": clip '" + c.name + "' frame " + std::to_string(f), "transform not finite",
                "fix the clip");
    }
  }
}

void normalize_weights(SkinWeights& w, int num_vertices, float min_weight, const std::string& rig_name) {
  SkinWeights out;
  out.offsets.reserve(static_cast<std::size_t>(num_vertices) + 1);
  out.offsets.push_back(0);
  std::map<int, float> acc;
  for (int v = 0; v < num_vertices; ++v) {
    acc.clear();
    float sum = 0;
    for (int k = w.offsets[v]; k < w.offsets[v + 1]; ++k) {
      const float x = w.weights[k];
      if (std::isfinite(x) && x > 0) {
        acc[w.joints[k]] += x;
        sum += x;
      }
    }
    require(sum > 0, rig_name + ": weights of vertex " + std::to_string(v), "no positive weight",
            "give every vertex at least one influence, or drop the weights to compute heat weights");
    float kept = 0;
    for (const auto& [j, x] : acc)
      if (x >= min_weight * sum) kept += x;
    for (const auto& [j, x] : acc)
      if (x >= min_weight * sum) {
        out.joints.push_back(j);
        out.weights.push_back(x / kept);
      }
    out.offsets.push_back(static_cast<int>(out.joints.size()));
  }
  w = std::move(out);
}

std::vector<int> dominant_joint(const SkinWeights& w, int num_vertices) {
  std::vector<int> d(static_cast<std::size_t>(num_vertices), -1);
  for (int v = 0; v < num_vertices; ++v) {
    float best = -1;
    for (int k = w.offsets[v]; k < w.offsets[v + 1]; ++k)
      if (w.weights[k] > best || (w.weights[k] == best && w.joints[k] < d[v])) {
        best = w.weights[k];
        d[v] = w.joints[k];
      }
  }
  return d;
}

}  // namespace isokit::skinning
