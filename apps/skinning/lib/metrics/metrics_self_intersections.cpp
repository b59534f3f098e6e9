// SPDX-License-Identifier: MIT
// Exact self-intersection count of a triangle soup: CGAL's box intersection as the broad phase,
// run per slab in parallel, with the exact-predicate narrow-phase test in its callback. The only translation
// unit with CGAL headers.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "isokit/core/error.h"
#include "isokit/core/parallel.h"
#include "isokit/skinning/metrics.h"
#include "metrics/metrics_check.h"

namespace isokit::skinning {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Segment = Kernel::Segment_3;
using Triangle = Kernel::Triangle_3;
using Box =
    CGAL::Box_intersection_d::Box_with_info_d<double, 3, int, CGAL::Box_intersection_d::ID_FROM_BOX_ADDRESS>;

/// Below this many boxes CGAL's box intersection scans instead of recursing (PMP's value; much
/// faster than the default 10 on folded meshes).
constexpr std::ptrdiff_t kBoxCutoff = 2000;

/// Vertex indices of a triangle.
using Corners = std::array<int, 3>;

/// Two distinct non-degenerate triangles sharing exactly one vertex, `a[0] == b[0]`: they meet
/// beyond it iff the edge opposite the shared vertex of one meets the other triangle (the
/// intersection is convex and contains the shared vertex; if it contains another point, the
/// segment from the shared vertex through it leaves the smaller of the two along the
/// opposite edge, inside the other).
bool meet_beyond_vertex(const std::vector<Point>& p, const Corners& a, const Corners& b) {
  const Point& s = p[a[0]];
  // Both far corners of b strictly on one side of a's plane: b touches that plane only at s.
  const CGAL::Orientation o1 = CGAL::orientation(s, p[a[1]], p[a[2]], p[b[1]]);
  const CGAL::Orientation o2 = CGAL::orientation(s, p[a[1]], p[a[2]], p[b[2]]);
  if (o1 != CGAL::COPLANAR && o1 == o2) return false;
  const Triangle ta(s, p[a[1]], p[a[2]]);
  const Triangle tb(s, p[b[1]], p[b[2]]);
  return CGAL::do_intersect(Segment(p[a[1]], p[a[2]]), tb) ||
         CGAL::do_intersect(Segment(p[b[1]], p[b[2]]), ta);
}

/// Rotates `t` so that `t[0] == v` (v must be a corner), keeping the orientation.
Corners starting_at(const Corners& t, int v) {
  if (t[1] == v) return {t[1], t[2], t[0]};
  if (t[2] == v) return {t[2], t[0], t[1]};
  return t;
}

/// CGAL self_intersections semantics for two distinct, non-degenerate triangles.
bool faces_intersect(const std::vector<Point>& p, const Corners& a, const Corners& b) {
  int shared = 0;
  int shared_vertex[3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (a[i] == b[j]) shared_vertex[shared++] = a[i];
  switch (shared) {
    case 3:  // the same triangle twice
      return true;
    case 2: {  // shared edge (u, v): only a fold onto each other counts
      const int u = shared_vertex[0], v = shared_vertex[1];
      auto other = [&](const Corners& t) {
        for (int c : t)
          if (c != u && c != v) return c;
        return -1;
      };
      const Point& pa = p[other(a)];
      const Point& pb = p[other(b)];
      return CGAL::coplanar(p[u], p[v], pa, pb) &&
             CGAL::coplanar_orientation(p[u], p[v], pa, pb) == CGAL::POSITIVE;
    }
    case 1:
      return meet_beyond_vertex(p, starting_at(a, shared_vertex[0]), starting_at(b, shared_vertex[0]));
    default:
      return CGAL::do_intersect(Triangle(p[a[0]], p[a[1]], p[a[2]]), Triangle(p[b[0]], p[b[1]], p[b[2]]));
  }
}

/// The triangles over exact (double) copies of the float positions.
struct Soup {
  const track::Triangles& triangles;
  std::vector<Point> p;

  Corners corners(std::size_t f) const {
    const auto i = static_cast<Eigen::Index>(f);
    return Corners{triangles(i, 0), triangles(i, 1), triangles(i, 2)};
  }
};

/// The `parallel_for` grain: 0 (one serial pass) when the option `grain` is 0, else `parallel_grain`.
std::size_t grain_for(std::size_t grain, std::size_t parallel_grain) {
  return grain == 0 ? 0 : parallel_grain;
}

/// The positions as CGAL points (float -> double: exact).
std::vector<Point> exact_points(const track::Positions& positions, std::size_t grain) {
  std::vector<Point> p(static_cast<std::size_t>(positions.rows()));
  parallel_for(p.size(), grain_for(grain, kDefaultGrain), [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      const auto i = static_cast<Eigen::Index>(v);
      p[v] = Point(positions(i, 0), positions(i, 1), positions(i, 2));  // float -> double: exact
    }
  });
  return p;
}

/// Degenerate faces (exact collinearity; repeated indices are collinear too): 1, else 0.
std::vector<std::uint8_t> degenerate_faces(const Soup& soup, std::size_t grain) {
  const auto num_faces = static_cast<std::size_t>(soup.triangles.rows());
  std::vector<std::uint8_t> degenerate(num_faces, 0);
  parallel_for(num_faces, grain_for(grain, kDefaultGrain), [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f) {
      const Corners t = soup.corners(f);
      degenerate[f] = CGAL::collinear(soup.p[t[0]], soup.p[t[1]], soup.p[t[2]]) ? 1 : 0;
    }
  });
  return degenerate;
}

