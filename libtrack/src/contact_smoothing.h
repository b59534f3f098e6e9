// SPDX-License-Identifier: MIT
// Localised Laplacian smoothing at contacts with diffused β (2013 §5, eq. 7), shared by the 2013
// projector and the 2014 tracker (not installed).
#pragma once

#include <cstdint>
#include <vector>

#include "isokit/core/math.h"
#include "isokit/track/mesh.h"
#include "isokit/track/tracker_options.h"

namespace isokit::track::detail {

/// Diffuses β from the contact flags and applies the Laplacian smoothing (double-buffered).
/// With `detail` (one vector per vertex: the tracker's rest Laplacian coordinates turned by the
/// target rotations, SmoothingOptions::keep_detail), each step goes toward the one-ring centroid
/// plus the vertex's detail; without, toward the centroid (2013 eq. 7). Returns the number of
/// vertices with β > 0.
/// With `normals` (unit, per vertex; a zero vector: none known), each step is projected onto
/// the vertex's tangent plane (SmoothingOptions::tangential); `fixed` (per vertex, optional)
/// marks vertices that do not move (open borders).
int contact_smoothing(const Adjacency& adj, const std::vector<std::uint8_t>& contact,
                      const SmoothingOptions& options, std::size_t grain, std::vector<Vec3f>& pts,
                      std::vector<float>& beta, const Vec3f* detail = nullptr, const Vec3f* normals = nullptr,
                      const std::uint8_t* fixed = nullptr);

/// The one-ring centroid of vertex i (deg > 0), summed in neighbour order.
inline Vec3f ring_centroid(const Adjacency& adj, const std::vector<Vec3f>& pts, int i, int deg) {
  Vec3f c{};
  for (int k = adj.offsets[i]; k < adj.offsets[i + 1]; ++k) c += pts[adj.neighbors[k]];
  return c / static_cast<float>(deg);
}

}  // namespace isokit::track::detail
