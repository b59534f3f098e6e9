// SPDX-License-Identifier: MIT
// Rest-pose mesh geometry and topology the tracker precomputes: edge lengths, cotangent weights,
// the triangles around each vertex, ring growth (not installed).
#pragma once

#include <cstdint>
#include <vector>

#include "isokit/core/math.h"
#include "isokit/track/mesh.h"

namespace isokit::track::detail {

/// Mean rest length of each vertex's edges (global mean for isolated vertices).
std::vector<float> mean_edge_lengths(const std::vector<Vec3f>& rest, const Adjacency& adj);

/// Index of neighbour `j` in the row of `i` (CSR), or -1.
int find_neighbor(const Adjacency& adj, int i, int j);

/// Cotangent weights aligned with adj.neighbors, clamped per corner to [0, max_cot]; a vertex
/// whose weights sum to 0 gets uniform weights 1. Also returns the per-vertex sums.
void cotangent_weights(const std::vector<Vec3f>& rest, const Triangles& triangles, const Adjacency& adj,
                       float max_cot, std::vector<float>& weights, std::vector<float>& sums);

/// Triangles around each vertex, in CSR form (`neighbors` holds triangle indices).
Adjacency vertex_faces(const Triangles& triangles, std::size_t num_vertices);

/// Per vertex: the sum of its triangles' normals `(b - a) x (c - a)` (area-weighted, outward for
/// counter-clockwise triangles; not normalised, 0 for a vertex without triangles).
std::vector<Vec3f> area_weighted_normals(const std::vector<Vec3f>& pts, const Triangles& triangles);

/// Appends to `region` the vertices within `rings` rings of it (breadth first); `in` flags members.
void grow_rings(const Adjacency& adj, int rings, std::vector<int>& region, std::vector<std::uint8_t>& in);

}  // namespace isokit::track::detail
