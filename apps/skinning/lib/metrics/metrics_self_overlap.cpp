// SPDX-License-Identifier: MIT
// The volume a mesh encloses twice, by winding numbers swept along grid columns (self_overlap.h).
// Stages: the grid over the mesh's bounding box; each triangle's crossings of the column centres
// inside its (x, y) projection (counted, then written, so the result does not depend on the
// tasks); the crossings bucketed by column; each column sorted along z and swept.
#include "isokit/skinning/self_overlap.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <string>
#include <utility>

#include "isokit/core/error.h"
#include "isokit/core/parallel.h"
#include "metrics/metrics_check.h"

namespace isokit::skinning {
namespace {

/// The column grid: centres at `origin + (i + offset) * cell` along x and y.
struct ColumnGrid {
  double x0{0}, y0{0}, cell{1};
  int nx{0}, ny{0};
  /// Column centres sit this fraction of a cell past the grid lines, off 0.5 by an amount that no
  /// authored coordinate is likely to hit, so that centres rarely fall on vertices or edges.
  static constexpr double kOffsetX = 0.5 + 0.0137;
  static constexpr double kOffsetY = 0.5 + 0.0291;
  double cx(int i) const { return x0 + (i + kOffsetX) * cell; }
  double cy(int j) const { return y0 + (j + kOffsetY) * cell; }
};

/// One triangle crossing one column.
struct Crossing {
  int column;
  int triangle;
  double z;
  int step;  ///< change of the winding number along +z: -1 leaving (normal +z), +1 entering
};

void check_input(const track::Positions& p, const track::Triangles& t, const SelfOverlapOptions& o) {
  if (o.resolution < 1 || o.resolution > 4096)
    throw InputError("self_overlap: option resolution is " + std::to_string(o.resolution) +
                     "; it must be in [1, 4096] cells (default 160)");
  detail::check_triangles(t, p.rows(), "self_overlap");
  for (Eigen::Index f = 0; f < t.rows(); ++f)
    for (int c = 0; c < 3; ++c)
      if (!p.row(t(f, c)).allFinite())
        throw InputError("self_overlap: triangle " + std::to_string(f) + " has a non-finite corner (vertex " +
                         std::to_string(t(f, c)) + "); pass finite positions");
}

/// The grid over the bounding box of the triangles' corners: `resolution` cells across its
/// largest side. An empty grid when there is no triangle or the box is a point.
ColumnGrid make_grid(const track::Positions& p, const track::Triangles& t, int resolution) {
  ColumnGrid g;
  if (t.rows() == 0) return g;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (Eigen::Index f = 0; f < t.rows(); ++f)
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d v = p.row(t(f, c)).cast<double>().transpose();
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
  const double side = (hi - lo).maxCoeff();
  if (!(side > 0)) return g;
  g.cell = side / resolution;
  g.x0 = lo.x() - g.cell;  // one spare cell on each side: every centre inside the box is on the grid
  g.y0 = lo.y() - g.cell;
  g.nx = static_cast<int>(std::ceil((hi.x() - lo.x()) / g.cell)) + 2;
  g.ny = static_cast<int>(std::ceil((hi.y() - lo.y()) / g.cell)) + 2;
  return g;
}

/// The projected triangle and its canonical edge functions. Each edge function is computed from
/// the edge's lower-index vertex to its higher-index one, so two triangles sharing an edge compute
/// bitwise the same value and a centre on the edge is counted by exactly one of them when they lie
/// on opposite sides of it.
struct ProjectedTriangle {
  double x[3], y[3], z[3];
  int v[3];
  int sign{0};  ///< +1 counter-clockwise seen from +z (normal along +z), -1 clockwise, 0 edge-on

  ProjectedTriangle(const track::Positions& p, const track::Triangles& t, Eigen::Index f) {
    for (int c = 0; c < 3; ++c) {
      v[c] = t(f, c);
      x[c] = p(v[c], 0);
      y[c] = p(v[c], 1);
      z[c] = p(v[c], 2);
    }
    const double area2 = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
    sign = area2 > 0 ? 1 : area2 < 0 ? -1 : 0;
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) sign = 0;
  }

