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

}  // namespace

int count_self_intersections(const track::Positions& positions, const track::Triangles& triangles,
                             SelfIntersectionDetails* details, const SelfIntersectionOptions& options) {
  detail::check_triangles(triangles, positions.rows(), "count_self_intersections");
  for (Eigen::Index v = 0; v < positions.rows(); ++v)
    require(positions.row(v).allFinite(), "count_self_intersections: vertex " + std::to_string(v),
            "has a non-finite coordinate", "pass finite positions");
  const auto num_faces = static_cast<std::size_t>(triangles.rows());
  const std::size_t grain = options.grain;

  std::vector<Point> p(static_cast<std::size_t>(positions.rows()));
  parallel_for(p.size(), grain == 0 ? 0 : kDefaultGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      const auto i = static_cast<Eigen::Index>(v);
      p[v] = Point(positions(i, 0), positions(i, 1), positions(i, 2));  // float -> double: exact
    }
  });
  auto corners = [&](std::size_t f) {
    const auto i = static_cast<Eigen::Index>(f);
    return Corners{triangles(i, 0), triangles(i, 1), triangles(i, 2)};
  };

  // Degenerate faces (exact collinearity; repeated indices are collinear too).
  std::vector<std::uint8_t> degenerate(num_faces, 0);
  parallel_for(num_faces, grain == 0 ? 0 : kDefaultGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f) {
      const Corners t = corners(f);
      degenerate[f] = CGAL::collinear(p[t[0]], p[t[1]], p[t[2]]) ? 1 : 0;
    }
  });

  // Closed bounding boxes of the non-degenerate faces (exact: float coordinates).
  std::vector<Box> boxes;
  boxes.reserve(num_faces);
  CGAL::Bbox_3 all;
  for (std::size_t f = 0; f < num_faces; ++f) {
    if (degenerate[f]) continue;
    const Corners t = corners(f);
    boxes.emplace_back(p[t[0]].bbox() + p[t[1]].bbox() + p[t[2]].bbox(), static_cast<int>(f));
    all += boxes.back().bbox();
  }

  // Slabs along the longest axis, cut at sampled quantiles of the boxes' lower ends. A box goes
  // to every slab its extent meets; a pair of overlapping boxes is handled only in the slab that
  // holds the lower end of their overlap, so each pair is seen exactly once whatever the cuts.
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (all.max(a) - all.min(a) > all.max(axis) - all.min(axis)) axis = a;
  const std::size_t num_slabs =
      grain == 0 ? 1 : std::clamp<std::size_t>((boxes.size() + grain - 1) / grain, 1, 4096);
  std::vector<double> cuts;  // slab s = [cuts[s-1], cuts[s]), open-ended at both extremes
  if (num_slabs > 1) {
    std::vector<double> sample;
    const std::size_t step = std::max<std::size_t>(1, boxes.size() / (64 * num_slabs));
    for (std::size_t i = 0; i < boxes.size(); i += step) sample.push_back(boxes[i].min_coord(axis));
    std::sort(sample.begin(), sample.end());
    for (std::size_t s = 1; s < num_slabs; ++s) cuts.push_back(sample[s * sample.size() / num_slabs]);
  }
  auto slab_of = [&](double x) {
    return static_cast<std::size_t>(std::upper_bound(cuts.begin(), cuts.end(), x) - cuts.begin());
  };
  std::vector<std::vector<const Box*>> slabs(num_slabs);
  for (const Box& b : boxes)
    for (std::size_t s = slab_of(b.min_coord(axis)), last = slab_of(b.max_coord(axis)); s <= last; ++s)
      slabs[s].push_back(&b);

  // Broad phase per slab (CGAL box intersection), exact narrow phase in the callback.
  std::vector<std::vector<std::uint64_t>> slab_hits(num_slabs);
  std::vector<long long> slab_candidates(num_slabs, 0);
  parallel_for(num_slabs, grain == 0 ? 0 : 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t s = begin; s < end; ++s) {
      auto& hits = slab_hits[s];
      long long& candidates = slab_candidates[s];
      CGAL::box_self_intersection_d<CGAL::Sequential_tag>(
          slabs[s].begin(), slabs[s].end(),
          [&](const Box* a, const Box* b) {
            if (slab_of(std::max(a->min_coord(axis), b->min_coord(axis))) != s) return;
            ++candidates;
            const auto fa = static_cast<std::uint32_t>(std::min(a->info(), b->info()));
            const auto fb = static_cast<std::uint32_t>(std::max(a->info(), b->info()));
            if (faces_intersect(p, corners(fa), corners(fb))) hits.push_back(std::uint64_t(fa) << 32 | fb);
          },
          kBoxCutoff);
    }
  });

  std::vector<std::uint64_t> found;
  long long candidates = 0;
  for (std::size_t s = 0; s < num_slabs; ++s) {
    found.insert(found.end(), slab_hits[s].begin(), slab_hits[s].end());
    candidates += slab_candidates[s];
  }
  const int count = static_cast<int>(found.size());

  if (details) {
    const auto cap = static_cast<std::size_t>(std::max(options.max_pairs, 0));
    std::sort(found.begin(), found.end());
    details->pairs.clear();
    for (std::size_t i = 0; i < found.size() && i < cap; ++i)
      details->pairs.push_back({static_cast<int>(found[i] >> 32), static_cast<int>(found[i] & 0xffffffffu)});
    details->degenerate_faces.clear();
    details->degenerate_count = 0;
    for (std::size_t f = 0; f < num_faces; ++f) {
      if (!degenerate[f]) continue;
      ++details->degenerate_count;
      if (details->degenerate_faces.size() < cap) details->degenerate_faces.push_back(static_cast<int>(f));
    }
    details->candidate_pairs = candidates;
  }
  return count;
}

}  // namespace isokit::skinning
