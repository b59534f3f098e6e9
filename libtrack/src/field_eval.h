// SPDX-License-Identifier: MIT
// Batched field evaluation: at points, at listed vertices, and the inverted-triangle test at
// triangle centroids (not installed).
#pragma once

#include <cstdint>
#include <vector>

#include "isokit/core/math.h"
#include "isokit/track/field.h"
#include "isokit/track/mesh.h"
#include "isokit/track/tracker_options.h"

namespace isokit::track::detail {

/// Calls the field over [0, n) in parallel chunks (each chunk one call; `contact` zero-filled first).
void eval_field(const FieldFunction& field, const Vec3f* pts, std::size_t n, float* values, Vec3f* grads,
                std::uint8_t* contact, std::size_t grain);

/// Evaluates the field at the listed vertices: `values` updated, field contacts OR-ed into
/// `flags.contact`.
void refresh_values(const FieldFunction& field, const std::vector<Vec3f>& pts, const std::vector<int>& redo,
                    std::size_t grain, std::vector<float>& values, VertexFlags& flags);

/// Evaluates the field at the centroids of the triangles `tris` and sets `inverted[f]` for each
/// (isokit/core/mesh_quality.h: the normal points along `+∇f`; a zero gradient does not count).
void test_inverted(const FieldFunction& field, const std::vector<Vec3f>& pts, const Triangles& triangles,
                   const std::vector<int>& tris, std::size_t grain, std::vector<std::uint8_t>& inverted);

/// Per triangle: 1 if inverted (`test_inverted`). With `candidates`, only the listed triangles
/// are tested (the others get 0).
std::vector<std::uint8_t> inverted_triangles(const FieldFunction& field, const std::vector<Vec3f>& pts,
                                             const Triangles& triangles, std::size_t grain,
                                             const std::vector<int>* candidates = nullptr);

/// Per vertex: 1 if the field at the rest positions `rest` does not locate the vertex
/// (TrackerOptions::free_vertex_angle_deg): its inward direction ∇f/|∇f| is more than that angle
/// from the inward area-weighted vertex normal, or |∇f| ≤ min_gradient or not finite. A vertex
/// without triangles is never free; with the angle at 180 none is.
std::vector<std::uint8_t> free_vertices(const FieldFunction& field, const std::vector<Vec3f>& rest,
                                        const Triangles& triangles, const TrackerOptions& options);

}  // namespace isokit::track::detail