  /// Edge c (from corner c to corner c+1) at (px, py), positive on the triangle's inner side; and
  /// whether a centre exactly on the edge belongs to this triangle.
  double edge(int c, double px, double py, bool* owns_tie) const {
    const int a = c, b = (c + 1) % 3;
    const bool forward = v[a] < v[b];
    const int lo = forward ? a : b, hi = forward ? b : a;
    const double e = (x[hi] - x[lo]) * (py - y[lo]) - (y[hi] - y[lo]) * (px - x[lo]);
    const int orient = (forward ? 1 : -1) * sign;
    *owns_tie = orient > 0;
    return orient * e;
  }

  /// The crossing of the column through (px, py), if the centre is inside: writes z.
  bool cross(double px, double py, double* zc) const {
    double w[3];
    for (int c = 0; c < 3; ++c) {
      bool owns_tie = false;
      const double e = edge(c, px, py, &owns_tie);
      if (e < 0 || (e == 0 && !owns_tie)) return false;
      w[(c + 2) % 3] = e;  // edge c is opposite corner c + 2
    }
    const double sum = w[0] + w[1] + w[2];
    if (!(sum > 0)) return false;
    *zc = z[0] + (w[1] * (z[1] - z[0]) + w[2] * (z[2] - z[0])) / sum;  // exact on a level triangle
    return true;
  }
};

/// Calls `emit(column, z)` for every column centre inside the projected triangle.
template <class Emit>
void for_each_crossing(const ColumnGrid& g, const ProjectedTriangle& tri, Emit&& emit) {
  if (tri.sign == 0) return;
  const double xmin = std::min({tri.x[0], tri.x[1], tri.x[2]}),
               xmax = std::max({tri.x[0], tri.x[1], tri.x[2]});
  const double ymin = std::min({tri.y[0], tri.y[1], tri.y[2]}),
               ymax = std::max({tri.y[0], tri.y[1], tri.y[2]});
  const int i0 = std::max(0, static_cast<int>(std::floor((xmin - g.x0) / g.cell - ColumnGrid::kOffsetX)));
  const int i1 =
      std::min(g.nx - 1, static_cast<int>(std::ceil((xmax - g.x0) / g.cell - ColumnGrid::kOffsetX)));
  const int j0 = std::max(0, static_cast<int>(std::floor((ymin - g.y0) / g.cell - ColumnGrid::kOffsetY)));
  const int j1 =
      std::min(g.ny - 1, static_cast<int>(std::ceil((ymax - g.y0) / g.cell - ColumnGrid::kOffsetY)));
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      double z = 0;
      if (tri.cross(g.cx(i), g.cy(j), &z)) emit(j * g.nx + i, z);
    }
}

/// Every crossing, grouped by column (ascending column, then triangle order within a column).
/// Returns the crossings and, in `starts`, each column's first index (`columns + 1` entries).
std::vector<Crossing> column_crossings(const track::Positions& p, const track::Triangles& t,
                                       const ColumnGrid& g, std::size_t grain,
                                       std::vector<std::size_t>* starts) {
  const auto nf = static_cast<std::size_t>(t.rows());
  std::vector<std::size_t> per_triangle(nf + 1, 0);
  parallel_for(nf, grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t f = b; f < e; ++f) {
      std::size_t n = 0;
      for_each_crossing(g, ProjectedTriangle(p, t, static_cast<Eigen::Index>(f)), [&](int, double) { ++n; });
      per_triangle[f + 1] = n;
    }
  });
  for (std::size_t f = 0; f < nf; ++f) per_triangle[f + 1] += per_triangle[f];
  std::vector<Crossing> by_triangle(per_triangle[nf]);
  parallel_for(nf, grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t f = b; f < e; ++f) {
      const ProjectedTriangle tri(p, t, static_cast<Eigen::Index>(f));
      std::size_t k = per_triangle[f];
      for_each_crossing(g, tri, [&](int column, double z) {
        by_triangle[k++] = Crossing{column, static_cast<int>(f), z, -tri.sign};
      });
    }
  });
  // Counting sort by column (stable: triangle order is kept within a column).
  const std::size_t nc = static_cast<std::size_t>(g.nx) * static_cast<std::size_t>(g.ny);
  starts->assign(nc + 1, 0);
  for (const Crossing& c : by_triangle) ++(*starts)[static_cast<std::size_t>(c.column) + 1];
  for (std::size_t c = 0; c < nc; ++c) (*starts)[c + 1] += (*starts)[c];
  std::vector<std::size_t> next(starts->begin(), starts->end() - 1);
  std::vector<Crossing> by_column(by_triangle.size());
  for (const Crossing& c : by_triangle) by_column[next[static_cast<std::size_t>(c.column)]++] = c;
  return by_column;
}

