// SPDX-License-Identifier: MIT
#include <algorithm>
#include <cmath>

#include "detail.h"
#include "isokit/core/parallel.h"

namespace isokit::track {

namespace detail {

std::vector<Vec3f> to_points(const Positions& p, const std::string& what) {
  std::vector<Vec3f> out(static_cast<std::size_t>(p.rows()));
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    out[static_cast<std::size_t>(i)] = row(p, i);
    if (!finite(out[static_cast<std::size_t>(i)]))  // message built only on failure (hot path)
      require(false, what + " vertex " + std::to_string(i), "is not finite", "pass finite coordinates");
  }
  return out;
}

namespace {

// Spreads the low 21 bits of x to every third bit.
std::uint64_t spread_bits(std::uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffull;
  x = (x | x << 16) & 0x1f0000ff0000ffull;
  x = (x | x << 8) & 0x100f00f00f00f00full;
  x = (x | x << 4) & 0x10c30c30c30c30c3ull;
  x = (x | x << 2) & 0x1249249249249249ull;
  return x;
}

}  // namespace

std::vector<int> spatial_order(const std::vector<Vec3f>& pts) {
  Vec3f lo{0, 0, 0}, hi{0, 0, 0};
  if (!pts.empty()) lo = hi = pts[0];
  for (const Vec3f& p : pts) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  const float extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z, 1e-30f});
  const double scale = double((1 << 21) - 1) / double(extent);
  std::vector<std::uint64_t> key(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Vec3f d = pts[i] - lo;
    key[i] = spread_bits(std::uint64_t(double(d.x) * scale)) |
             spread_bits(std::uint64_t(double(d.y) * scale)) << 1 |
             spread_bits(std::uint64_t(double(d.z) * scale)) << 2;
  }
  std::vector<int> order(pts.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return key[a] != key[b] ? key[a] < key[b] : a < b; });
  return order;
}

void from_points(const std::vector<Vec3f>& pts, Positions& p) {
  p.resize(static_cast<Eigen::Index>(pts.size()), 3);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const auto r = static_cast<Eigen::Index>(i);
    p(r, 0) = pts[i].x, p(r, 1) = pts[i].y, p(r, 2) = pts[i].z;
  }
}

std::vector<float> mean_edge_lengths(const std::vector<Vec3f>& rest, const Adjacency& adj) {
  const int n = static_cast<int>(rest.size());
  std::vector<float> out(rest.size(), 0.f);
  double total = 0;
  long count = 0;
  for (int i = 0; i < n; ++i) {
    double s = 0;
    for (int k = adj.offsets[i]; k < adj.offsets[i + 1]; ++k) s += norm(rest[adj.neighbors[k]] - rest[i]);
    if (adj.degree(i) > 0) out[i] = static_cast<float>(s / adj.degree(i));
    total += s;
    count += adj.degree(i);
  }
  const float global = count > 0 ? static_cast<float>(total / count) : 1.f;
  for (int i = 0; i < n; ++i)
    if (!(out[i] > 0.f)) out[i] = global > 0.f ? global : 1.f;
  return out;
}

float bbox_diagonal(const std::vector<Vec3f>& pts) {
  Box3f b;
  for (const Vec3f& p : pts) b.extend(p);
  return b.empty() ? 0.f : norm(b.size());
}

int find_neighbor(const Adjacency& adj, int i, int j) {
  const auto b = adj.neighbors.begin() + adj.offsets[i], e = adj.neighbors.begin() + adj.offsets[i + 1];
  const auto it = std::lower_bound(b, e, j);
  return (it != e && *it == j) ? static_cast<int>(it - adj.neighbors.begin()) : -1;
}

