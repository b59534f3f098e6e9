// SPDX-License-Identifier: MIT
#include "isokit/track/mesh.h"

#include <algorithm>
#include <string>

#include "validation.h"

namespace isokit::track {

Adjacency vertex_adjacency(const Triangles& triangles, int num_vertices) {
  detail::validate_triangles(triangles, num_vertices);
  const Eigen::Index nf = triangles.rows();
  // Count directed half-edges per vertex (each triangle gives every corner two neighbours),
  // fill, then sort and deduplicate each row in place.
  std::vector<int> count(static_cast<std::size_t>(num_vertices) + 1, 0);
  for (Eigen::Index f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) count[static_cast<std::size_t>(triangles(f, k)) + 1] += 2;
  for (std::size_t v = 1; v < count.size(); ++v) count[v] += count[v - 1];
  std::vector<int> raw(static_cast<std::size_t>(count.back()));
  std::vector<int> fill(count.begin(), count.end() - 1);
  for (Eigen::Index f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int v = triangles(f, k);
      raw[static_cast<std::size_t>(fill[v]++)] = triangles(f, (k + 1) % 3);
      raw[static_cast<std::size_t>(fill[v]++)] = triangles(f, (k + 2) % 3);
    }
  Adjacency adj;
  adj.offsets.assign(static_cast<std::size_t>(num_vertices) + 1, 0);
  adj.neighbors.reserve(raw.size() / 2);
  for (int v = 0; v < num_vertices; ++v) {
    auto first = raw.begin() + count[v], last = raw.begin() + count[v + 1];
    std::sort(first, last);
    last = std::unique(first, last);
    adj.neighbors.insert(adj.neighbors.end(), first, last);
    adj.offsets[static_cast<std::size_t>(v) + 1] = static_cast<int>(adj.neighbors.size());
  }
  return adj;
}

}  // namespace isokit::track
