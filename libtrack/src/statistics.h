// SPDX-License-Identifier: MIT
// Per-call statistics (TrackStats) shared by the tracker and the projector (not installed).
#pragma once

#include <cstdint>
#include <vector>

#include "isokit/core/math.h"
#include "isokit/track/field.h"
#include "isokit/track/mesh.h"

namespace isokit::track::detail {

/// Contact / lost / free counts and iso residuals over the vertices with β == 0 that are neither
/// contact, lost nor free (`flags.free` may be empty: none), nor pinned (`stiffness` 1; null or
/// empty: none), and have a finite value.
void vertex_stats(const std::vector<float>& values, const std::vector<float>& iso, const VertexFlags& flags,
                  TrackStats& stats, const std::vector<float>* stiffness = nullptr);

/// The number of flags set.
int count_flags(const std::vector<std::uint8_t>& flags);

/// Final statistics: residuals over vertices with β == 0 and a usable field value, contact
/// flags from the field (OR-ed into `contact`), inverted triangles (every triangle tested).
void final_stats(const FieldFunction& field, const std::vector<Vec3f>& pts, const Triangles& triangles,
                 const std::vector<float>& iso, std::size_t grain, VertexFlags& flags, TrackStats& stats);

}  // namespace isokit::track::detail