/// Closed bounding boxes of the non-degenerate faces (exact: float coordinates), in face order;
/// `all` becomes the box around them.
std::vector<Box> face_boxes(const Soup& soup, const std::vector<std::uint8_t>& degenerate,
                            CGAL::Bbox_3& all) {
  std::vector<Box> boxes;
  boxes.reserve(degenerate.size());
  for (std::size_t f = 0; f < degenerate.size(); ++f) {
    if (degenerate[f]) continue;
    const Corners t = soup.corners(f);
    boxes.emplace_back(soup.p[t[0]].bbox() + soup.p[t[1]].bbox() + soup.p[t[2]].bbox(), static_cast<int>(f));
    all += boxes.back().bbox();
  }
  return boxes;
}

/// Slabs along the longest axis, cut at sampled quantiles of the boxes' lower ends. A box goes
/// to every slab its extent meets; a pair of overlapping boxes is handled only in the slab that
/// holds the lower end of their overlap, so each pair is seen exactly once whatever the cuts.
struct Slabs {
  int axis{0};
  std::vector<double> cuts;                      ///< slab s = [cuts[s-1], cuts[s]), open-ended
  std::vector<std::vector<const Box*>> members;  ///< boxes per slab

  std::size_t slab_of(double x) const {
    return static_cast<std::size_t>(std::upper_bound(cuts.begin(), cuts.end(), x) - cuts.begin());
  }
};

/// Cuts the boxes into about one slab per `grain` boxes (one slab for `grain` 0, at most 4096).
Slabs cut_slabs(const std::vector<Box>& boxes, const CGAL::Bbox_3& all, std::size_t grain) {
  Slabs slabs;
  int& axis = slabs.axis;
  for (int a = 1; a < 3; ++a)
    if (all.max(a) - all.min(a) > all.max(axis) - all.min(axis)) axis = a;
  const std::size_t num_slabs =
      grain == 0 ? 1 : std::clamp<std::size_t>((boxes.size() + grain - 1) / grain, 1, 4096);
  if (num_slabs > 1) {
    std::vector<double> sample;
    const std::size_t step = std::max<std::size_t>(1, boxes.size() / (64 * num_slabs));
    for (std::size_t i = 0; i < boxes.size(); i += step) sample.push_back(boxes[i].min_coord(axis));
    std::sort(sample.begin(), sample.end());
    for (std::size_t s = 1; s < num_slabs; ++s) slabs.cuts.push_back(sample[s * sample.size() / num_slabs]);
  }
  slabs.members.resize(num_slabs);
  for (const Box& b : boxes)
    for (std::size_t s = slabs.slab_of(b.min_coord(axis)), last = slabs.slab_of(b.max_coord(axis)); s <= last;
         ++s)
      slabs.members[s].push_back(&b);
  return slabs;
}

