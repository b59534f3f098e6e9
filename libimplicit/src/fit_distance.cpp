// SPDX-License-Identifier: MIT
// The distance field of a mesh part (fit.h, `fit_part_distance`; not in the papers:
// docs/decisions/part-fields-from-the-mesh.md). Steps: close the part's triangles with a dome over
// each border loop → measure its thickness (inward rays) → choose the grid and `r` → unsigned
// distance (exact near the triangles, closest points propagated by sweeps elsewhere) → inside by
// ray crossings along the three axes (two of three votes) → `t_r` of the signed distance.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "fit_caps.h"
#include "isokit/core/error.h"
#include "isokit/implicit/fit.h"

namespace isokit::implicit {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// The part closed by domes, in the bone frame. Vertices [0, own) are the part's own.
struct ClosedPart {
  std::vector<Vec3d> v;
  std::vector<std::array<int, 3>> t;
  int own{0};
  int domes{0};
};

/// Closest point to `p` on the triangle `a b c` (Ericson, Real-Time Collision Detection §5.1.5).
Vec3d closest_on_triangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3d bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vec3d cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0)) return a;  // degenerate triangle: its first vertex
  return a + ab * (vb / denom) + ac * (vc / denom);
}

/// One dome over `loop` (indices into `c.v`): rings from the loop (θ = 0) to an apex (θ = π/2),
/// ring θ at `centre + (v − centre) cos θ + out h sin θ`, so the dome leaves the loop along
/// `out` (tangent to a tube's wall) and closes it watertight.
void add_dome(ClosedPart& c, const std::vector<int>& loop, double height, const Vec3d& axis) {
  const std::size_t n = loop.size();
  Vec3d centre{}, newell{};
  double perimeter = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d a = c.v[static_cast<std::size_t>(loop[i])],
                b = c.v[static_cast<std::size_t>(loop[(i + 1) % n])];
    const double l = norm(b - a);
    centre += (a + b) * (0.5 * l);
    perimeter += l;
    newell += cross(a, b);
  }
  if (!(perimeter > 0)) return;
  centre = centre / perimeter;
  const double nn = norm(newell);
  const Vec3d out = nn > 0 ? newell * (-1.0 / nn) : axis;
  double radius = 0;
  for (int i : loop) {
    const Vec3d d = c.v[static_cast<std::size_t>(i)] - centre;
    radius += norm(d - out * dot(d, out)) / double(n);
  }
  const double h = height * radius * std::abs(dot(out, axis));
  const double spacing = perimeter / double(n);
  const int rings =
      std::clamp(int(std::ceil(0.5 * kPi * std::max(radius, h) / std::max(spacing, 1e-300))), 1, 12);
  std::vector<int> prev(loop.begin(), loop.end());
  for (int k = 1; k < rings; ++k) {
    const double th = 0.5 * kPi * double(k) / double(rings);
    std::vector<int> ring(n);
    for (std::size_t i = 0; i < n; ++i) {
      ring[i] = int(c.v.size());
      c.v.push_back(centre + (c.v[static_cast<std::size_t>(loop[i])] - centre) * std::cos(th) +
                    out * (h * std::sin(th)));
    }
    for (std::size_t i = 0; i < n; ++i) {  // the loop runs as its triangles do: the cap the other way
      const std::size_t j = (i + 1) % n;
      c.t.push_back({prev[j], prev[i], ring[i]});
      c.t.push_back({prev[j], ring[i], ring[j]});
    }
    prev = std::move(ring);
  }
  const int apex = int(c.v.size());
  c.v.push_back(centre + out * h);
  for (std::size_t i = 0; i < n; ++i) c.t.push_back({prev[(i + 1) % n], prev[i], apex});
  ++c.domes;
}

ClosedPart close_part(const std::vector<Vec3d>& v, const std::vector<std::array<int, 3>>& t, double height) {
  ClosedPart c{v, t, int(v.size()), 0};
  for (const std::vector<int>& loop : detail::boundary_loops(t, int(v.size())))
    add_dome(c, loop, height, {0, 0, 1});
  return c;
}

