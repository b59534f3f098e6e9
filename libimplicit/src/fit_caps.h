// SPDX-License-Identifier: MIT
/// \file
/// Caps over a part's open borders (docs/skinning.md, "Decision: capping a part's borders"; not
/// in the papers): the fit's own steps, internal to libimplicit.
#pragma once

#include <array>
#include <vector>

#include "isokit/implicit/hrbf.h"

namespace isokit::implicit::detail {

/// The closed boundary loops of a triangle set: chains of the edges used by exactly one
/// triangle, each in the direction its triangle runs it (vertex indices). Edges of three or
/// more triangles are not borders; a chain that does not close, or closes in fewer than three
/// vertices, is dropped.
std::vector<std::vector<int>> boundary_loops(const std::vector<std::array<int, 3>>& triangles, int vertices);

/// A dome over one boundary loop (`loop` indexes `v`): its centre lifted `height × R × |n · axis|`
/// out of the part, and rings of points down to the rim, about `spacing` apart, with the dome's
/// normals. n: the cap's outward normal, against the loop's Newell normal (the triangles run
/// their border the other way round from a cap); R: the loop's mean distance to its centroid in
/// its plane; `axis`: the bone (unit). A hole at a bone end (n along the bone, where the next
/// limb goes on) gets the full dome, a hole in the side of the part (a neighbour's patch) a
/// flat cap that does not bulge out of the side.
/// \return the samples; empty when the loop encloses no area (a slit: vector area below 5 %
/// of a circle's with the same perimeter).
std::vector<HrbfSample> loop_cap(const std::vector<Vec3d>& v, const std::vector<int>& loop, double height,
                                 double spacing, const Vec3d& axis);

/// The part closed for measuring a fit: `vertices` / `triangles` plus a fan from each border
/// loop's centroid over the loop (its flat cap), appended to both.
void close_with_fans(std::vector<Vec3d>& vertices, std::vector<std::array<int, 3>>& triangles);

}  // namespace isokit::implicit::detail