/// The intersecting pairs `fa << 32 | fb` (`fa < fb`), slab after slab, and how many pairs of
/// boxes overlapped.
struct PairHits {
  std::vector<std::uint64_t> found;
  long long candidates{0};
};

/// Broad phase per slab (CGAL box intersection), exact narrow phase (`faces_intersect`) in the
/// callback; slabs in parallel unless `grain` is 0. CGAL reorders each slab's boxes in place.
PairHits intersecting_pairs(const Soup& soup, Slabs& slabs, std::size_t grain) {
  const std::size_t num_slabs = slabs.members.size();
  const int axis = slabs.axis;
  std::vector<std::vector<std::uint64_t>> slab_hits(num_slabs);
  std::vector<long long> slab_candidates(num_slabs, 0);
  parallel_for(num_slabs, grain_for(grain, 1), [&](std::size_t begin, std::size_t end) {
    for (std::size_t s = begin; s < end; ++s) {
      auto& hits = slab_hits[s];
      long long& candidates = slab_candidates[s];
      CGAL::box_self_intersection_d<CGAL::Sequential_tag>(
          slabs.members[s].begin(), slabs.members[s].end(),
          [&](const Box* a, const Box* b) {
            if (slabs.slab_of(std::max(a->min_coord(axis), b->min_coord(axis))) != s) return;
            ++candidates;
            const auto fa = static_cast<std::uint32_t>(std::min(a->info(), b->info()));
            const auto fb = static_cast<std::uint32_t>(std::max(a->info(), b->info()));
            if (faces_intersect(soup.p, soup.corners(fa), soup.corners(fb)))
              hits.push_back(std::uint64_t(fa) << 32 | fb);
          },
          kBoxCutoff);
    }
  });
  PairHits out;
  for (std::size_t s = 0; s < num_slabs; ++s) {
    out.found.insert(out.found.end(), slab_hits[s].begin(), slab_hits[s].end());
    out.candidates += slab_candidates[s];
  }
  return out;
}

/// Fills `details`: the pairs sorted, the degenerate faces (lists capped at `max_pairs`).
void fill_details(PairHits& hits, const std::vector<std::uint8_t>& degenerate, int max_pairs,
                  SelfIntersectionDetails& details) {
  std::vector<std::uint64_t>& found = hits.found;
  const auto cap = static_cast<std::size_t>(std::max(max_pairs, 0));
  std::sort(found.begin(), found.end());
  details.pairs.clear();
  for (std::size_t i = 0; i < found.size() && i < cap; ++i)
    details.pairs.push_back({static_cast<int>(found[i] >> 32), static_cast<int>(found[i] & 0xffffffffu)});
  details.degenerate_faces.clear();
  details.degenerate_count = 0;
  for (std::size_t f = 0; f < degenerate.size(); ++f) {
    if (!degenerate[f]) continue;
    ++details.degenerate_count;
    if (details.degenerate_faces.size() < cap) details.degenerate_faces.push_back(static_cast<int>(f));
  }
  details.candidate_pairs = hits.candidates;
}

}  // namespace

int count_self_intersections(const track::Positions& positions, const track::Triangles& triangles,
                             SelfIntersectionDetails* details, const SelfIntersectionOptions& options) {
  detail::check_triangles(triangles, positions.rows(), "count_self_intersections");
  for (Eigen::Index v = 0; v < positions.rows(); ++v)
    require(positions.row(v).allFinite(), "count_self_intersections: vertex " + std::to_string(v),
            "has a non-finite coordinate", "pass finite positions");
  const std::size_t grain = options.grain;
  const Soup soup{triangles, exact_points(positions, grain)};
  const std::vector<std::uint8_t> degenerate = degenerate_faces(soup, grain);
  CGAL::Bbox_3 all;
  const std::vector<Box> boxes = face_boxes(soup, degenerate, all);
  Slabs slabs = cut_slabs(boxes, all, grain);
  PairHits hits = intersecting_pairs(soup, slabs, grain);
  const int count = static_cast<int>(hits.found.size());
  if (details) fill_details(hits, degenerate, options.max_pairs, *details);
  return count;
}

}  // namespace isokit::skinning
