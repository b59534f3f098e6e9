// SPDX-License-Identifier: MIT
/// \file
/// Flat triangle-mesh arrays and the compressed (CSR) one-ring adjacency the tracker's hot loops
/// walk. Meshes come in as plain Eigen arrays (`#V by 3` positions, `#F by 3` vertex indices).
#pragma once

#include <vector>

#include <Eigen/Core>

namespace isokit::track {

/// `#V by 3` row-major vertex positions.
using Positions = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// `#F by 3` row-major triangle vertex indices (counter-clockwise seen from outside).
using Triangles = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// One-ring neighbours in CSR form: the neighbours of vertex `v` are
/// `neighbors[offsets[v] .. offsets[v+1])`, sorted ascending, without duplicates.
/// `offsets.size() == #V + 1`. Isolated vertices have no neighbours.
struct Adjacency {
  std::vector<int> offsets;
  std::vector<int> neighbors;

  int degree(int v) const { return offsets[v + 1] - offsets[v]; }
};

/// Builds the vertex one-ring adjacency of `triangles` over `num_vertices` vertices.
/// \throw InputError naming the triangle if an index is out of `[0, num_vertices)` or a
/// triangle repeats a vertex, or if `num_vertices < 0`.
Adjacency vertex_adjacency(const Triangles& triangles, int num_vertices);

}  // namespace isokit::track