/// Distance along `d` from `o` to the triangle `a b c` (Möller–Trumbore), infinite when missed.
double ray_triangle(const Vec3d& o, const Vec3d& d, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d e1 = b - a, e2 = c - a, pv = cross(d, e2);
  const double det = dot(e1, pv);
  if (std::abs(det) < 1e-300) return kInf;
  const double inv = 1.0 / det;
  const Vec3d tv = o - a;
  const double u = dot(tv, pv) * inv;
  if (u < 0 || u > 1) return kInf;
  const Vec3d qv = cross(tv, e1);
  const double w = dot(d, qv) * inv;
  if (w < 0 || u + w > 1) return kInf;
  const double s = dot(e2, qv) * inv;
  return s > 0 ? s : kInf;
}

/// The part's thickness at up to 512 of its own vertices: from the vertex along its inward
/// (area-weighted) normal to the nearest triangle not incident to it. Sorted.
std::vector<double> thicknesses(const ClosedPart& c) {
  std::vector<Vec3d> normal(c.v.size());
  for (const auto& tri : c.t) {
    const Vec3d n = cross(c.v[tri[1]] - c.v[tri[0]], c.v[tri[2]] - c.v[tri[0]]);
    for (int k = 0; k < 3; ++k) normal[static_cast<std::size_t>(tri[k])] += n;
  }
  const int stride = std::max(1, c.own / 512);
  std::vector<double> out;
  for (int i = 0; i < c.own; i += stride) {
    const double l = norm(normal[i]);
    if (!(l > 0)) continue;
    const Vec3d d = normal[i] * (-1.0 / l);
    double best = kInf;
    for (const auto& tri : c.t) {
      if (tri[0] == i || tri[1] == i || tri[2] == i) continue;
      best = std::min(best, ray_triangle(c.v[i], d, c.v[tri[0]], c.v[tri[1]], c.v[tri[2]]));
    }
    if (std::isfinite(best) && best > 0) out.push_back(best);
  }
  std::sort(out.begin(), out.end());
  return out;
}

double percentile(const std::vector<double>& sorted, double q) {
  const std::size_t i = std::min(sorted.size() - 1, std::size_t(q * double(sorted.size())));
  return sorted[i];
}

/// A regular lattice of n³ nodes over `box`, x fastest (GridField's layout).
struct Lattice {
  int n{0};
  Box3d box;
  Vec3d step;
  Vec3d node(int i, int j, int k) const {
    return {box.lo.x + step.x * i, box.lo.y + step.y * j, box.lo.z + step.z * k};
  }
  std::size_t index(int i, int j, int k) const {
    return (std::size_t(k) * std::size_t(n) + std::size_t(j)) * std::size_t(n) + std::size_t(i);
  }
  std::size_t size() const { return std::size_t(n) * std::size_t(n) * std::size_t(n); }
};

/// The closest-point propagation's state per node.
struct ClosestPoints {
  std::vector<double> dist;          ///< distance to the closest point found (infinite: none yet)
  std::vector<Vec3f> cp;             ///< that point
  std::vector<std::uint8_t> has_cp;  ///< holds a closest point
  std::vector<std::uint8_t> fixed;   ///< exact (band) or beyond reach: not swept
};

/// Exact closest points at the nodes within `band` of a triangle's box.
void exact_band(const Lattice& L, const ClosedPart& c, double band, ClosestPoints& s) {
  for (const auto& tri : c.t) {
    const Vec3d &a = c.v[tri[0]], &b = c.v[tri[1]], &d = c.v[tri[2]];
    int lo[3], hi[3];
    for (int ax = 0; ax < 3; ++ax) {
      const double mn = std::min({a[ax], b[ax], d[ax]}) - band, mx = std::max({a[ax], b[ax], d[ax]}) + band;
      lo[ax] = std::max(0, int(std::floor((mn - L.box.lo[ax]) / L.step[ax])));
      hi[ax] = std::min(L.n - 1, int(std::ceil((mx - L.box.lo[ax]) / L.step[ax])));
    }
    for (int k = lo[2]; k <= hi[2]; ++k)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int i = lo[0]; i <= hi[0]; ++i) {
          const Vec3d p = L.node(i, j, k);
          const Vec3d q = closest_on_triangle(p, a, b, d);
          const double dd = norm(p - q);
          const std::size_t id = L.index(i, j, k);
          if (dd < s.dist[id])
            s.dist[id] = dd, s.cp[id] = {float(q.x), float(q.y), float(q.z)}, s.has_cp[id] = 1;
        }
  }
}

