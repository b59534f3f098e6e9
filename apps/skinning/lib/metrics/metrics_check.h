// SPDX-License-Identifier: MIT
// Input checks shared by the metrics and the renderer (private).
#pragma once

#include <string>

#include "isokit/core/error.h"
#include "isokit/track/mesh.h"

namespace isokit::skinning::detail {

/// Throws InputError naming the first triangle with an index outside `[0, #V)`.
inline void check_triangles(const track::Triangles& triangles, Eigen::Index num_vertices,
                            const std::string& what) {
  for (Eigen::Index f = 0; f < triangles.rows(); ++f)
    for (int c = 0; c < 3; ++c) {
      const int v = triangles(f, c);
      if (v < 0 || v >= num_vertices)
        throw InputError(what + ": triangle " + std::to_string(f) + " has vertex index " + std::to_string(v) +
                         " outside [0, " + std::to_string(num_vertices) +
                         "); pass triangles over the given positions");
    }
}

/// Throws InputError unless both position arrays have the same number of vertices.
inline void check_same_vertex_count(const track::Positions& a, const track::Positions& b,
                                    const std::string& what) {
  if (a.rows() != b.rows())
    throw InputError(what + ": the two meshes have " + std::to_string(a.rows()) + " and " +
                     std::to_string(b.rows()) +
                     " vertices; pass two poses of the same mesh (same vertex order)");
}

}  // namespace isokit::skinning::detail
