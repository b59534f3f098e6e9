// SPDX-License-Identifier: MIT
// Localised Laplacian smoothing (2013 §5, eq. 7; docs/tracking.md, 2014 tracker step 4).
#include "contact_smoothing.h"

#include <algorithm>

#include "isokit/core/parallel.h"
#include "mesh_geometry.h"
#include "stages.h"

namespace isokit::track::detail {

namespace {

// β_i <- (β_i + Σ_j β_j) / (1 + deg_i) over `region`, `steps` times (double-buffered).
void diffuse_beta(const Adjacency& adj, const std::vector<int>& region, int steps, std::size_t grain,
                  std::vector<float>& beta) {
  std::vector<float> next(beta.size(), 0.f);
  for (int s = 0; s < steps; ++s) {
    parallel_for(region.size(), grain, [&](std::size_t b, std::size_t e) {
      for (std::size_t a = b; a < e; ++a) {
        const int i = region[a];
        float acc = beta[i];
        for (int k = adj.offsets[i]; k < adj.offsets[i + 1]; ++k) acc += beta[adj.neighbors[k]];
        next[i] = acc / static_cast<float>(1 + adj.degree(i));
      }
    });
    beta.swap(next);
  }
}

// v_i <- (1 - β_i) v_i + β_i (centroid(one-ring) + detail_i) over `region`, `steps` times
// (double-buffered; no detail: 0).
// With `normals`, the step's normal component is removed; `fixed` vertices stay.
void smooth(const Adjacency& adj, const std::vector<int>& region, const std::vector<float>& beta, int steps,
            std::size_t grain, const Vec3f* detail, const Vec3f* normals, const std::uint8_t* fixed,
            std::vector<Vec3f>& pts) {
  std::vector<Vec3f> buf(region.size());
  for (int s = 0; s < steps; ++s) {
    parallel_for(region.size(), grain, [&](std::size_t b, std::size_t e) {
      for (std::size_t a = b; a < e; ++a) {
        const int i = region[a];
        const int deg = adj.degree(i);
        if (beta[i] <= 0.f || deg == 0 || (fixed && fixed[i])) {
          buf[a] = pts[i];
          continue;
        }
        Vec3f c = ring_centroid(adj, pts, i, deg);
        if (detail) c += detail[i];
        Vec3f step = (c - pts[i]) * beta[i];
        if (normals) step = step - normals[i] * dot(step, normals[i]);
        buf[a] = pts[i] + step;
      }
    });
    for (std::size_t a = 0; a < region.size(); ++a) pts[region[a]] = buf[a];
  }
}

// Per vertex: its rest Laplacian coordinate turned by the target rotations, the mean of its edge
// targets ½ (Ri + Rj)(pi - pj) (SmoothingOptions::keep_detail): centroid + detail is the vertex
// itself for a rigidly moved rest shape.
std::vector<Vec3f> rest_detail(const TrackState& s) {
  const Adjacency& adj = s.m.adj;
  std::vector<Vec3f> detail(s.n, Vec3f{});
  for (std::size_t i = 0; i < s.n; ++i) {
    const int deg = adj.degree(static_cast<int>(i));
    if (deg == 0) continue;
    Vec3f d{};
    for (int k = adj.offsets[i]; k < adj.offsets[i + 1]; ++k) d += s.targets[static_cast<std::size_t>(k)];
    detail[i] = d / static_cast<float>(deg);
  }
  return detail;
}

// Per vertex: on an open border (fewer triangles around it than neighbours: its fan does not close).
std::vector<std::uint8_t> border_vertices(const TrackerModel& m) {
  std::vector<std::uint8_t> border(m.rest.size(), 0);
  for (std::size_t i = 0; i < border.size(); ++i)
    border[i] = m.vertex_faces.degree(static_cast<int>(i)) < m.adj.degree(static_cast<int>(i)) ? 1 : 0;
  return border;
}

}  // namespace

int contact_smoothing(const Adjacency& adj, const std::vector<std::uint8_t>& contact,
                      const SmoothingOptions& options, std::size_t grain, std::vector<Vec3f>& pts,
                      std::vector<float>& beta, const Vec3f* detail, const Vec3f* normals,
                      const std::uint8_t* fixed) {
  const std::size_t n = pts.size();
  beta.assign(n, 0.f);
  // β is 0 beyond beta_diffusion_steps rings of the contact vertices: only that region is
  // diffused and smoothed (the same arithmetic per vertex as a pass over every vertex).
  std::vector<int> region;
  std::vector<std::uint8_t> in(n, 0);
  for (std::size_t i = 0; i < n; ++i)
    if (contact[i]) in[i] = 1, region.push_back(static_cast<int>(i));
  if (region.empty()) return 0;
  grow_rings(adj, options.beta_diffusion_steps, region, in);
  std::sort(region.begin(), region.end());
  for (int i : region) beta[i] = contact[i] ? 1.f : 0.f;
  diffuse_beta(adj, region, options.beta_diffusion_steps, grain, beta);
  // Contact vertices keep β = 1 (2013: "β = 1 for vertices stopped at a gradient discontinuity").
  for (int i : region)
    if (contact[i]) beta[i] = 1.f;
  smooth(adj, region, beta, options.smoothing_steps, grain, detail, normals, fixed, pts);
  int count = 0;
  for (int i : region) count += beta[i] > 0.f ? 1 : 0;
  return count;
}

namespace {

// Newton sweeps over the smoothed vertices around the contacts (SmoothingOptions::reproject_steps;
// the contact vertices themselves stay where the smoothing flattened the crease), stopping early
// when none moves by more than the tolerance.
void reproject_smoothed(TrackState& s) {
  const int steps = s.m.options.smoothing.reproject_steps;
  if (steps <= 0 || s.stats.smoothed_vertices <= 0) return;
  s.active.clear();
  for (std::size_t i = 0; i < s.n; ++i)
    if (s.flags.beta[i] > 0.f && !s.flags.contact[i] && !s.pinned(i)) s.active.push_back(static_cast<int>(i));
  for (int k = 0; k < steps && !s.active.empty(); ++k)
    if (sweep(s, false, true) <= s.tol) break;
}

}  // namespace

void smooth_contacts(TrackState& s) {
  const TrackerOptions& o = s.m.options;
  std::vector<Vec3f> detail;
  if (o.smoothing.keep_detail) detail = rest_detail(s);
  std::vector<std::uint8_t> border;
  if (o.smoothing.tangential) border = border_vertices(s.m);
  s.stats.smoothed_vertices = contact_smoothing(s.m.adj, s.flags.contact, o.smoothing, o.grain, s.cur,
                                                s.flags.beta, detail.empty() ? nullptr : detail.data(),
                                                o.smoothing.tangential ? s.normal.data() : nullptr,
                                                border.empty() ? nullptr : border.data());
  if (!s.anchors.empty())  // pinned vertices stay at their anchors
    for (std::size_t i = 0; i < s.n; ++i)
      if (s.pinned(i) && s.flags.beta[i] > 0.f) {
        s.cur[i] = s.anchors[i];
        s.flags.beta[i] = 0.f;
        --s.stats.smoothed_vertices;
      }
  if (o.smoothing.smoothing_steps > 0)
    for (std::size_t i = 0; i < s.n; ++i)
      if (s.flags.beta[i] > 0.f) s.touched[i] = 1;
  reproject_smoothed(s);
}

}  // namespace isokit::track::detail