/// The 8 diagonal sweeps: each node not fixed takes the nearest of its 7 upwind neighbours'
/// closest points (squared distances compared over precomputed index offsets).
void sweep(const Lattice& L, ClosestPoints& st) {
  const long sy = L.n, sz = long(L.n) * L.n;
  for (int sweep = 0; sweep < 8; ++sweep) {
    const int s[3] = {sweep & 1 ? -1 : 1, sweep & 2 ? -1 : 1, sweep & 4 ? -1 : 1};
    long offset[8] = {0};
    for (int o = 1; o < 8; ++o)
      offset[o] = -((o & 1) ? s[0] : 0) - ((o & 2) ? s[1] * sy : 0) - ((o & 4) ? s[2] * sz : 0);
    for (int tk = 0; tk < L.n; ++tk)
      for (int tj = 0; tj < L.n; ++tj)
        for (int ti = 0; ti < L.n; ++ti) {
          const int i = s[0] > 0 ? ti : L.n - 1 - ti, j = s[1] > 0 ? tj : L.n - 1 - tj,
                    k = s[2] > 0 ? tk : L.n - 1 - tk;
          const std::size_t id = L.index(i, j, k);
          if (st.fixed[id]) continue;
          // An upwind step leaves the lattice only from the first node of a sweep's axis.
          const int ok = (ti > 0 ? 1 : 0) | (tj > 0 ? 2 : 0) | (tk > 0 ? 4 : 0);
          const Vec3d pd = L.node(i, j, k);
          const Vec3f p{float(pd.x), float(pd.y), float(pd.z)};
          float best2 = std::isfinite(st.dist[id]) ? float(st.dist[id] * st.dist[id])
                                                   : std::numeric_limits<float>::infinity();
          long from = -1;
          for (int o = 1; o < 8; ++o) {
            if ((o & ok) != o) continue;
            const std::size_t nb = std::size_t(long(id) + offset[o]);
            if (!st.has_cp[nb]) continue;
            const Vec3f e = p - st.cp[nb];
            const float d2 = dot(e, e);
            if (d2 < best2) best2 = d2, from = long(nb);
          }
          if (from >= 0) {
            st.cp[id] = st.cp[std::size_t(from)];
            st.dist[id] = std::sqrt(double(best2));
            st.has_cp[id] = 1;
          }
        }
  }
}

/// Unsigned distance to the triangles: exact at the nodes within 1.5 cells of a triangle's box
/// (`exact_band`), propagated elsewhere (`sweep`). Only the nodes within `reach` of the closed
/// part's box are swept; farther ones keep their distance to that box, a lower bound (`t_r` is
/// 0 there anyway), and nodes no sweep reaches get `reach`.
std::vector<double> unsigned_distance(const Lattice& L, const ClosedPart& c, double reach) {
  ClosestPoints st{std::vector<double>(L.size(), kInf), std::vector<Vec3f>(L.size()),
                   std::vector<std::uint8_t>(L.size(), 0), std::vector<std::uint8_t>(L.size(), 0)};
  const double band = 1.5 * std::max({L.step.x, L.step.y, L.step.z});
  exact_band(L, c, band, st);
  Box3d core;
  for (const Vec3d& p : c.v) core.extend(p);
  for (int k = 0; k < L.n; ++k)
    for (int j = 0; j < L.n; ++j)
      for (int i = 0; i < L.n; ++i) {
        const std::size_t id = L.index(i, j, k);
        if (st.dist[id] <= band) {
          st.fixed[id] = 1;
          continue;
        }
        const Vec3d p = L.node(i, j, k);
        Vec3d out;
        for (int a = 0; a < 3; ++a) out[a] = std::max({core.lo[a] - p[a], 0.0, p[a] - core.hi[a]});
        const double box_distance = norm(out);
        if (box_distance > reach) st.dist[id] = box_distance, st.fixed[id] = 1, st.has_cp[id] = 0;
      }
  sweep(L, st);
  for (double& d : st.dist)
    if (!std::isfinite(d)) d = reach;
  return st.dist;
}

