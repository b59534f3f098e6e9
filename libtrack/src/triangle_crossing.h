// SPDX-License-Identifier: MIT
// Exact triangle–triangle crossing tests over a spatial hash, for the orientation repair's
// "never move a triangle through another" rule (docs/tracking.md, step 6; not installed).
#pragma once

#include <cstdint>
#include <vector>

#include "isokit/core/math.h"
#include "isokit/track/mesh.h"

namespace isokit::track::detail {

/// The bounding box of triangle f.
Box3f face_box(const std::vector<Vec3f>& pts, const Triangles& tris, int f);

/// Whether two boxes overlap (touching included).
bool overlap(const Box3f& a, const Box3f& b);

/// A spatial hash of the bounding boxes of the triangles that overlap a few region boxes, over a
/// uniform grid (buckets filled by counting sort); triangles moved after the build are appended to
/// a short list. A triangle that leaves the regions counts as crossing (the hash cannot tell).
class TriangleHash {
 public:
  /// `pts` and `triangles` are referenced, not copied: `crosses_any` reads the current positions.
  TriangleHash(const std::vector<Vec3f>& pts, const Triangles& triangles, float cell,
               std::vector<Box3f> regions);

  /// The face moved: also found in the cells of its new box.
  void update(int f) { moved_.push_back(f); }

  /// Whether face f (at the current positions) crosses a face it does not share an edge with:
  /// exact orientation tests in double precision (QUALITY.md's self-intersection pairs).
  bool crosses_any(int f);

 private:
  // Visits the keys of the cells the face's box overlaps; false (nothing visited) for a box over
  // more than 4096 cells.
  template <class F>
  bool for_cells(int f, F&& visit) const;

  const std::vector<Vec3f>& pts_;
  const Triangles& tris_;
  float inv_cell_;
  std::vector<Box3f> regions_;
  std::size_t mask_{0};
  std::vector<int> start_, entries_, moved_, big_;
  std::vector<std::uint32_t> stamp_;
  std::uint32_t now_{0};
};

}  // namespace isokit::track::detail