/// Small union-find over vertex indices (the border's connected pieces).
struct DisjointSets {
  std::vector<int> parent;
  explicit DisjointSets(std::size_t n) : parent(n) {
    for (std::size_t i = 0; i < n; ++i) parent[i] = static_cast<int>(i);
  }
  int find(int i) {
    while (parent[static_cast<std::size_t>(i)] != i)
      i = parent[static_cast<std::size_t>(i)] =
          parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    return i;
  }
  void join(int a, int b) { parent[static_cast<std::size_t>(find(a))] = find(b); }
};

/// The mesh with its open borders closed: the border is the boundary of the triangles as a chain
/// (each undirected edge with the net number of times the triangles run it one way), and each
/// connected piece of it is coned to the centroid of its vertices. The boundary of a boundary is
/// empty, so the result is closed whatever the holes' shapes (and misoriented pairs, which leave
/// an edge run twice the same way, are closed too). For a closed mesh `closed` is false and the
/// arrays stay empty: the caller's mesh is used as it is, without a copy.
struct ClosedMesh {
  bool closed{false};
  track::Positions positions;
  track::Triangles triangles;
};

ClosedMesh close_borders(const track::Positions& p, const track::Triangles& t) {
  std::vector<std::pair<std::uint64_t, int>> runs;  // (lo << 32 | hi, +1 when run lo -> hi)
  runs.reserve(static_cast<std::size_t>(t.rows()) * 3);
  for (Eigen::Index f = 0; f < t.rows(); ++f)
    for (int c = 0; c < 3; ++c) {
      const int a = t(f, c), b = t(f, (c + 1) % 3);
      if (a == b) continue;
      const auto lo = static_cast<std::uint32_t>(std::min(a, b)),
                 hi = static_cast<std::uint32_t>(std::max(a, b));
      runs.emplace_back(std::uint64_t(lo) << 32 | hi, a < b ? 1 : -1);
    }
  std::sort(runs.begin(), runs.end());
  std::vector<std::pair<std::uint64_t, int>> border;  // net runs != 0
  for (std::size_t k = 0; k < runs.size();) {
    std::size_t e = k;
    int net = 0;
    for (; e < runs.size() && runs[e].first == runs[k].first; ++e) net += runs[e].second;
    if (net != 0) border.emplace_back(runs[k].first, net);
    k = e;
  }
  ClosedMesh out;
  if (border.empty()) return out;
  out = ClosedMesh{true, p, t};
  DisjointSets sets(static_cast<std::size_t>(p.rows()));
  for (const auto& [key, net] : border)
    sets.join(static_cast<int>(key >> 32), static_cast<int>(key & 0xffffffffu));
  std::vector<int> apex_of(static_cast<std::size_t>(p.rows()), -1);
  std::vector<Eigen::Vector3d> sum;
  std::vector<int> count;
  auto apex = [&](int v) {
    const int root = sets.find(v);
    int& a = apex_of[static_cast<std::size_t>(root)];
    if (a < 0) {
      a = static_cast<int>(sum.size());
      sum.emplace_back(Eigen::Vector3d::Zero());
      count.push_back(0);
    }
    return a;
  };
  std::vector<std::array<int, 3>> cones;
  std::vector<char> summed(static_cast<std::size_t>(p.rows()), 0);
  for (const auto& [key, net] : border) {
    const int lo = static_cast<int>(key >> 32), hi = static_cast<int>(key & 0xffffffffu);
    const int a = apex(lo);
    for (const int v : {lo, hi})
      if (!summed[static_cast<std::size_t>(v)]) {
        summed[static_cast<std::size_t>(v)] = 1;
        sum[static_cast<std::size_t>(a)] += p.row(v).cast<double>().transpose();
        ++count[static_cast<std::size_t>(a)];
      }
    const int apex_vertex = static_cast<int>(p.rows()) + a;
    for (int n = 0; n < std::abs(net); ++n)  // the cone runs the edge the other way round
      cones.push_back(net > 0 ? std::array<int, 3>{hi, lo, apex_vertex}
                              : std::array<int, 3>{lo, hi, apex_vertex});
  }
  out.positions.conservativeResize(p.rows() + static_cast<Eigen::Index>(sum.size()), 3);
  for (std::size_t a = 0; a < sum.size(); ++a)
    out.positions.row(p.rows() + static_cast<Eigen::Index>(a)) =
        (sum[a] / count[a]).cast<float>().transpose();
  out.triangles.conservativeResize(t.rows() + static_cast<Eigen::Index>(cones.size()), 3);
  for (std::size_t k = 0; k < cones.size(); ++k)
    out.triangles.row(t.rows() + static_cast<Eigen::Index>(k)) << cones[k][0], cones[k][1], cones[k][2];
  return out;
}

