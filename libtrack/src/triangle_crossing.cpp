// SPDX-License-Identifier: MIT
#include "triangle_crossing.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

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

Tri tri(const Triangles& tris, int f) {
  return {{tris(f, 0), tris(f, 1), tris(f, 2)}};
}

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

}  // namespace

Box3f face_box(const std::vector<Vec3f>& pts, const Triangles& tris, int f) {
  Box3f b;
  for (int k = 0; k < 3; ++k) b.extend(pts[tris(f, k)]);
  return b;
}

bool overlap(const Box3f& a, const Box3f& b) {
  return a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y && a.lo.z <= b.hi.z &&
         b.lo.z <= a.hi.z;
}

template <class F>
bool TriangleHash::for_cells(int f, F&& visit) const {
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

TriangleHash::TriangleHash(const std::vector<Vec3f>& pts, const Triangles& triangles, float cell,
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

bool TriangleHash::crosses_any(int f) {
  const Box3f fb = face_box(pts_, tris_, f);
  if (std::none_of(regions_.begin(), regions_.end(), [&](const Box3f& r) { return r.contains(fb); }))
    return true;
  ++now_;
  const Tri s = tri(tris_, f);
  bool hit = false;
  auto test = [&](int g) {
    if (hit || g == f || stamp_[g] == now_) return;
    stamp_[g] = now_;
    hit = overlap(fb, face_box(pts_, tris_, g)) && triangles_cross(pts_, s, tri(tris_, g));
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

}  // namespace isokit::track::detail