void cotangent_weights(const std::vector<Vec3f>& rest, const Triangles& triangles, const Adjacency& adj,
                       float max_cot, std::vector<float>& weights, std::vector<float>& sums) {
  weights.assign(adj.neighbors.size(), 0.f);
  for (Eigen::Index f = 0; f < triangles.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      // Corner c opposite the edge (a, b).
      const int c = triangles(f, k), a = triangles(f, (k + 1) % 3), b = triangles(f, (k + 2) % 3);
      const Vec3f u = rest[a] - rest[c], v = rest[b] - rest[c];
      const float cr = norm(cross(u, v));
      float cot = 0.f;  // degenerate (zero-area) triangles contribute nothing
      if (cr > 1e-12f * (squared_norm(u) + squared_norm(v))) cot = dot(u, v) / cr;
      cot = std::clamp(cot, 0.f, max_cot);
      weights[find_neighbor(adj, a, b)] += 0.5f * cot;
      weights[find_neighbor(adj, b, a)] += 0.5f * cot;
    }
  }
  const int n = static_cast<int>(rest.size());
  sums.assign(rest.size(), 0.f);
  for (int i = 0; i < n; ++i) {
    float s = 0.f;
    for (int k = adj.offsets[i]; k < adj.offsets[i + 1]; ++k) s += weights[k];
    if (!(s > 0.f) && adj.degree(i) > 0) {  // all incident triangles degenerate: uniform
      for (int k = adj.offsets[i]; k < adj.offsets[i + 1]; ++k) weights[k] = 1.f;
      s = static_cast<float>(adj.degree(i));
    }
    sums[i] = s;
  }
}

namespace {
// Appends to `region` the vertices within `rings` rings of it (breadth first); `in` flags members.
void grow_rings(const Adjacency& adj, int rings, std::vector<int>& region, std::vector<std::uint8_t>& in) {
  for (int r = 0, begin = 0; r < rings; ++r) {
    const int end = static_cast<int>(region.size());
    for (int a = begin; a < end; ++a)
      for (int k = adj.offsets[region[a]]; k < adj.offsets[region[a] + 1]; ++k)
        if (!in[adj.neighbors[k]]) in[adj.neighbors[k]] = 1, region.push_back(adj.neighbors[k]);
    begin = end;
  }
}
}  // namespace

