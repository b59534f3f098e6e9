// SPDX-License-Identifier: MIT
// Orientation repair (TrackerOptions::orientation_repair; docs/tracking.md, "Orientation repair").
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include <Eigen/Geometry>

#include "detail.h"

namespace isokit::track::detail {

namespace {

using V3 = Eigen::Vector3d;

V3 to3(const Vec3f& p) {
  return {p.x, p.y, p.z};
}

// Sign of the volume of (a, b, c, d): > 0 when d lies on the side of the plane (a, b, c) that
// (b - a) x (c - a) points to.
double orient(const V3& a, const V3& b, const V3& c, const V3& d) {
  return (b - a).cross(c - a).dot(d - a);
}

// Whether the segment (a, b) passes through the triangle (p, q, r), touching included; false for
// a segment in the triangle's plane.
bool segment_crosses(const V3& a, const V3& b, const V3& p, const V3& q, const V3& r) {
  const double sa = orient(p, q, r, a), sb = orient(p, q, r, b);
  if ((sa > 0 && sb > 0) || (sa < 0 && sb < 0) || (sa == 0 && sb == 0)) return false;
  const double e1 = orient(a, b, p, q), e2 = orient(a, b, q, r), e3 = orient(a, b, r, p);
  return (e1 >= 0 && e2 >= 0 && e3 >= 0) || (e1 <= 0 && e2 <= 0 && e3 <= 0);
}

// Triangles as three vertex indices into `pts`.
struct Tri {
  int v[3];
};

// Whether two triangles intersect anywhere but at the vertices they share (QUALITY.md counts
// such pairs; triangles sharing an edge are never tested). Non-coplanar configurations only: two
// triangles cross iff an edge of one passes through the other; with one shared vertex s, iff the
// edge opposite s of one passes through the other.
bool triangles_cross(const std::vector<Vec3f>& pts, const Tri& s, const Tri& t) {
  int shared = 0;
  for (int i : s.v)
    for (int j : t.v) shared += i == j ? 1 : 0;
  if (shared >= 2) return false;
  const V3 a[3] = {to3(pts[s.v[0]]), to3(pts[s.v[1]]), to3(pts[s.v[2]])};
  const V3 b[3] = {to3(pts[t.v[0]]), to3(pts[t.v[1]]), to3(pts[t.v[2]])};
  auto in = [](const Tri& x, int v) { return x.v[0] == v || x.v[1] == v || x.v[2] == v; };
  for (int k = 0; k < 3; ++k) {
    const int i = s.v[k], j = s.v[(k + 1) % 3];
    if (shared == 1 && (in(t, i) || in(t, j))) continue;  // an edge from the shared vertex
    if (segment_crosses(a[k], a[(k + 1) % 3], b[0], b[1], b[2])) return true;
  }
  for (int k = 0; k < 3; ++k) {
    const int i = t.v[k], j = t.v[(k + 1) % 3];
    if (shared == 1 && (in(s, i) || in(s, j))) continue;
    if (segment_crosses(b[k], b[(k + 1) % 3], a[0], a[1], a[2])) return true;
  }
  return false;
}

Box3f face_box(const std::vector<Vec3f>& pts, const Triangles& tris, int f) {
  Box3f b;
  for (int k = 0; k < 3; ++k) b.extend(pts[tris(f, k)]);
  return b;
}

bool overlap(const Box3f& a, const Box3f& b) {
  return a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y && a.lo.z <= b.hi.z &&
         b.lo.z <= a.hi.z;
}

// A spatial hash of the bounding boxes of the triangles that overlap a few region boxes, over a
// uniform grid (buckets filled by counting sort); triangles moved after the build are appended to
// a short list. A triangle that leaves the regions counts as crossing (the hash cannot tell).
class TriangleHash {
 public:
  TriangleHash(const std::vector<Vec3f>& pts, const Triangles& triangles, float cell,
               std::vector<Box3f> regions)
      : pts_(pts),
        tris_(triangles),
        inv_cell_(1.f / cell),
        regions_(std::move(regions)),
        stamp_(static_cast<std::size_t>(triangles.rows()), 0) {
    const std::size_t nf = stamp_.size();
    std::vector<std::uint64_t> keys;
    std::vector<int> faces;
    for (std::size_t f = 0; f < nf; ++f) {
      const Box3f b = face_box(pts, triangles, static_cast<int>(f));
      if (std::none_of(regions_.begin(), regions_.end(), [&](const Box3f& r) { return overlap(b, r); }))
        continue;
      if (!for_cells(static_cast<int>(f),
                     [&](std::uint64_t k) { keys.push_back(k), faces.push_back(static_cast<int>(f)); }))
        big_.push_back(static_cast<int>(f));
    }
    std::size_t buckets = 1;
    while (buckets < 2 * keys.size()) buckets <<= 1;
    mask_ = buckets - 1;
    start_.assign(buckets + 1, 0);
    for (std::uint64_t k : keys) ++start_[(k & mask_) + 1];
    for (std::size_t b = 0; b < buckets; ++b) start_[b + 1] += start_[b];
    entries_.resize(keys.size());
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (std::size_t e = 0; e < keys.size(); ++e) entries_[fill[keys[e] & mask_]++] = faces[e];
  }

