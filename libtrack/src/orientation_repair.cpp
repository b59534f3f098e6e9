// SPDX-License-Identifier: MIT
// Orientation repair (TrackerOptions::orientation_repair; not in the papers, docs/tracking.md
// step 6): single-vertex moves that turn the triangles still inverted after the fold repair the
// right way, never through another triangle.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <utility>

#include "field_eval.h"
#include "isokit/core/mesh_quality.h"
#include "stages.h"
#include "statistics.h"
#include "triangle_crossing.h"

namespace isokit::track::detail {

namespace {

// A candidate position's score: (inverted triangles around the vertex, Σ max(0, n̂·ĝ + margin)
// over them), compared lexicographically.
using Score = std::pair<int, double>;

class OrientationRepair {
 public:
  explicit OrientationRepair(TrackState& s)
      : s_(s),
        o_(s.m.options.orientation_repair),
        tris_(s.m.triangles),
        vf_(s.m.vertex_faces),
        pts_(s.cur),
        moved_(s.n, 0),
        stuck_(s.n, 0) {}

  // Moves the vertices of the folded triangles, round after round while one moves; returns the
  // moved vertices, sorted.
  std::vector<int> run() {
    if (o_.rounds <= 0 || o_.samples <= 0 || !(o_.max_move > 0.f)) return moved_list_;
    std::vector<int> verts = fold_vertices();
    if (verts.empty() || static_cast<double>(verts.size()) > o_.max_fraction * static_cast<double>(s_.n))
      return moved_list_;
    if (!build_hash(verts)) return moved_list_;
    for (int round = 0; round < o_.rounds && !verts.empty(); ++round) {
      if (repair_round(verts) == 0) break;
      verts = fold_vertices();
    }
    std::sort(moved_list_.begin(), moved_list_.end());
    return moved_list_;
  }

 private:
  bool folded(std::size_t f) const {
    return s_.inverted[f] && (s_.m.rest_inverted.empty() || !s_.m.rest_inverted[f]);
  }
  bool rest_inverted(int f) const {
    return !s_.m.rest_inverted.empty() && s_.m.rest_inverted[static_cast<std::size_t>(f)];
  }
  Vec3f face_normal(int f) const {
    return triangle_normal(pts_[tris_(f, 0)], pts_[tris_(f, 1)], pts_[tris_(f, 2)]);
  }

  // The vertices of the folded triangles, sorted, without duplicates.
  std::vector<int> fold_vertices() const {
    std::vector<int> verts;
    for (std::size_t f = 0; f < s_.inverted.size(); ++f)
      if (folded(f))
        for (int k = 0; k < 3; ++k) verts.push_back(tris_(static_cast<Eigen::Index>(f), k));
    std::sort(verts.begin(), verts.end());
    verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
    return verts;
  }

  bool build_hash(const std::vector<int>& verts);
  int repair_round(const std::vector<int>& verts);
  bool repair_vertex(int v, const Vec3f& gradient);
  std::vector<Vec3f> directions(int v, const Vec3f& nv, const Vec3f& gin) const;
  std::vector<Vec3f> candidates(const Vec3f& p0, const std::vector<Vec3f>& dirs, const Vec3f& nv,
                                const Vec3f& gin, float h) const;
  std::vector<Score> score(int v, const std::vector<Vec3f>& cand);
  bool accept_best(int v, const Vec3f& p0, const std::vector<Vec3f>& cand, const std::vector<Score>& scores);