/// Inside votes along axis `a`: the signed number of crossings of the ray from each node towards
/// +a (an outward-facing triangle crossed counts +1) is positive inside a closed, outward surface.
void vote_inside(const Lattice& L, const ClosedPart& c, int a, std::vector<std::uint8_t>& votes) {
  const int b = (a + 1) % 3, e = (a + 2) % 3;
  const std::size_t n = std::size_t(L.n);
  struct Crossing {
    std::size_t column;
    double x;
    int sign;
  };
  std::vector<Crossing> crossings;
  // Rays run off the lattice lines by a small irrational fraction of a cell, so that they miss
  // the triangles' edges and vertices that sit on the lines.
  const double ob = 1.2345678e-4 * L.step[b], oe = 2.7182818e-4 * L.step[e];
  for (const auto& tri : c.t) {
    const Vec3d &p0 = c.v[tri[0]], &p1 = c.v[tri[1]], &p2 = c.v[tri[2]];
    const double na = cross(p1 - p0, p2 - p0)[a];
    if (na == 0) continue;
    const int sign = na > 0 ? 1 : -1;
    const int jb0 =
        std::max(0, int(std::floor((std::min({p0[b], p1[b], p2[b]}) - ob - L.box.lo[b]) / L.step[b])));
    const int jb1 =
        std::min(L.n - 1, int(std::ceil((std::max({p0[b], p1[b], p2[b]}) - ob - L.box.lo[b]) / L.step[b])));
    const int je0 =
        std::max(0, int(std::floor((std::min({p0[e], p1[e], p2[e]}) - oe - L.box.lo[e]) / L.step[e])));
    const int je1 =
        std::min(L.n - 1, int(std::ceil((std::max({p0[e], p1[e], p2[e]}) - oe - L.box.lo[e]) / L.step[e])));
    auto edge = [&](const Vec3d& u, const Vec3d& v, double qb, double qe) {
      return (v[b] - u[b]) * (qe - u[e]) - (v[e] - u[e]) * (qb - u[b]);
    };
    for (int je = je0; je <= je1; ++je)
      for (int jb = jb0; jb <= jb1; ++jb) {
        const double qb = L.box.lo[b] + L.step[b] * jb + ob, qe = L.box.lo[e] + L.step[e] * je + oe;
        const double w0 = edge(p1, p2, qb, qe), w1 = edge(p2, p0, qb, qe), w2 = edge(p0, p1, qb, qe);
        const bool in = (w0 >= 0 && w1 >= 0 && w2 >= 0) || (w0 <= 0 && w1 <= 0 && w2 <= 0);
        const double sum = w0 + w1 + w2;
        if (!in || sum == 0) continue;
        const double xa = (w0 * p0[a] + w1 * p1[a] + w2 * p2[a]) / sum;
        crossings.push_back({std::size_t(je) * n + std::size_t(jb), xa, sign});
      }
  }
  std::sort(crossings.begin(), crossings.end(), [](const Crossing& x, const Crossing& y) {
    return x.column != y.column ? x.column < y.column : x.x > y.x;
  });
  std::size_t next = 0;
  for (std::size_t col = 0; col < n * n; ++col) {
    const std::size_t jb = col % n, je = col / n;
    int w = 0;
    for (int ia = L.n - 1; ia >= 0; --ia) {
      const double x = L.box.lo[a] + L.step[a] * ia;
      while (next < crossings.size() && crossings[next].column == col && crossings[next].x > x)
        w += crossings[next++].sign;
      int idx[3];
      idx[a] = ia;
      idx[b] = int(jb);
      idx[e] = int(je);
      if (w > 0) ++votes[L.index(idx[0], idx[1], idx[2])];
    }
    while (next < crossings.size() && crossings[next].column == col) ++next;  // below the lattice
  }
}

/// `passes` passes of the binomial filter [1 2 1] / 4 along each axis (the faces keep their
/// own value on the missing side): rounds the signed distance's creases over about a cell per
/// pass, so that the gradient turns gradually around a coarse mesh's corners.
void smooth(const Lattice& L, int passes, std::vector<double>& d) {
  std::vector<double> tmp(d.size());
  for (int pass = 0; pass < passes; ++pass)
    for (int a = 0; a < 3; ++a) {
      for (int k = 0; k < L.n; ++k)
        for (int j = 0; j < L.n; ++j)
          for (int i = 0; i < L.n; ++i) {
            int lo[3] = {i, j, k}, hi[3] = {i, j, k};
            lo[a] = std::max(0, lo[a] - 1);
            hi[a] = std::min(L.n - 1, hi[a] + 1);
            const std::size_t id = L.index(i, j, k);
            tmp[id] = 0.25 * (d[L.index(lo[0], lo[1], lo[2])] + 2 * d[id] + d[L.index(hi[0], hi[1], hi[2])]);
          }
      d.swap(tmp);
    }
}