int contact_smoothing(const Adjacency& adj, const std::vector<std::uint8_t>& contact,
                      const SmoothingOptions& options, std::size_t grain, std::vector<Vec3f>& pts,
                      std::vector<float>& beta) {
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
  std::vector<float> next(n, 0.f);
  for (int s = 0; s < options.beta_diffusion_steps; ++s) {
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
  // Contact vertices keep β = 1 (2013: "β = 1 for vertices stopped at a gradient discontinuity").
  for (int i : region)
    if (contact[i]) beta[i] = 1.f;
  std::vector<Vec3f> buf(region.size());
  for (int s = 0; s < options.smoothing_steps; ++s) {
    parallel_for(region.size(), grain, [&](std::size_t b, std::size_t e) {
      for (std::size_t a = b; a < e; ++a) {
        const int i = region[a];
        const int deg = adj.degree(i);
        if (beta[i] <= 0.f || deg == 0) {
          buf[a] = pts[i];
          continue;
        }
        Vec3f c{};
        for (int k = adj.offsets[i]; k < adj.offsets[i + 1]; ++k) c += pts[adj.neighbors[k]];
        c = c / static_cast<float>(deg);
        buf[a] = pts[i] * (1.f - beta[i]) + c * beta[i];
      }
    });
    for (std::size_t a = 0; a < region.size(); ++a) pts[region[a]] = buf[a];
  }
  int count = 0;
  for (int i : region) count += beta[i] > 0.f ? 1 : 0;
  return count;
}

int fold_repair(const FieldFunction& field, const Triangles& triangles, const Adjacency& adj,
                const Adjacency& vertex_faces, const std::vector<std::uint8_t>& rest_inverted,
                const std::vector<std::uint8_t>& lost, const std::vector<std::uint8_t>& movable,
                const FoldRepairOptions& options, std::size_t grain, std::vector<Vec3f>& pts,
                std::vector<float>& beta, std::vector<std::uint8_t>& touched,
                std::vector<std::uint8_t>& inverted, std::vector<std::uint8_t>& fresh) {
  const std::size_t n = pts.size(), nf = static_cast<std::size_t>(triangles.rows());
  std::vector<std::uint8_t> tested(nf, 0), in(n, 0), moved(n, 0);
  fresh.assign(nf, 0);
  std::vector<int> candidates, region;
  // The triangles the contact smoothing may have changed: those around a vertex with β > 0.
  auto add_faces_of = [&](int i) {
    for (int k = vertex_faces.offsets[i]; k < vertex_faces.offsets[i + 1]; ++k) {
      const int f = vertex_faces.neighbors[k];
      fresh[f] = 0;
      if (!tested[f]) tested[f] = 1, candidates.push_back(f);
    }
  };
  for (std::size_t i = 0; i < n; ++i)
    if (beta[i] > 0.f) add_faces_of(static_cast<int>(i));
  auto pinned = [&](int i) { return lost[i] || (!movable.empty() && !movable[i]); };
  std::vector<Vec3f> buf;
  int count = 0;
  for (int round = 0; round < options.rounds && !candidates.empty(); ++round) {
    std::sort(candidates.begin(), candidates.end());
    const std::vector<std::uint8_t> now = inverted_triangles(field, pts, triangles, grain, &candidates);
    region.clear();
    for (int f : candidates) {
      const auto t = static_cast<std::size_t>(f);
      tested[t] = 0;
      inverted[t] = now[t];
      fresh[t] = 1;
      if (!now[t] || (!rest_inverted.empty() && rest_inverted[f])) continue;
      for (int k = 0; k < 3; ++k) {
        const int v = triangles(f, k);
        if (!in[v]) in[v] = 1, region.push_back(v);
      }
    }
    candidates.clear();
    if (region.empty()) break;
    if (round == 0 && static_cast<double>(region.size()) > options.max_fraction * static_cast<double>(n)) {
      // The field disagrees with the mesh broadly (an under-resolved rig): smoothing would
      // erase the shape rather than untangle a fold.
      for (int i : region) in[i] = 0;
      break;
    }
    grow_rings(adj, options.rings, region, in);
    std::sort(region.begin(), region.end());
    buf.resize(region.size());
    for (int s = 0; s < options.steps; ++s) {
      parallel_for(region.size(), grain, [&](std::size_t b, std::size_t e) {
        for (std::size_t a = b; a < e; ++a) {
          const int i = region[a];
          const int deg = adj.degree(i);
          buf[a] = pts[i];
          if (deg == 0 || pinned(i)) continue;
          Vec3f c{};
          for (int k = adj.offsets[i]; k < adj.offsets[i + 1]; ++k) c += pts[adj.neighbors[k]];
          buf[a] = c / static_cast<float>(deg);
        }
      });
      for (std::size_t a = 0; a < region.size(); ++a) pts[region[a]] = buf[a];
    }
    for (int i : region) {
      in[i] = 0;
      if (pinned(i)) continue;
      if (!moved[i]) moved[i] = 1, ++count;
      beta[i] = 1.f;
      touched[i] = 1;
      add_faces_of(i);
    }
  }
  return count;
}

void eval_field(const FieldFunction& field, const Vec3f* pts, std::size_t n, float* values, Vec3f* grads,
                std::uint8_t* contact, std::size_t grain) {
  parallel_for(n, grain, [&](std::size_t b, std::size_t e) {
    std::fill(contact + b, contact + e, std::uint8_t{0});
    field(pts + b, e - b, values + b, grads + b, contact + b);
  });
}

void vertex_stats(const std::vector<float>& values, const std::vector<float>& iso, const VertexFlags& flags,
                  TrackStats& stats) {
  double sum = 0;
  long count = 0;
  float mx = 0.f;
  stats.contact_vertices = 0;
  stats.lost_vertices = 0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    stats.contact_vertices += flags.contact[i];
    stats.lost_vertices += flags.lost[i];
    if (flags.contact[i] || flags.lost[i] || flags.beta[i] > 0.f || !std::isfinite(values[i])) continue;
    const float r = std::abs(values[i] - iso[i]);
    mx = std::max(mx, r);
    sum += r;
    ++count;
  }
  stats.max_residual = mx;
  stats.mean_residual = count > 0 ? static_cast<float>(sum / count) : 0.f;
}