  TrackState& s_;
  const OrientationRepairOptions& o_;
  const Triangles& tris_;
  const Adjacency& vf_;
  std::vector<Vec3f>& pts_;
  std::optional<TriangleHash> hash_;
  std::vector<std::uint8_t> moved_, stuck_;  // stuck: no better place since its ring last changed
  std::vector<int> moved_list_;
  std::vector<Vec3f> cen_, grad_;  // candidate evaluation batch
  std::vector<float> val_;
  std::vector<std::uint8_t> fc_;
};

// The hash's cells: twice the mean edge length around the vertices to repair. Its regions: the
// boxes of their one-rings grown by twice the longest edge there (a few rounds of moves), merged
// where they overlap. False (nothing to do) without a usable edge length.
bool OrientationRepair::build_hash(const std::vector<int>& verts) {
  double edge_sum = 0;
  long edge_count = 0;
  std::vector<Box3f> regions;
  for (int v : verts) {
    Box3f ring;
    float longest = 0.f;
    for (int k = vf_.offsets[v]; k < vf_.offsets[v + 1]; ++k) {
      const Eigen::Index f = vf_.neighbors[k];
      for (int c = 0; c < 3; ++c) {
        const float e = norm(pts_[tris_(f, c)] - pts_[tris_(f, (c + 1) % 3)]);
        edge_sum += e, ++edge_count, longest = std::max(longest, e);
        ring.extend(pts_[tris_(f, c)]);
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
  if (!(mean_edge > 0.f) || !std::isfinite(mean_edge)) return false;
  hash_.emplace(pts_, tris_, 2.f * mean_edge, std::move(regions));
  return true;
}

// One round over `verts` (Gauss–Seidel: a vertex sees its neighbours' new positions). Returns the
// number of moves.
int OrientationRepair::repair_round(const std::vector<int>& verts) {
  // The field's inward direction at each vertex (one batch: a vertex moves only in its turn).
  const std::size_t m = verts.size();
  std::vector<Vec3f> vp(m), vg(m);
  std::vector<float> vv(m);
  std::vector<std::uint8_t> vc(m, 0);
  for (std::size_t a = 0; a < m; ++a) vp[a] = pts_[verts[a]];
  s_.field(vp.data(), vp.size(), vv.data(), vg.data(), vc.data());
  const std::vector<std::uint8_t>& movable = s_.m.repair_mask;
  int moves = 0;
  for (std::size_t a = 0; a < m; ++a) {
    const int v = verts[a];
    if (s_.flags.lost[v] || (!movable.empty() && !movable[v]) || stuck_[v] || s_.pinned(std::size_t(v)))
      continue;
    if (repair_vertex(v, vg[a])) ++moves;
  }
  return moves;
}

// Tries the candidate positions of vertex v (gradient: the field's at v); true if it moved.
bool OrientationRepair::repair_vertex(int v, const Vec3f& gradient) {
  const int fb = vf_.offsets[v], fe = vf_.offsets[v + 1], deg = fe - fb;
  if (deg == 0) return false;
  Vec3f nv{};  // area-weighted vertex normal
  double ring = 0;
  for (int k = fb; k < fe; ++k) {
    const int f = vf_.neighbors[k];
    nv += face_normal(f);
    for (int c = 0; c < 3; ++c) ring += norm(pts_[tris_(f, c)] - pts_[v]);
  }
  const float nl = norm(nv), h = static_cast<float>(ring / (2.0 * deg));  // h: mean edge length
  if (!(nl > 0.f) || !(h > 0.f)) return false;
  nv = nv / nl;
  const float gl = norm(gradient);
  const Vec3f gin = gl > 0.f && std::isfinite(gl) ? gradient / gl : Vec3f{};
  const Vec3f p0 = pts_[v];
  const std::vector<Vec3f> cand = candidates(p0, directions(v, nv, gin), nv, gin, h);
  if (!accept_best(v, p0, cand, score(v, cand))) {
    stuck_[v] = 1;
    return false;
  }
  if (!moved_[v]) moved_[v] = 1, moved_list_.push_back(v);
  // Its neighbours' triangles changed: they may move again.
  for (int k = fb; k < fe; ++k)
    for (int c = 0; c < 3; ++c) stuck_[tris_(vf_.neighbors[k], c)] = 0;
  return true;
}

// The vertex normal first; then the field's inward direction and the inverted triangles' normals.
std::vector<Vec3f> OrientationRepair::directions(int v, const Vec3f& nv, const Vec3f& gin) const {
  std::vector<Vec3f> dirs{nv};
  if (gin != Vec3f{}) dirs.push_back(gin);
  for (int k = vf_.offsets[v]; k < vf_.offsets[v + 1]; ++k)
    if (folded(static_cast<std::size_t>(vf_.neighbors[k]))) {
      const Vec3f nf3 = face_normal(vf_.neighbors[k]);
      const float l = norm(nf3);
      if (l > 0.f) dirs.push_back(nf3 / l);
    }
  return dirs;
}

// p0 first, then positions along `dirs`, both ways: inward moves up to max_move · h in `samples`
// even steps, outward ones (along the vertex normal or against the field's inward direction) one
// step of max_outward_move · h: an outward move is what can push skin through the skin facing it.
std::vector<Vec3f> OrientationRepair::candidates(const Vec3f& p0, const std::vector<Vec3f>& dirs,
                                                 const Vec3f& nv, const Vec3f& gin, float h) const {
  std::vector<Vec3f> cand{p0};
  for (const Vec3f& d0 : dirs)
    for (float sign : {1.f, -1.f}) {
      const Vec3f d = d0 * sign;
      const bool outward = dot(d, nv) > 0.f || dot(d, gin) < 0.f;
      if (outward) {
        if (o_.max_outward_move > 0.f) cand.push_back(p0 + d * (o_.max_outward_move * h));
        continue;
      }
      for (int k = 1; k <= o_.samples; ++k)
        cand.push_back(p0 + d * (o_.max_move * h * static_cast<float>(k) / static_cast<float>(o_.samples)));
    }
  return cand;
}

// Each candidate's triangles around v, evaluated at their centroids in one batch, and scored.
// Leaves pts_[v] at the last candidate.
std::vector<Score> OrientationRepair::score(int v, const std::vector<Vec3f>& cand) {
  const int fb = vf_.offsets[v], fe = vf_.offsets[v + 1], deg = fe - fb;
  const std::size_t m = cand.size() * static_cast<std::size_t>(deg);
  cen_.resize(m), grad_.resize(m), val_.resize(m), fc_.assign(m, 0);
  for (std::size_t c = 0; c < cand.size(); ++c) {
    pts_[v] = cand[c];
    for (int k = fb; k < fe; ++k) {
      const int f = vf_.neighbors[k];
      cen_[c * deg + (k - fb)] = triangle_centroid(pts_[tris_(f, 0)], pts_[tris_(f, 1)], pts_[tris_(f, 2)]);
    }
  }
  s_.field(cen_.data(), m, val_.data(), grad_.data(), fc_.data());
  std::vector<Score> scores(cand.size());
  for (std::size_t c = 0; c < cand.size(); ++c) {
    pts_[v] = cand[c];
    int count = 0;
    double energy = 0;
    for (int k = fb; k < fe; ++k) {
      const int f = vf_.neighbors[k];
      const Vec3f nrm = face_normal(f), g = grad_[c * deg + (k - fb)];
      const float d = dot(nrm, g), l = norm(nrm) * norm(g);
      if (!std::isfinite(d)) {
        count = std::numeric_limits<int>::max() / 2;
        break;
      }
      if (d > 0.f && !rest_inverted(f)) ++count;
      if (l > 0.f && !rest_inverted(f)) energy += std::max(0.0, static_cast<double>(d / l) + o_.margin);
    }
    scores[c] = {count, energy};
  }
  return scores;
}

// Moves v to the best candidate better than p0 (cand[0]) whose triangles cross no other
// triangle, then the next best; updates the inverted flags of its triangles from the candidate's
// evaluation. False (v back at p0) if none.
bool OrientationRepair::accept_best(int v, const Vec3f& p0, const std::vector<Vec3f>& cand,
                                    const std::vector<Score>& scores) {
  const int fb = vf_.offsets[v], fe = vf_.offsets[v + 1], deg = fe - fb;
  std::vector<std::size_t> order;
  for (std::size_t c = 1; c < cand.size(); ++c)
    if (scores[c].first < scores[0].first ||
        (scores[c].first == scores[0].first && scores[c].second < scores[0].second - 1e-6))
      order.push_back(c);
  std::sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) {
    return scores[x] != scores[y] ? scores[x] < scores[y] : x < y;
  });
  for (std::size_t c : order) {
    pts_[v] = cand[c];
    bool crosses = false;
    for (int k = fb; k < fe && !crosses; ++k) crosses = hash_->crosses_any(vf_.neighbors[k]);
    if (crosses) continue;
    for (int k = fb; k < fe; ++k) {
      const int f = vf_.neighbors[k];
      hash_->update(f);
      s_.inverted[static_cast<std::size_t>(f)] =
          is_inverted(face_normal(f), grad_[c * deg + (k - fb)]) ? 1 : 0;
    }
    return true;
  }
  pts_[v] = p0;
  return false;
}

}  // namespace

void repair_orientation(TrackState& s) {
  if (s.m.options.orientation_repair.rounds <= 0 || s.stats.inverted_triangles <= 0) return;
  const std::vector<int> oriented = OrientationRepair(s).run();
  s.stats.oriented_vertices = static_cast<int>(oriented.size());
  if (oriented.empty()) return;
  // Moved off their iso-values on purpose, like smoothed vertices: β = 1, out of the residual.
  for (int i : oriented) s.flags.beta[static_cast<std::size_t>(i)] = 1.f;
  refresh_values(s.field, s.cur, oriented, s.m.options.grain, s.values, s.flags);
  s.stats.smoothed_vertices = count_smoothed(s);
  vertex_stats(s.values, s.m.iso, s.flags, s.stats, &s.m.anchor_k);
  s.stats.inverted_triangles = count_flags(s.inverted);
}

}  // namespace isokit::track::detail