/// Node data (value, gradient) of `t_r(d)`, `d` the signed distance, ∇d by central differences
/// (one-sided on the faces).
std::vector<float> remapped_nodes(const Lattice& L, const std::vector<double>& d, double r) {
  std::vector<float> nodes(4 * L.size());
  for (int k = 0; k < L.n; ++k)
    for (int j = 0; j < L.n; ++j)
      for (int i = 0; i < L.n; ++i) {
        const int idx[3] = {i, j, k};
        Vec3d g;
        for (int a = 0; a < 3; ++a) {
          int lo[3] = {i, j, k}, hi[3] = {i, j, k};
          lo[a] = std::max(0, idx[a] - 1);
          hi[a] = std::min(L.n - 1, idx[a] + 1);
          g[a] = (d[L.index(hi[0], hi[1], hi[2])] - d[L.index(lo[0], lo[1], lo[2])]) /
                 (L.step[a] * (hi[a] - lo[a]));
        }
        double dt = 0;
        const double f = remap_tr(d[L.index(i, j, k)], r, &dt);
        float* node = &nodes[4 * L.index(i, j, k)];
        node[0] = float(f);
        node[1] = float(dt * g.x);
        node[2] = float(dt * g.y);
        node[3] = float(dt * g.z);
      }
  return nodes;
}

/// The lattice and `r`: spacing from the thinnest feature, `r` from the width; the box is the
/// closed part's box grown by `r` and a cell on each axis, so that the field is 0 on its faces.
/// The same number of nodes on every axis: a long, thin part (a sword, a finger) gets finer
/// cells across than along.
Lattice choose_lattice(const ClosedPart& c, const DistanceFitOptions& o, double& r) {
  Box3d core;
  for (const Vec3d& p : c.v) core.extend(p);
  const double diag = norm(core.size());
  const std::vector<double> th = thicknesses(c);
  const double feature = th.empty() ? diag / 8 : percentile(th, o.feature_percentile);
  r = th.empty() ? diag / 4 : 0.5 * percentile(th, o.width_percentile);
  const double span = std::max({core.size().x, core.size().y, core.size().z});
  const double wanted = feature / o.cells_per_feature;
  Lattice L;
  L.n = std::clamp(int(std::ceil((span + 2 * r) / std::max(wanted, 1e-12 * diag))) + 3, o.min_resolution,
                   o.max_resolution);
  // Two cells at least (across the thinnest axis): below that t_r is a step.
  const double thinnest = std::min({core.size().x, core.size().y, core.size().z});
  r = std::max(r, 2 * (thinnest + 2 * r) / double(L.n - 3));
  for (int a = 0; a < 3; ++a) {
    const double grow = r + (core.size()[a] + 2 * r) / double(L.n - 3);
    L.box.lo[a] = core.lo[a] - grow;
    L.box.hi[a] = core.hi[a] + grow;
    L.step[a] = (L.box.hi[a] - L.box.lo[a]) / double(L.n - 1);
  }
  return L;
}

/// The part's input, checked: finite bone of non-zero length, a sub-mesh, indices in range,
/// finite vertices.
void check_part(const MeshPart& part) {
  const std::string& name = part.name;
  require(std::isfinite(part.bone_start.x) && std::isfinite(part.bone_start.y) &&
              std::isfinite(part.bone_start.z) && std::isfinite(part.bone_end.x) &&
              std::isfinite(part.bone_end.y) && std::isfinite(part.bone_end.z),
          name + ": bone", "has non-finite end points", "fix the skeleton");
  require(!part.vertices.empty() && !part.triangles.empty(), name, "the sub-mesh is empty",
          "assign triangles to this bone or leave it out of the rig");
  const int nv = int(part.vertices.size());
  for (std::size_t t = 0; t < part.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)
      if (part.triangles[t][k] < 0 || part.triangles[t][k] >= nv)
        require(false, name + ": triangle " + std::to_string(t),
                "indexes vertex " + std::to_string(part.triangles[t][k]) + " of " + std::to_string(nv),
                "fix the indices");
  Box3d vbox;
  for (std::size_t i = 0; i < part.vertices.size(); ++i) {
    const Vec3d& p = part.vertices[i];
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)))
      require(false, name + ": vertex " + std::to_string(i), "is not finite", "remove NaN/inf vertices");
    vbox.extend(p);
  }
  const double len = norm(part.bone_end - part.bone_start);
  require(len > 1e-9 * std::max(1.0, norm(vbox.size())), name + ": bone",
          "has zero length (" + format_number(len) + ")", "give the bone distinct end points");
}

}  // namespace