void final_stats(const FieldFunction& field, const std::vector<Vec3f>& pts, const Triangles& triangles,
                 const std::vector<float>& iso, std::size_t grain, VertexFlags& flags, TrackStats& stats,
                 const std::vector<std::uint8_t>* inverted) {
  const std::size_t n = pts.size();
  std::vector<float> values(n);
  std::vector<Vec3f> grads(n);
  std::vector<std::uint8_t> fc(n);
  eval_field(field, pts.data(), n, values.data(), grads.data(), fc.data(), grain);
  for (std::size_t i = 0; i < n; ++i)
    if (fc[i]) flags.contact[i] = 1;
  vertex_stats(values, iso, flags, stats);
  stats.inverted_triangles = 0;
  if (inverted)
    for (std::uint8_t f : *inverted) stats.inverted_triangles += f;
  else
    for (std::uint8_t f : inverted_triangles(field, pts, triangles, grain)) stats.inverted_triangles += f;
}

Adjacency vertex_faces(const Triangles& triangles, std::size_t num_vertices) {
  Adjacency out;
  out.offsets.assign(num_vertices + 1, 0);
  for (Eigen::Index f = 0; f < triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k) ++out.offsets[static_cast<std::size_t>(triangles(f, k)) + 1];
  for (std::size_t v = 0; v < num_vertices; ++v) out.offsets[v + 1] += out.offsets[v];
  out.neighbors.resize(static_cast<std::size_t>(out.offsets.back()));
  std::vector<int> fill(out.offsets.begin(), out.offsets.end() - 1);
  for (Eigen::Index f = 0; f < triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k) out.neighbors[fill[triangles(f, k)]++] = static_cast<int>(f);
  return out;
}

void refresh_values(const FieldFunction& field, const std::vector<Vec3f>& pts, const std::vector<int>& redo,
                    std::size_t grain, std::vector<float>& values, VertexFlags& flags) {
  std::vector<Vec3f> p(redo.size()), g(redo.size());
  std::vector<float> v(redo.size());
  std::vector<std::uint8_t> c(redo.size());
  for (std::size_t a = 0; a < redo.size(); ++a) p[a] = pts[redo[a]];
  eval_field(field, p.data(), p.size(), v.data(), g.data(), c.data(), grain);
  for (std::size_t a = 0; a < redo.size(); ++a) {
    values[redo[a]] = v[a];
    if (c[a]) flags.contact[redo[a]] = 1;
  }
}

