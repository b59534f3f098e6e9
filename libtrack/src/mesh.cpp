// SPDX-License-Identifier: MIT
#include "isokit/track/mesh.h"

#include <algorithm>
#include <string>

#include "detail.h"
#include "isokit/core/error.h"

namespace isokit::track {

namespace detail {

void validate_triangles(const Triangles& triangles, int num_vertices) {
  require(num_vertices >= 0, "vertex_adjacency num_vertices",
          "is negative (" + std::to_string(num_vertices) + ")", "pass the vertex count");
  // Messages are built only on failure: this runs over every triangle of large meshes.
  for (Eigen::Index f = 0; f < triangles.rows(); ++f) {
    const int a = triangles(f, 0), b = triangles(f, 1), c = triangles(f, 2);
    for (int v : {a, b, c})
      if (v < 0 || v >= num_vertices)
        require(false, "triangle " + std::to_string(f),
                "vertex index " + std::to_string(v) + " is outside [0, " + std::to_string(num_vertices) + ")",
                "fix the face list or pass all vertices");
    if (a == b || b == c || a == c)
      require(false, "triangle " + std::to_string(f),
              "repeats a vertex (" + std::to_string(a) + ", " + std::to_string(b) + ", " + std::to_string(c) +
                  ")",
              "remove degenerate triangles before building the mesh");
  }
}

}  // namespace detail

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