  // The face moved: also found in the cells of its new box.
  void update(int f) { moved_.push_back(f); }

  // Whether face f (at the current positions) crosses a face it does not share an edge with.
  bool crosses_any(int f) {
    const Box3f fb = face_box(pts_, tris_, f);
    if (std::none_of(regions_.begin(), regions_.end(), [&](const Box3f& r) { return r.contains(fb); }))
      return true;
    ++now_;
    const Tri s = tri(f);
    bool hit = false;
    auto test = [&](int g) {
      if (hit || g == f || stamp_[g] == now_) return;
      stamp_[g] = now_;
      hit = overlap(fb, face_box(pts_, tris_, g)) && triangles_cross(pts_, s, tri(g));
    };
    const bool listed = for_cells(f, [&](std::uint64_t k) {
      const std::size_t b = k & mask_;
      for (int e = start_[b]; e < start_[b + 1] && !hit; ++e) test(entries_[e]);
    });
    if (!listed) return true;  // a sliver over thousands of cells: refused, not searched
    for (int g : big_) test(g);
    for (int g : moved_) test(g);
    return hit;
  }

 private:
  Tri tri(int f) const { return {{tris_(f, 0), tris_(f, 1), tris_(f, 2)}}; }

  // Visits the keys of the cells the face's box overlaps; false (nothing visited) for a box over
  // more than 4096 cells.
  template <class F>
  bool for_cells(int f, F&& visit) const {
    const Box3f b = face_box(pts_, tris_, f);
    const Vec3f lo = b.lo, hi = b.hi;
    const double span = (std::floor(double(hi.x) * inv_cell_) - std::floor(double(lo.x) * inv_cell_) + 1) *
                        (std::floor(double(hi.y) * inv_cell_) - std::floor(double(lo.y) * inv_cell_) + 1) *
                        (std::floor(double(hi.z) * inv_cell_) - std::floor(double(lo.z) * inv_cell_) + 1);
    if (!(span <= 4096)) return false;  // also NaN
    auto cell = [&](float x) { return static_cast<std::int64_t>(std::floor(double(x) * inv_cell_)); };
    const std::int64_t x0 = cell(lo.x), x1 = cell(hi.x), y0 = cell(lo.y), y1 = cell(hi.y), z0 = cell(lo.z),
                       z1 = cell(hi.z);
    for (std::int64_t x = x0; x <= x1; ++x)
      for (std::int64_t y = y0; y <= y1; ++y)
        for (std::int64_t z = z0; z <= z1; ++z)
          visit(static_cast<std::uint64_t>(x) * 0x9e3779b97f4a7c15ull ^
                static_cast<std::uint64_t>(y) * 0xc2b2ae3d27d4eb4full ^
                static_cast<std::uint64_t>(z) * 0x165667b19e3779f9ull);
    return true;
  }