/// One column's sweep: lengths enclosed once and twice, whether it is open, and (optionally) the
/// crossings that border a segment enclosed twice.
struct ColumnResult {
  double once{0}, twice{0};
  bool open{false};
};

ColumnResult sweep_column(Crossing* begin, Crossing* end, std::vector<char>* marks) {
  ColumnResult r;
  if (end - begin < 2) {
    r.open = end != begin;
    return r;
  }
  std::sort(begin, end, [](const Crossing& a, const Crossing& b) {
    return a.z != b.z ? a.z < b.z : a.triangle < b.triangle;
  });
  int total = 0;
  for (const Crossing* c = begin; c != end; ++c) total += c->step;
  r.open = total != 0;
  int below = 0;  // winding number counted from -z
  for (Crossing* c = begin; c + 1 != end; ++c) {
    below += c->step;
    const int above = below - total;  // counted from +z
    const int w = total == 0 ? std::abs(below) : std::min(std::abs(below), std::abs(above));
    const double len = c[1].z - c->z;
    if (w >= 1) r.once += len;
    if (w >= 2) {
      r.twice += len;
      if (marks) {
        for (const Crossing* k : {c, c + 1})  // cone triangles (past the marks) are not the skin's
          if (static_cast<std::size_t>(k->triangle) < marks->size())
            (*marks)[static_cast<std::size_t>(k->triangle)] = 1;
      }
    }
  }
  return r;
}

}  // namespace

SelfOverlap self_overlap(const track::Positions& positions, const track::Triangles& triangles,
                         const SelfOverlapOptions& options) {
  check_input(positions, triangles, options);
  SelfOverlap out;
  const ClosedMesh lids = close_borders(positions, triangles);
  const track::Positions& p = lids.closed ? lids.positions : positions;
  const track::Triangles& t = lids.closed ? lids.triangles : triangles;
  const ColumnGrid g = make_grid(p, t, options.resolution);
  out.cell = g.cell;
  out.columns = g.nx * g.ny;
  if (out.columns == 0) return out;
  std::vector<std::size_t> starts;
  std::vector<Crossing> crossings = column_crossings(p, t, g, options.grain, &starts);
  const auto nc = static_cast<std::size_t>(out.columns);
  std::vector<ColumnResult> columns(nc);
  // Marks are written by several columns' sweeps: one byte per triangle per task would cost
  // memory, so the marking pass runs serially (it is only asked for by the viewer and renders).
  std::vector<char> marks;
  if (options.mark_triangles) marks.assign(static_cast<std::size_t>(triangles.rows()), 0);
  const std::size_t column_grain = options.mark_triangles || options.grain == 0 ? 0 : options.grain;
  parallel_for(nc, column_grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t c = b; c < e; ++c)
      columns[c] = sweep_column(crossings.data() + starts[c], crossings.data() + starts[c + 1],
                                options.mark_triangles ? &marks : nullptr);
  });
  double once = 0, twice = 0;
  for (const ColumnResult& c : columns) {
    once += c.once;
    twice += c.twice;
    out.open_columns += c.open ? 1 : 0;
  }
  const double area = g.cell * g.cell;
  out.enclosed = once * area;
  out.overlap = twice * area;
  for (std::size_t f = 0; f < marks.size(); ++f)
    if (marks[f]) out.overlap_triangles.push_back(static_cast<int>(f));
  return out;
}

std::vector<int> new_overlap_triangles(const track::Positions& rest, const track::Positions& posed,
                                       const track::Triangles& triangles) {
  detail::check_same_vertex_count(rest, posed, "new_overlap_triangles");
  SelfOverlapOptions options;
  options.mark_triangles = true;
  const std::vector<int> now = self_overlap(posed, triangles, options).overlap_triangles;
  if (now.empty()) return now;
  const std::vector<int> before = self_overlap(rest, triangles, options).overlap_triangles;
  std::vector<int> out;
  std::set_difference(now.begin(), now.end(), before.begin(), before.end(), std::back_inserter(out));
  return out;
}

}  // namespace isokit::skinning