void final_stats_touched(const FieldFunction& field, const std::vector<Vec3f>& pts,
                         const Triangles& triangles, const Adjacency& vertex_faces,
                         const std::vector<float>& iso, std::vector<float>& values,
                         const std::vector<std::uint8_t>& touched, std::size_t grain, VertexFlags& flags,
                         TrackStats& stats, std::vector<std::uint8_t>& inverted,
                         const std::vector<std::uint8_t>* fresh) {
  const std::size_t n = pts.size();
  // Vertices to evaluate again, and triangles around smoothed vertices to test again.
  std::vector<int> redo;
  std::vector<std::uint8_t> tri_redo(inverted.size(), 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (touched[i]) redo.push_back(static_cast<int>(i));
    if (flags.beta[i] > 0.f)
      for (int k = vertex_faces.offsets[i]; k < vertex_faces.offsets[i + 1]; ++k) {
        const int f = vertex_faces.neighbors[k];
        if (!fresh || fresh->empty() || !(*fresh)[static_cast<std::size_t>(f)]) tri_redo[f] = 1;
      }
  }
  refresh_values(field, pts, redo, grain, values, flags);
  std::vector<int> tris;
  for (std::size_t f = 0; f < tri_redo.size(); ++f)
    if (tri_redo[f]) tris.push_back(static_cast<int>(f));
  {
    std::vector<Vec3f> cen(tris.size()), g(tris.size());
    std::vector<float> v(tris.size());
    std::vector<std::uint8_t> c(tris.size());
    for (std::size_t a = 0; a < tris.size(); ++a)
      cen[a] = (pts[triangles(tris[a], 0)] + pts[triangles(tris[a], 1)] + pts[triangles(tris[a], 2)]) / 3.f;
    eval_field(field, cen.data(), cen.size(), v.data(), g.data(), c.data(), grain);
    for (std::size_t a = 0; a < tris.size(); ++a) {
      const Eigen::Index r = tris[a];
      const Vec3f x = pts[triangles(r, 0)], y = pts[triangles(r, 1)], z = pts[triangles(r, 2)];
      inverted[static_cast<std::size_t>(r)] = dot(cross(y - x, z - x), g[a]) > 0.f ? 1 : 0;
    }
  }
  vertex_stats(values, iso, flags, stats);
  stats.inverted_triangles = 0;
  for (std::uint8_t f : inverted) stats.inverted_triangles += f;
}

std::vector<std::uint8_t> inverted_triangles(const FieldFunction& field, const std::vector<Vec3f>& pts,
                                             const Triangles& triangles, std::size_t grain,
                                             const std::vector<int>* candidates) {
  const std::size_t nf = static_cast<std::size_t>(triangles.rows());
  std::vector<int> all;
  if (!candidates) {
    all.resize(nf);
    for (std::size_t f = 0; f < nf; ++f) all[f] = static_cast<int>(f);
    candidates = &all;
  }
  const std::size_t m = candidates->size();
  std::vector<Vec3f> cen(m), cg(m);
  std::vector<float> cv(m);
  std::vector<std::uint8_t> cc(m), out(nf, 0);
  for (std::size_t k = 0; k < m; ++k) {
    const auto r = static_cast<Eigen::Index>((*candidates)[k]);
    cen[k] = (pts[triangles(r, 0)] + pts[triangles(r, 1)] + pts[triangles(r, 2)]) / 3.f;
  }
  eval_field(field, cen.data(), m, cv.data(), cg.data(), cc.data(), grain);
  for (std::size_t k = 0; k < m; ++k) {
    const auto r = static_cast<Eigen::Index>((*candidates)[k]);
    const Vec3f a = pts[triangles(r, 0)], b = pts[triangles(r, 1)], c = pts[triangles(r, 2)];
    if (dot(cross(b - a, c - a), cg[k]) > 0.f) out[static_cast<std::size_t>(r)] = 1;
  }
  return out;
}

void validate_mesh(const Positions& rest, const Triangles& triangles, std::size_t iso_size) {
  require(rest.rows() > 0, "rest positions", "are empty", "pass a mesh with vertices");
  require(
      iso_size == static_cast<std::size_t>(rest.rows()), "iso values",
      "size " + std::to_string(iso_size) + " differs from the vertex count " + std::to_string(rest.rows()),
      "pass one iso-value per vertex");
  validate_triangles(triangles, static_cast<int>(rest.rows()));
}

}  // namespace detail

std::vector<float> sample_iso_values(const FieldFunction& field, const Positions& positions) {
  const std::vector<Vec3f> pts = detail::to_points(positions, "positions");
  const std::size_t n = pts.size();
  std::vector<float> values(n);
  std::vector<Vec3f> grads(n);
  std::vector<std::uint8_t> contact(n);
  detail::eval_field(field, pts.data(), n, values.data(), grads.data(), contact.data(), 0);
  for (std::size_t i = 0; i < n; ++i)
    require(std::isfinite(values[i]), "field value at vertex " + std::to_string(i), "is not finite",
            "check the field");
  return values;
}

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