  const std::vector<Vec3f>& pts_;
  const Triangles& tris_;
  float inv_cell_;
  std::vector<Box3f> regions_;
  std::size_t mask_{0};
  std::vector<int> start_, entries_, moved_, big_;
  std::vector<std::uint32_t> stamp_;
  std::uint32_t now_{0};
};

}  // namespace

std::vector<int> orientation_repair(const FieldFunction& field, const Triangles& triangles,
                                    const Adjacency& vertex_faces,
                                    const std::vector<std::uint8_t>& rest_inverted,
                                    const std::vector<std::uint8_t>& lost,
                                    const std::vector<std::uint8_t>& movable,
                                    const OrientationRepairOptions& options, std::vector<Vec3f>& pts,
                                    std::vector<std::uint8_t>& inverted) {
  const std::size_t n = pts.size(), nf = inverted.size();
  std::vector<int> moved_list;
  if (options.rounds <= 0 || options.samples <= 0 || !(options.max_move > 0.f)) return moved_list;
  auto folded = [&](std::size_t f) { return inverted[f] && (rest_inverted.empty() || !rest_inverted[f]); };
  auto vertices_of_folds = [&]() {
    std::vector<int> verts;
    for (std::size_t f = 0; f < nf; ++f)
      if (folded(f))
        for (int k = 0; k < 3; ++k) verts.push_back(triangles(static_cast<Eigen::Index>(f), k));
    std::sort(verts.begin(), verts.end());
    verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
    return verts;
  };
  std::vector<int> verts = vertices_of_folds();
  if (verts.empty() || static_cast<double>(verts.size()) > options.max_fraction * static_cast<double>(n))
    return moved_list;

  // The hash's cells: twice the mean edge length around the vertices to repair. Its regions: the
  // boxes of their one-rings grown by twice the longest edge there (a few rounds of moves),
  // merged where they overlap.
  double edge_sum = 0;
  long edge_count = 0;
  std::vector<Box3f> regions;
  for (int v : verts) {
    Box3f ring;
    float longest = 0.f;
    for (int k = vertex_faces.offsets[v]; k < vertex_faces.offsets[v + 1]; ++k) {
      const Eigen::Index f = vertex_faces.neighbors[k];
      for (int c = 0; c < 3; ++c) {
        const float e = norm(pts[triangles(f, c)] - pts[triangles(f, (c + 1) % 3)]);
        edge_sum += e, ++edge_count, longest = std::max(longest, e);
        ring.extend(pts[triangles(f, c)]);
      }
    }
    if (ring.empty()) continue;
    const Vec3f grow{2.f * longest, 2.f * longest, 2.f * longest};
    ring = {ring.lo - grow, ring.hi + grow};
    bool merged = false;
    for (Box3f& r : regions)
      if (overlap(r, ring)) {
        r.extend(ring.lo), r.extend(ring.hi), merged = true;
        break;
      }
    if (!merged) regions.push_back(ring);
  }
  const float mean_edge = edge_count > 0 ? static_cast<float>(edge_sum / edge_count) : 0.f;
  if (!(mean_edge > 0.f) || !std::isfinite(mean_edge)) return moved_list;
  TriangleHash hash(pts, triangles, 2.f * mean_edge, std::move(regions));

  std::vector<std::uint8_t> moved(n, 0), stuck(n, 0);  // stuck: no better place since its ring last changed
  std::vector<Vec3f> cen, grad;
  std::vector<float> val;
  std::vector<std::uint8_t> fc;
  auto face_normal = [&](int f) {
    const Vec3f a = pts[triangles(f, 0)], b = pts[triangles(f, 1)], c = pts[triangles(f, 2)];
    return cross(b - a, c - a);
  };
  std::vector<Vec3f> vp, vg;
  std::vector<float> vv;
  std::vector<std::uint8_t> vc;
  for (int round = 0; round < options.rounds && !verts.empty(); ++round) {
    int moves = 0;
    // The field's inward direction at each vertex (one batch: a vertex moves only in its turn).
    vp.resize(verts.size()), vg.resize(verts.size()), vv.resize(verts.size()), vc.assign(verts.size(), 0);
    for (std::size_t a = 0; a < verts.size(); ++a) vp[a] = pts[verts[a]];
    field(vp.data(), vp.size(), vv.data(), vg.data(), vc.data());
    for (std::size_t a = 0; a < verts.size(); ++a) {
      const int v = verts[a];
      if (lost[v] || (!movable.empty() && !movable[v]) || stuck[v]) continue;
      const int fb = vertex_faces.offsets[v], fe = vertex_faces.offsets[v + 1], deg = fe - fb;
      if (deg == 0) continue;
      // Directions: the vertex normal, the field's inward direction at the vertex, and the normals
      // of its inverted triangles; each both ways.
      Vec3f nv{};
      double ring = 0;
      for (int k = fb; k < fe; ++k) {
        const int f = vertex_faces.neighbors[k];
        nv += face_normal(f);
        for (int c = 0; c < 3; ++c) ring += norm(pts[triangles(f, c)] - pts[v]);
      }
      const float nl = norm(nv), h = static_cast<float>(ring / (2.0 * deg));
      if (!(nl > 0.f) || !(h > 0.f)) continue;
      nv = nv / nl;
      const float gl = norm(vg[a]);
      const Vec3f gin = gl > 0.f && std::isfinite(gl) ? vg[a] / gl : Vec3f{};
      const Vec3f p0 = pts[v];
      // Candidate positions along `dirs`, both ways: inward moves up to max_move · h, outward ones
      // (along the vertex normal or against the field's inward direction) up to
      // max_outward_move · h: an outward move is what can push skin through the skin facing it.
      // The best one that improves on p0 and whose triangles cross no other triangle is taken.
      auto attempt = [&](const std::vector<Vec3f>& dirs) {
        std::vector<Vec3f> cand{p0};
        for (const Vec3f& d0 : dirs)
          for (float sign : {1.f, -1.f}) {
            const Vec3f d = d0 * sign;
            const bool outward = dot(d, nv) > 0.f || dot(d, gin) < 0.f;
            if (outward) {
              if (options.max_outward_move > 0.f) cand.push_back(p0 + d * (options.max_outward_move * h));
              continue;
            }
            for (int k = 1; k <= options.samples; ++k)
              cand.push_back(p0 + d * (options.max_move * h * static_cast<float>(k) /
                                       static_cast<float>(options.samples)));
          }
        // Each candidate's triangles around v, evaluated at their centroids in one batch.
        const std::size_t m = cand.size() * static_cast<std::size_t>(deg);
        cen.resize(m), grad.resize(m), val.resize(m), fc.assign(m, 0);
        for (std::size_t c = 0; c < cand.size(); ++c) {
          pts[v] = cand[c];
          for (int k = fb; k < fe; ++k) {
            const int f = vertex_faces.neighbors[k];
            cen[c * deg + (k - fb)] =
                (pts[triangles(f, 0)] + pts[triangles(f, 1)] + pts[triangles(f, 2)]) / 3.f;
          }
        }
        field(cen.data(), m, val.data(), grad.data(), fc.data());
        // Score: (inverted triangles, Σ max(0, n̂·ĝ + margin)), lexicographic.
        std::vector<std::pair<int, double>> score(cand.size());
        for (std::size_t c = 0; c < cand.size(); ++c) {
          pts[v] = cand[c];
          int count = 0;
          double energy = 0;
          for (int k = fb; k < fe; ++k) {
            const int f = vertex_faces.neighbors[k];
            const Vec3f nrm = face_normal(f), g = grad[c * deg + (k - fb)];
            const float d = dot(nrm, g), l = norm(nrm) * norm(g);
            if (!std::isfinite(d)) {
              count = std::numeric_limits<int>::max() / 2;
              break;
            }
            const bool rest = !rest_inverted.empty() && rest_inverted[static_cast<std::size_t>(f)];
            if (d > 0.f && !rest) ++count;
            if (l > 0.f && !rest) energy += std::max(0.0, static_cast<double>(d / l) + options.margin);
          }
          score[c] = {count, energy};
        }
        std::vector<std::size_t> order;
        for (std::size_t c = 1; c < cand.size(); ++c)
          if (score[c].first < score[0].first ||
              (score[c].first == score[0].first && score[c].second < score[0].second - 1e-6))
            order.push_back(c);
        std::sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) {
          return score[x] != score[y] ? score[x] < score[y] : x < y;
        });
        for (std::size_t c : order) {
          pts[v] = cand[c];
          bool crosses = false;
          for (int k = fb; k < fe && !crosses; ++k) crosses = hash.crosses_any(vertex_faces.neighbors[k]);
          if (crosses) continue;
          for (int k = fb; k < fe; ++k) {
            const int f = vertex_faces.neighbors[k];
            hash.update(f);
            inverted[static_cast<std::size_t>(f)] =
                dot(face_normal(f), grad[c * deg + (k - fb)]) > 0.f ? 1 : 0;
          }
          return true;
        }
        pts[v] = p0;
        return false;
      };
      // The vertex normal first; then the field's inward direction and the inverted triangles'
      // normals.
      std::vector<Vec3f> dirs{nv};
      if (gin != Vec3f{}) dirs.push_back(gin);
      for (int k = fb; k < fe; ++k)
        if (folded(static_cast<std::size_t>(vertex_faces.neighbors[k]))) {
          const Vec3f nf3 = face_normal(vertex_faces.neighbors[k]);
          const float l = norm(nf3);
          if (l > 0.f) dirs.push_back(nf3 / l);
        }
      const bool accepted = attempt(dirs);
      if (accepted) {
        if (!moved[v]) moved[v] = 1, moved_list.push_back(v);
        ++moves;
        // Its neighbours' triangles changed: they may move again.
        for (int k = fb; k < fe; ++k)
          for (int c = 0; c < 3; ++c) stuck[triangles(vertex_faces.neighbors[k], c)] = 0;
      } else {
        stuck[v] = 1;
      }
    }
    if (moves == 0) break;
    verts = vertices_of_folds();
  }
  std::sort(moved_list.begin(), moved_list.end());
  return moved_list;
}

}  // namespace isokit::track::detail