void check_distance_options(const DistanceFitOptions& o, const std::string& where) {
  require(o.cells_per_feature >= 1 && o.cells_per_feature <= 16, where + ".cells_per_feature",
          "must be in [1, 16] (got " + format_number(o.cells_per_feature) + ")", "use the default 3");
  require(o.feature_percentile > 0 && o.feature_percentile < 1, where + ".feature_percentile",
          "must be in (0, 1) (got " + format_number(o.feature_percentile) + ")", "use the default 0.25");
  require(o.width_percentile > 0 && o.width_percentile <= 1, where + ".width_percentile",
          "must be in (0, 1] (got " + format_number(o.width_percentile) + ")", "use the default 0.9");
  require(o.min_resolution >= 8 && o.max_resolution <= GridField::kMaxResolution &&
              o.min_resolution <= o.max_resolution,
          where + ".min_resolution / max_resolution",
          "need 8 <= min_resolution <= max_resolution <= " + std::to_string(GridField::kMaxResolution) +
              " (got " + std::to_string(o.min_resolution) + ", " + std::to_string(o.max_resolution) + ")",
          "use the defaults 32 and 64");
  require(o.overlap_rings >= 0 && o.overlap_rings <= 8, where + ".overlap_rings",
          "must be in [0, 8] (got " + std::to_string(o.overlap_rings) + ")", "use the default 1");
  require(o.smoothing_passes >= 0 && o.smoothing_passes <= 8, where + ".smoothing_passes",
          "must be in [0, 8] (got " + std::to_string(o.smoothing_passes) + ")", "use the default 0");
  require(o.overlap_sink >= 0 && o.overlap_sink <= 1, where + ".overlap_sink",
          "must be in [0, 1] (got " + format_number(o.overlap_sink) + ")", "use the default 0.2");
  require(o.cap_height >= 0 && o.cap_height <= 2, where + ".cap_height",
          "must be in [0, 2] (got " + format_number(o.cap_height) + ")", "use the default 1");
}

FittedPart fit_part_distance(const MeshPart& part, const PartFitOptions& options) {
  const std::string& name = part.name;
  check_distance_options(options.distance, name + ": distance");
  check_part(part);
  FittedPart out;
  out.local_to_world = bone_frame(part.bone_start, part.bone_end);
  std::vector<Vec3d> local(part.vertices.size());
  for (std::size_t i = 0; i < local.size(); ++i)
    local[i] = out.local_to_world.apply_inverse(part.vertices[i]);
  const ClosedPart closed = close_part(local, part.triangles, options.distance.cap_height);
  out.closure_points = closed.domes;
  double r = 0;
  const Lattice L = choose_lattice(closed, options.distance, r);
  std::vector<double> d = unsigned_distance(L, closed, r + 2 * std::max({L.step.x, L.step.y, L.step.z}));
  std::vector<std::uint8_t> votes(L.size(), 0);
  for (int a = 0; a < 3; ++a) vote_inside(L, closed, a, votes);
  std::size_t inside = 0;
  for (std::size_t i = 0; i < d.size(); ++i)
    if (votes[i] >= 2) d[i] = -d[i], ++inside;
  require(inside > 0, name,
          "the part's closed surface has no inside on its grid (an open sheet, or triangles "
          "oriented inward)",
          "leave the part to the HRBF fit (fit.field \"hrbf\"), or flip the triangle winding");
  smooth(L, options.distance.smoothing_passes, d);
  out.r = r;
  const Box3f box{{float(L.box.lo.x), float(L.box.lo.y), float(L.box.lo.z)},
                  {float(L.box.hi.x), float(L.box.hi.y), float(L.box.hi.z)}};
  out.grid = std::make_shared<const GridField>(L.n, box, remapped_nodes(L, d, r), options.grid_storage);
  return out;
}

}  // namespace isokit::implicit
