// SPDX-License-Identifier: MIT
// Statistics of a call (TrackStats; docs/tracking.md, "Statistics").
#include "statistics.h"

#include <algorithm>
#include <cmath>

#include "field_eval.h"
#include "points.h"
#include "stages.h"

namespace isokit::track {

namespace detail {

void vertex_stats(const std::vector<float>& values, const std::vector<float>& iso, const VertexFlags& flags,
                  TrackStats& stats, const std::vector<float>* stiffness) {
  double sum = 0;
  long count = 0;
  float mx = 0.f;
  stats.contact_vertices = 0;
  stats.lost_vertices = 0;
  stats.free_vertices = 0;
  const bool with_free = !flags.free.empty();
  for (std::size_t i = 0; i < values.size(); ++i) {
    stats.contact_vertices += flags.contact[i];
    stats.lost_vertices += flags.lost[i];
    const bool free = with_free && flags.free[i];
    stats.free_vertices += free ? 1 : 0;
    if (free || flags.contact[i] || flags.lost[i] || flags.beta[i] > 0.f || !std::isfinite(values[i]))
      continue;
    if (stiffness && !stiffness->empty() && (*stiffness)[i] >= 1.f) continue;  // pinned
    const float r = std::abs(values[i] - iso[i]);
    mx = std::max(mx, r);
    sum += r;
    ++count;
  }
  stats.max_residual = mx;
  stats.mean_residual = count > 0 ? static_cast<float>(sum / count) : 0.f;
}

int count_flags(const std::vector<std::uint8_t>& flags) {
  int count = 0;
  for (std::uint8_t f : flags) count += f;
  return count;
}

void final_stats(const FieldFunction& field, const std::vector<Vec3f>& pts, const Triangles& triangles,
                 const std::vector<float>& iso, std::size_t grain, VertexFlags& flags, TrackStats& stats) {
  const std::size_t n = pts.size();
  std::vector<float> values(n);
  std::vector<Vec3f> grads(n);
  std::vector<std::uint8_t> fc(n);
  eval_field(field, pts.data(), n, values.data(), grads.data(), fc.data(), grain);
  for (std::size_t i = 0; i < n; ++i)
    if (fc[i]) flags.contact[i] = 1;
  vertex_stats(values, iso, flags, stats);
  stats.inverted_triangles = count_flags(inverted_triangles(field, pts, triangles, grain));
}

int count_smoothed(const TrackState& s) {
  int count = 0;
  for (std::size_t i = 0; i < s.n; ++i) count += s.flags.beta[i] > 0.f ? 1 : 0;
  return count;
}

// The tracker's final statistics. `values` holds each vertex's value at its last evaluation; the
// vertices marked `touched` (moved after the first evaluation, or smoothed) are evaluated again at
// the final positions, the others keep that value (they moved by less than the tolerance since).
// `inverted` holds the flags of the positions before the contact smoothing; the triangles around a
// smoothed vertex (β > 0) are tested again, so the count is exact — except those marked in `fresh`
// (tested at these very positions by the fold repair).
void collect_statistics(TrackState& s) {
  std::vector<int> redo;
  std::vector<std::uint8_t> tri_redo(s.inverted.size(), 0);
  const Adjacency& vf = s.m.vertex_faces;
  for (std::size_t i = 0; i < s.n; ++i) {
    if (s.touched[i]) redo.push_back(static_cast<int>(i));
    if (s.flags.beta[i] > 0.f)
      for (int k = vf.offsets[i]; k < vf.offsets[i + 1]; ++k) {
        const int f = vf.neighbors[k];
        if (s.fresh.empty() || !s.fresh[static_cast<std::size_t>(f)]) tri_redo[f] = 1;
      }
  }
  refresh_values(s.field, s.cur, redo, s.m.options.grain, s.values, s.flags);
  std::vector<int> tris;
  for (std::size_t f = 0; f < tri_redo.size(); ++f)
    if (tri_redo[f]) tris.push_back(static_cast<int>(f));
  test_inverted(s.field, s.cur, s.m.triangles, tris, s.m.options.grain, s.inverted);
  vertex_stats(s.values, s.m.iso, s.flags, s.stats, &s.m.anchor_k);
  s.stats.inverted_triangles = count_flags(s.inverted);
}

}  // namespace detail

int count_inverted_triangles(const FieldFunction& field, const Positions& positions,
                             const Triangles& triangles) {
  const std::vector<Vec3f> pts = detail::to_points(positions, "positions");
  vertex_adjacency(triangles, static_cast<int>(pts.size()));  // validates indices
  VertexFlags flags;
  flags.contact.assign(pts.size(), 0);
  flags.lost.assign(pts.size(), 0);
  flags.beta.assign(pts.size(), 0.f);
  TrackStats stats;
  std::vector<float> iso(pts.size(), 0.5f);
  detail::final_stats(field, pts, triangles, iso, 0, flags, stats);
  return stats.inverted_triangles;
}

}  // namespace isokit::track
