// SPDX-License-Identifier: MIT
// Connected components of a triangle mesh and their border, non-manifold and misoriented edges.
#include "isokit/skinning/mesh_closure.h"

#include <algorithm>
#include <cstdint>
#include <utility>

#include "metrics/metrics_check.h"

namespace isokit::skinning {
namespace {

/// Union-find root with path halving.
int root(std::vector<int>& parent, int v) {
  while (parent[v] != v) v = parent[v] = parent[parent[v]];
  return v;
}

/// Component of each triangle (joined through shared vertices), numbered by first triangle.
std::vector<int> triangle_components(const track::Triangles& triangles, Eigen::Index num_vertices,
                                     int& count) {
  std::vector<int> parent(static_cast<std::size_t>(num_vertices));
  for (std::size_t v = 0; v < parent.size(); ++v) parent[v] = static_cast<int>(v);
  for (Eigen::Index f = 0; f < triangles.rows(); ++f)
    for (int c = 1; c < 3; ++c) parent[root(parent, triangles(f, c))] = root(parent, triangles(f, 0));
  std::vector<int> id(parent.size(), -1), component(static_cast<std::size_t>(triangles.rows()));
  count = 0;
  for (Eigen::Index f = 0; f < triangles.rows(); ++f) {
    int& c = id[static_cast<std::size_t>(root(parent, triangles(f, 0)))];
    if (c < 0) c = count++;
    component[static_cast<std::size_t>(f)] = c;
  }
  return component;
}

/// Classifies each undirected edge by its directed uses (`lo << 33 | hi << 1 | reversed`, sorted)
/// and adds its defect to the component of its triangles.
void count_edge_defects(const track::Triangles& triangles, MeshClosure& out) {
  std::vector<std::pair<std::uint64_t, int>> uses;  // (key, component)
  uses.reserve(static_cast<std::size_t>(triangles.rows()) * 3);
  for (Eigen::Index f = 0; f < triangles.rows(); ++f)
    for (int c = 0; c < 3; ++c) {
      const int a = triangles(f, c), b = triangles(f, (c + 1) % 3);
      if (a == b) continue;
      const auto lo = static_cast<std::uint64_t>(std::min(a, b)),
                 hi = static_cast<std::uint64_t>(std::max(a, b));
      uses.push_back({lo << 33 | hi << 1 | (a > b ? 1u : 0u), out.component[static_cast<std::size_t>(f)]});
    }
  std::sort(uses.begin(), uses.end());
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i, reversed = 0;
    for (; j < uses.size() && uses[j].first >> 1 == uses[i].first >> 1; ++j) reversed += uses[j].first & 1;
    MeshComponent& comp = out.components[static_cast<std::size_t>(uses[i].second)];
    const std::size_t n = j - i;
    comp.border_edges += n == 1 ? 1 : 0;
    comp.non_manifold_edges += n > 2 ? 1 : 0;
    comp.misoriented_edges += n == 2 && reversed != 1 ? 1 : 0;
    i = j;
  }
}

}  // namespace

bool MeshClosure::closed() const {
  return !components.empty() && closed_components() == static_cast<int>(components.size());
}

int MeshClosure::closed_components() const {
  return static_cast<int>(
      std::count_if(components.begin(), components.end(), [](const MeshComponent& c) { return c.closed(); }));
}

MeshClosure mesh_closure(const track::Triangles& triangles, Eigen::Index num_vertices) {
  detail::check_triangles(triangles, num_vertices, "mesh_closure");
  MeshClosure out;
  int count = 0;
  out.component = triangle_components(triangles, num_vertices, count);
  out.components.resize(static_cast<std::size_t>(count));
  for (int c : out.component) ++out.components[static_cast<std::size_t>(c)].triangles;
  count_edge_defects(triangles, out);
  return out;
}

}  // namespace isokit::skinning
