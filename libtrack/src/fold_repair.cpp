// SPDX-License-Identifier: MIT
// Fold repair after the contact smoothing (TrackerOptions::fold_repair; not in the papers,
// docs/tracking.md step 5): the triangles around the smoothed vertices are tested again; the
// vertices of those still inverted (and not inverted at rest), grown by `rings` rings, take
// `steps` double-buffered Laplacian steps (β = 1), and the triangles around them are tested again,
// up to `rounds` rounds. Lost and masked vertices stay. Nothing is done when the first round's
// vertices exceed `max_fraction` of the mesh. Every triangle tested gets its flag in `inverted`
// and `fresh[f] = 1`, reset to 0 when one of its vertices moves afterwards: the final statistics
// need not test the fresh ones again.
#include <algorithm>

#include "contact_smoothing.h"
#include "field_eval.h"
#include "isokit/core/parallel.h"
#include "mesh_geometry.h"
#include "stages.h"

namespace isokit::track::detail {

namespace {

class FoldRepair {
 public:
  explicit FoldRepair(TrackState& s)
      : s_(s),
        o_(s.m.options.fold_repair),
        tested_(static_cast<std::size_t>(s.m.triangles.rows()), 0),
        in_(s.n, 0) {
    s.fresh.assign(tested_.size(), 0);
    // The triangles the contact smoothing may have changed: those around a vertex with β > 0.
    for (std::size_t i = 0; i < s.n; ++i)
      if (s.flags.beta[i] > 0.f) add_faces_of(static_cast<int>(i));
  }

  void run() {
    for (int round = 0; round < o_.rounds && !candidates_.empty(); ++round) {
      test_candidates();
      if (region_.empty()) break;
      if (round == 0 && static_cast<double>(region_.size()) > o_.max_fraction * static_cast<double>(s_.n)) {
        // The field disagrees with the mesh broadly (an under-resolved rig): smoothing would
        // erase the shape rather than untangle a fold.
        for (int i : region_) in_[i] = 0;
        break;
      }
      grow_rings(s_.m.adj, o_.rings, region_, in_);
      std::sort(region_.begin(), region_.end());
      smooth_region();
      release_region();
    }
  }

 private:
  bool pinned(int i) const {
    const std::vector<std::uint8_t>& movable = s_.m.repair_mask;
    return s_.flags.lost[i] || (!movable.empty() && !movable[i]) || s_.pinned(std::size_t(i));
  }

  void add_faces_of(int i) {
    const Adjacency& vf = s_.m.vertex_faces;
    for (int k = vf.offsets[i]; k < vf.offsets[i + 1]; ++k) {
      const int f = vf.neighbors[k];
      s_.fresh[f] = 0;
      if (!tested_[f]) tested_[f] = 1, candidates_.push_back(f);
    }
  }

  // Tests the candidate triangles; the region becomes the vertices of the inverted ones (not
  // inverted at rest).
  void test_candidates() {
    std::sort(candidates_.begin(), candidates_.end());
    test_inverted(s_.field, s_.cur, s_.m.triangles, candidates_, s_.m.options.grain, s_.inverted);
    const std::vector<std::uint8_t>& rest = s_.m.rest_inverted;
    region_.clear();
    for (int f : candidates_) {
      const auto t = static_cast<std::size_t>(f);
      tested_[t] = 0;
      s_.fresh[t] = 1;
      if (!s_.inverted[t] || (!rest.empty() && rest[f])) continue;
      for (int k = 0; k < 3; ++k) {
        const int v = s_.m.triangles(f, k);
        if (!in_[v]) in_[v] = 1, region_.push_back(v);
      }
    }
    candidates_.clear();
  }

  // `steps` uniform Laplacian steps of the region's free vertices (double-buffered).
  void smooth_region() {
    const Adjacency& adj = s_.m.adj;
    std::vector<Vec3f>& pts = s_.cur;
    buf_.resize(region_.size());
    for (int step = 0; step < o_.steps; ++step) {
      parallel_for(region_.size(), s_.m.options.grain, [&](std::size_t b, std::size_t e) {
        for (std::size_t a = b; a < e; ++a) {
          const int i = region_[a];
          const int deg = adj.degree(i);
          buf_[a] = pts[i];
          if (deg == 0 || pinned(i)) continue;
          buf_[a] = ring_centroid(adj, pts, i, deg);
        }
      });
      for (std::size_t a = 0; a < region_.size(); ++a) pts[region_[a]] = buf_[a];
    }
  }

  // The region's free vertices were moved: β = 1, touched, their triangles to test again.
  void release_region() {
    for (int i : region_) {
      in_[i] = 0;
      if (pinned(i)) continue;
      s_.flags.beta[i] = 1.f;
      s_.touched[i] = 1;
      add_faces_of(i);
    }
  }

  TrackState& s_;
  const FoldRepairOptions& o_;
  std::vector<std::uint8_t> tested_, in_;
  std::vector<int> candidates_, region_;
  std::vector<Vec3f> buf_;
};

}  // namespace

void repair_folds(TrackState& s) {
  const FoldRepairOptions& o = s.m.options.fold_repair;
  if (o.rounds <= 0 || o.steps <= 0) return;
  FoldRepair(s).run();
  s.stats.smoothed_vertices = count_smoothed(s);
}

}  // namespace isokit::track::detail
