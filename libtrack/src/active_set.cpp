// SPDX-License-Identifier: MIT
#include "active_set.h"

#include <algorithm>

namespace isokit::track::detail {

ActiveSet::ActiveSet(std::size_t n, const Adjacency& adj) : adj_(adj), mark_(n, 0), dense_(n) {
  for (std::size_t i = 0; i < n; ++i) dense_[i] = static_cast<int>(i);
}

void ActiveSet::update(std::vector<int>& active, std::vector<std::uint8_t>& moved) {
  const std::size_t n = dense_.size();
  std::size_t count = 0;
  for (int i : active) count += moved[i];
  if (count == n) {  // everything still moves: keep every vertex
    std::fill(moved.begin(), moved.end(), std::uint8_t{0});
    return;
  }
  if (small(count)) {
    seeds_.clear();
    for (int i : active)
      if (moved[i]) seeds_.push_back(i), moved[i] = 0;
    dilate(seeds_);
    active.swap(seeds_);
    return;
  }
  for (int i : active)
    if (moved[i]) moved[i] = 0, mark_ring(i);
  collect(active);
}

void ActiveSet::dilate(std::vector<int>& active) {
  if (!small(active.size())) {
    for (int i : active) mark_ring(i);
    collect(active);
    return;
  }
  next_.clear();
  auto add = [&](int v) {
    if (!mark_[v]) mark_[v] = 1, next_.push_back(v);
  };
  for (int i : active) {
    add(i);
    for (int k = adj_.offsets[i]; k < adj_.offsets[i + 1]; ++k) add(adj_.neighbors[k]);
  }
  for (int v : next_) mark_[v] = 0;
  std::sort(next_.begin(), next_.end());
  active.swap(next_);
}

void ActiveSet::mark_ring(int i) {
  mark_[i] = 1;
  for (int k = adj_.offsets[i]; k < adj_.offsets[i + 1]; ++k) mark_[adj_.neighbors[k]] = 1;
}

void ActiveSet::collect(std::vector<int>& out) {
  const std::size_t n = mark_.size();
  out.resize(n);
  std::size_t c = 0;
  for (std::size_t v = 0; v < n; ++v) {
    out[c] = static_cast<int>(v);
    c += mark_[v];
    mark_[v] = 0;
  }
  out.resize(c);
}

}  // namespace isokit::track::detail
