// SPDX-License-Identifier: MIT
#include "isokit/skinning/rigid_pieces.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

#include "isokit/core/error.h"

namespace isokit::skinning {

namespace {

/// Component id per vertex (over triangles: vertices sharing a triangle), by union-find;
/// vertices in no triangle get -1.
std::vector<int> components(const Rig& rig, int* count) {
  const auto n = static_cast<std::size_t>(rig.rest.rows());
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int v) {
    while (parent[static_cast<std::size_t>(v)] != v) {
      parent[static_cast<std::size_t>(v)] =
          parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(v)])];
      v = parent[static_cast<std::size_t>(v)];
    }
    return v;
  };
  std::vector<char> used(n, 0);
  for (Eigen::Index t = 0; t < rig.triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = find(rig.triangles(t, k));
      const int b = find(rig.triangles(t, (k + 1) % 3));
      used[static_cast<std::size_t>(rig.triangles(t, k))] = 1;
      if (a != b) parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
    }
  std::vector<int> id(n, -1), id_of_root(n, -1);
  *count = 0;
  for (std::size_t v = 0; v < n; ++v) {
    if (!used[v]) continue;
    const auto r = static_cast<std::size_t>(find(static_cast<int>(v)));
    if (id_of_root[r] < 0) id_of_root[r] = (*count)++;
    id[v] = id_of_root[r];
  }
  return id;
}

/// A vertex's influences as (joint, weight) pairs sorted by joint (weights are not sorted in
/// every source).
std::vector<std::pair<int, float>> influences(const SkinWeights& w, int v) {
  std::vector<std::pair<int, float>> out;
  for (int k = w.offsets[static_cast<std::size_t>(v)]; k < w.offsets[static_cast<std::size_t>(v) + 1]; ++k)
    out.emplace_back(w.joints[static_cast<std::size_t>(k)], w.weights[static_cast<std::size_t>(k)]);
  std::sort(out.begin(), out.end());
  return out;
}

bool same_influences(const std::vector<std::pair<int, float>>& a, const std::vector<std::pair<int, float>>& b,
                     double tolerance) {
  if (a.size() != b.size()) return false;
  for (std::size_t k = 0; k < a.size(); ++k)
    if (a[k].first != b[k].first || std::abs(a[k].second - b[k].second) > tolerance) return false;
  return true;
}

}  // namespace

std::vector<RigidPiece> find_rigid_pieces(const Rig& rig, double tolerance) {
  require(std::isfinite(tolerance) && tolerance >= 0, "find_rigid_pieces tolerance",
          "must be finite and >= 0 (got " + format_number(tolerance) + ")", "use e.g. 1e-4");
  if (rig.weights.empty()) return {};
  int count = 0;
  const std::vector<int> id = components(rig, &count);
  std::vector<int> first(static_cast<std::size_t>(count), -1);  // the first vertex of each component
  std::vector<std::vector<std::pair<int, float>>> shared(static_cast<std::size_t>(count));
  std::vector<char> rigid(static_cast<std::size_t>(count), 1);
  for (int v = 0; v < static_cast<int>(id.size()); ++v) {
    const int c = id[static_cast<std::size_t>(v)];
    if (c < 0 || !rigid[static_cast<std::size_t>(c)]) continue;
    int& f = first[static_cast<std::size_t>(c)];
    if (f < 0) {
      f = v;
      shared[static_cast<std::size_t>(c)] = influences(rig.weights, v);
    } else if (!same_influences(shared[static_cast<std::size_t>(c)], influences(rig.weights, v), tolerance)) {
      rigid[static_cast<std::size_t>(c)] = 0;
    }
  }
  std::vector<RigidPiece> pieces(static_cast<std::size_t>(count));
  for (int v = 0; v < static_cast<int>(id.size()); ++v) {
    const int c = id[static_cast<std::size_t>(v)];
    if (c >= 0 && rigid[static_cast<std::size_t>(c)])
      pieces[static_cast<std::size_t>(c)].vertices.push_back(v);
  }
  for (Eigen::Index t = 0; t < rig.triangles.rows(); ++t) {
    const int c = id[static_cast<std::size_t>(rig.triangles(t, 0))];
    if (rigid[static_cast<std::size_t>(c)]) ++pieces[static_cast<std::size_t>(c)].triangles;
  }
  std::vector<RigidPiece> out;
  for (int c = 0; c < count; ++c) {
    if (!rigid[static_cast<std::size_t>(c)]) continue;
    RigidPiece p = std::move(pieces[static_cast<std::size_t>(c)]);
    for (const auto& [j, w] : shared[static_cast<std::size_t>(c)]) {
      p.joints.push_back(j);
      p.weights.push_back(w);
    }
    out.push_back(std::move(p));
  }
  return out;
}

}  // namespace isokit::skinning
