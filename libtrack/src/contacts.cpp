// SPDX-License-Identifier: MIT
// Contact vertices after the relaxation (docs/tracking.md, step 3): the field's contact flags
// (the gradient-angle rule of 2013 §5 flags vertices during the sweeps, newton_step.h) and the
// vertices of folds — triangles the relaxation left inverted (`fold_contacts`, not in the papers).
#include <cmath>

#include "field_eval.h"
#include "isokit/core/mesh_quality.h"
#include "stages.h"

namespace isokit::track::detail {

namespace {

// Unless test_all_triangles, only the triangles that may be inverted are tested at their
// centroid: those whose normal deviates by more than kFoldCandidateDeg from the outward
// direction -∇f/|∇f| last evaluated at one of their vertices, with a contact or lost vertex, or
// inverted at rest or at the end of the last call. Elsewhere the field would have to turn by
// more than that angle inside the triangle, which it does only across contact creases.
std::vector<int> fold_candidates(const TrackState& s) {
  const Triangles& tris = s.m.triangles;
  const std::vector<std::uint8_t>& last = s.m.last_inverted;
  const std::vector<std::uint8_t>& rest = s.m.rest_inverted;
  const float cos_candidate = std::cos(kFoldCandidateDeg * kPiF / 180.f);
  std::vector<int> candidates;
  for (Eigen::Index f = 0; f < tris.rows(); ++f) {
    const int v0 = tris(f, 0), v1 = tris(f, 1), v2 = tris(f, 2);
    const Vec3f c = triangle_normal(s.cur[v0], s.cur[v1], s.cur[v2]);
    const float len = std::sqrt(squared_norm(c));
    const std::size_t t = static_cast<std::size_t>(f);
    bool candidate = !(len > 0.f) || (!last.empty() && last[t]) || (!rest.empty() && rest[t]);
    for (int v : {v0, v1, v2}) {
      if (candidate) break;
      const Vec3f nv = s.normal[v];
      candidate = s.flags.contact[v] || s.field_contact[v] || s.flags.lost[v] || nv == Vec3f{} ||
                  -dot(c, nv) < cos_candidate * len;
    }
    if (candidate) candidates.push_back(static_cast<int>(f));
  }
  return candidates;
}

}  // namespace

void mark_contacts(TrackState& s) {
  const TrackerOptions& o = s.m.options;
  // Contacts reported by the field at the last evaluation also get smoothed.
  for (std::size_t i = 0; i < s.n; ++i)
    if (s.field_contact[i] && !s.flags.lost[i] && !s.pinned(i)) s.flags.contact[i] = 1;
  // Folds: the vertices of a triangle that the relaxation left inverted (typically at a crease
  // where no consecutive gradients differed by the contact angle) are smoothed like contacts;
  // triangles already inverted at rest (mark_rest_inversions) are not folds.
  std::vector<int> candidates;
  if (!o.test_all_triangles) candidates = fold_candidates(s);
  s.inverted = inverted_triangles(s.field, s.cur, s.m.triangles, o.grain,
                                  o.test_all_triangles ? nullptr : &candidates);
  if (!o.fold_contacts) return;
  const Triangles& tris = s.m.triangles;
  const std::vector<std::uint8_t>& rest = s.m.rest_inverted;
  for (Eigen::Index f = 0; f < tris.rows(); ++f) {
    const std::size_t t = static_cast<std::size_t>(f);
    if (s.inverted[t] && (rest.empty() || !rest[t]))
      for (int k = 0; k < 3; ++k)
        if (!s.flags.lost[tris(f, k)] && !s.pinned(std::size_t(tris(f, k)))) s.flags.contact[tris(f, k)] = 1;
  }
}

}  // namespace isokit::track::detail
