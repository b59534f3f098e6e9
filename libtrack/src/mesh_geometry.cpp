// SPDX-License-Identifier: MIT
#include "mesh_geometry.h"

#include <algorithm>

#include "isokit/core/mesh_quality.h"

namespace isokit::track::detail {

std::vector<float> mean_edge_lengths(const std::vector<Vec3f>& rest, const Adjacency& adj) {
  const int n = static_cast<int>(rest.size());
  std::vector<float> out(rest.size(), 0.f);
  double total = 0;
  long count = 0;
  for (int i = 0; i < n; ++i) {
    double s = 0;
    for (int k = adj.offsets[i]; k < adj.offsets[i + 1]; ++k) s += norm(rest[adj.neighbors[k]] - rest[i]);
    if (adj.degree(i) > 0) out[i] = static_cast<float>(s / adj.degree(i));
    total += s;
    count += adj.degree(i);
  }
  const float global = count > 0 ? static_cast<float>(total / count) : 1.f;
  for (int i = 0; i < n; ++i)
    if (!(out[i] > 0.f)) out[i] = global > 0.f ? global : 1.f;
  return out;
}

int find_neighbor(const Adjacency& adj, int i, int j) {
  const auto b = adj.neighbors.begin() + adj.offsets[i], e = adj.neighbors.begin() + adj.offsets[i + 1];
  const auto it = std::lower_bound(b, e, j);
  return (it != e && *it == j) ? static_cast<int>(it - adj.neighbors.begin()) : -1;
}

void cotangent_weights(const std::vector<Vec3f>& rest, const Triangles& triangles, const Adjacency& adj,
                       float max_cot, std::vector<float>& weights, std::vector<float>& sums) {
  weights.assign(adj.neighbors.size(), 0.f);
  for (Eigen::Index f = 0; f < triangles.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      // Corner c opposite the edge (a, b).
      const int c = triangles(f, k), a = triangles(f, (k + 1) % 3), b = triangles(f, (k + 2) % 3);
      const Vec3f u = rest[a] - rest[c], v = rest[b] - rest[c];
      const float cr = norm(cross(u, v));
      float cot = 0.f;  // degenerate (zero-area) triangles contribute nothing
      if (cr > 1e-12f * (squared_norm(u) + squared_norm(v))) cot = dot(u, v) / cr;
      cot = std::clamp(cot, 0.f, max_cot);
      weights[find_neighbor(adj, a, b)] += 0.5f * cot;
      weights[find_neighbor(adj, b, a)] += 0.5f * cot;
    }
  }
  const int n = static_cast<int>(rest.size());
  sums.assign(rest.size(), 0.f);
  for (int i = 0; i < n; ++i) {
    float s = 0.f;
    for (int k = adj.offsets[i]; k < adj.offsets[i + 1]; ++k) s += weights[k];
    if (!(s > 0.f) && adj.degree(i) > 0) {  // all incident triangles degenerate: uniform
      for (int k = adj.offsets[i]; k < adj.offsets[i + 1]; ++k) weights[k] = 1.f;
      s = static_cast<float>(adj.degree(i));
    }
    sums[i] = s;
  }
}

Adjacency vertex_faces(const Triangles& triangles, std::size_t num_vertices) {
  Adjacency out;
  out.offsets.assign(num_vertices + 1, 0);
  for (Eigen::Index f = 0; f < triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k) ++out.offsets[static_cast<std::size_t>(triangles(f, k)) + 1];
  for (std::size_t v = 0; v < num_vertices; ++v) out.offsets[v + 1] += out.offsets[v];
  out.neighbors.resize(static_cast<std::size_t>(out.offsets.back()));
  std::vector<int> fill(out.offsets.begin(), out.offsets.end() - 1);
  for (Eigen::Index f = 0; f < triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k) out.neighbors[fill[triangles(f, k)]++] = static_cast<int>(f);
  return out;
}

void grow_rings(const Adjacency& adj, int rings, std::vector<int>& region, std::vector<std::uint8_t>& in) {
  for (int r = 0, begin = 0; r < rings; ++r) {
    const int end = static_cast<int>(region.size());
    for (int a = begin; a < end; ++a)
      for (int k = adj.offsets[region[a]]; k < adj.offsets[region[a] + 1]; ++k)
        if (!in[adj.neighbors[k]]) in[adj.neighbors[k]] = 1, region.push_back(adj.neighbors[k]);
    begin = end;
  }
}

std::vector<Vec3f> area_weighted_normals(const std::vector<Vec3f>& pts, const Triangles& triangles) {
  std::vector<Vec3f> out(pts.size(), Vec3f{});
  for (Eigen::Index f = 0; f < triangles.rows(); ++f) {
    const int a = triangles(f, 0), b = triangles(f, 1), c = triangles(f, 2);
    const Vec3f nf = triangle_normal(pts[a], pts[b], pts[c]);
    out[a] += nf, out[b] += nf, out[c] += nf;
  }
  return out;
}

}  // namespace isokit::track::detail
