// SPDX-License-Identifier: MIT
// The tracker's internal vertex order (TrackerOptions::reorder_vertices; not installed).
#pragma once

#include <vector>

#include "isokit/core/math.h"

namespace isokit::track::detail {

/// A cache-friendly vertex order: the vertices sorted by the Morton code of their position
/// (21 bits per axis over the bounding box; ties by index). `order[k]` is the k-th vertex.
std::vector<int> spatial_order(const std::vector<Vec3f>& pts);

}  // namespace isokit::track::detail
