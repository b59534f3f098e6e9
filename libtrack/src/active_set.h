// SPDX-License-Identifier: MIT
// The vertex set one relaxation iteration updates (docs/tracking.md, "Active set"; not installed).
#pragma once

#include <cstdint>
#include <vector>

#include "isokit/track/mesh.h"

namespace isokit::track::detail {

/// The vertices that moved by more than the tolerance in the previous iteration and their
/// one-ring neighbours (whose Jacobi targets changed). Sorted ascending, so the result does not
/// depend on the order in which vertices were found.
class ActiveSet {
 public:
  ActiveSet(std::size_t n, const Adjacency& adj);
  /// Every vertex, ascending.
  const std::vector<int>& all() const { return dense_; }

  /// Rebuilds `active` from the per-vertex flags `moved` (set only inside `active`; all zero on
  /// return).
  void update(std::vector<int>& active, std::vector<std::uint8_t>& moved);

  /// Adds the one-ring neighbours of every vertex of `active` (sorted ascending on return).
  void dilate(std::vector<int>& active);

 private:
  // Few seeds: list their rings and sort; more: mark them (branch-free stores) and scan the marks
  // (the scan costs about as much as 1/32 of the vertices' rings).
  bool small(std::size_t seeds) const { return seeds * 32 < mark_.size(); }
  void mark_ring(int i);
  // `out` <- the marked vertices in ascending order; clears the marks.
  void collect(std::vector<int>& out);

  const Adjacency& adj_;
  std::vector<std::uint8_t> mark_;
  std::vector<int> dense_;
  std::vector<int> seeds_, next_;  // scratch, kept between iterations
};

}  // namespace isokit::track::detail
