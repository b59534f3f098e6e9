// SPDX-License-Identifier: MIT
// Input checks of the tracker and the projector: meshes, per-call inputs, options. Each throws
// InputError naming the item, why it is wrong and the fix (not installed).
#pragma once

#include <cstddef>
#include <vector>

#include "isokit/core/math.h"
#include "isokit/track/field.h"
#include "isokit/track/mesh.h"
#include "isokit/track/tracker_options.h"

namespace isokit::track::detail {

/// Every triangle's indices lie in [0, num_vertices) and are distinct; throws naming the triangle.
void validate_triangles(const Triangles& triangles, int num_vertices);
/// Non-empty rest positions, one iso-value per vertex, valid triangles.
void validate_mesh(const Positions& rest, const Triangles& triangles, std::size_t iso_size);

/// Checks the per-call inputs shared by the tracker and the projector: one position per vertex
/// and a non-empty field function.
void validate_call(const Positions& positions, std::size_t n, const FieldFunction& field);

/// One finite rotation per vertex, or none.
void validate_rotations(const std::vector<Mat3f>& rotations, std::size_t n);

/// Every value finite.
void validate_iso_values(const std::vector<float>& iso);

/// Every option in its documented range (tracker_options.h).
void validate_options(const TrackerOptions& options);

}  // namespace isokit::track::detail
