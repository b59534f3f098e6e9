// SPDX-License-Identifier: MIT
// The surface report (`inspect_surface`): edge manifoldness, components, angles, volume. Apart
// from the procedural rigs so that the rig loader needs no procedural geometry (or CGAL's Mesh_3).
#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>
#include <vector>

#include "isokit/core/error.h"
#include "isokit/core/math.h"
#include "isokit/skinning/metrics.h"
#include "isokit/skinning/procedural.h"

namespace isokit::skinning {

namespace {
struct UnionFind {
  std::vector<int> p;
  explicit UnionFind(std::size_t n) : p(n) { std::iota(p.begin(), p.end(), 0); }
  int find(int x) {
    while (p[static_cast<std::size_t>(x)] != x)
      x = p[static_cast<std::size_t>(x)] = p[static_cast<std::size_t>(p[static_cast<std::size_t>(x)])];
    return x;
  }
  void unite(int a, int b) { p[static_cast<std::size_t>(find(a))] = find(b); }
};
}  // namespace

SurfaceReport inspect_surface(const track::Positions& v, const track::Triangles& t,
                              bool check_self_intersections) {
  const int nv = static_cast<int>(v.rows()), nf = static_cast<int>(t.rows());
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k)
      require(t(f, k) >= 0 && t(f, k) < nv, "surface report: triangle " + std::to_string(f),
              "index out of range", "indices must lie in [0, " + std::to_string(nv) + ")");
  SurfaceReport r;
  // Directed edges sorted by (min, max): groups are the undirected edges.
  struct E {
    int a, b, f, k;
    bool fwd;
  };
  std::vector<E> e;
  e.reserve(static_cast<std::size_t>(std::max(nf, 0)) * 3);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = t(f, k), b = t(f, (k + 1) % 3);
      e.push_back({std::min(a, b), std::max(a, b), f, k, a < b});
    }
  std::sort(e.begin(), e.end(), [](const E& x, const E& y) {
    return std::tie(x.a, x.b, x.f, x.k) < std::tie(y.a, y.b, y.f, y.k);
  });
  UnionFind faces(static_cast<std::size_t>(nf));
  UnionFind corners(static_cast<std::size_t>(nf) * 3);  // corner 3f+k = vertex t(f,k) in face f
  auto corner_of = [&](int f, int vert) {
    for (int k = 0; k < 3; ++k)
      if (t(f, k) == vert) return 3 * f + k;
    return -1;
  };
  int edges = 0;
  for (std::size_t i = 0; i < e.size();) {
    std::size_t j = i;
    while (j < e.size() && e[j].a == e[i].a && e[j].b == e[i].b) ++j;
    ++edges;
    const std::size_t n = j - i;
    if (n == 1) ++r.boundary_edges;
    if (n > 2) ++r.nonmanifold_edges;
    if (n == 2) {
      if (e[i].fwd == e[i + 1].fwd) ++r.inconsistent_edges;
      faces.unite(e[i].f, e[i + 1].f);
      corners.unite(corner_of(e[i].f, e[i].a), corner_of(e[i + 1].f, e[i].a));
      corners.unite(corner_of(e[i].f, e[i].b), corner_of(e[i + 1].f, e[i].b));
    }
    i = j;
  }
  std::vector<int> fan_root(static_cast<std::size_t>(nv), -1);
  std::vector<char> bad(static_cast<std::size_t>(nv), 0);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int vert = t(f, k), root = corners.find(3 * f + k);
      int& fr = fan_root[static_cast<std::size_t>(vert)];
      if (fr < 0)
        fr = root;
      else if (fr != root)
        bad[static_cast<std::size_t>(vert)] = 1;
    }
  r.nonmanifold_vertices = static_cast<int>(std::count(bad.begin(), bad.end(), 1));
  for (int f = 0; f < nf; ++f)
    if (faces.find(f) == f) ++r.components;
  r.euler = nv - edges + nf;
  r.min_angle_deg = nf > 0 ? 180.0 : 0.0;
  int below = 0;
  for (int f = 0; f < nf; ++f) {
    const Eigen::Vector3d p[3] = {v.row(t(f, 0)).cast<double>().transpose(),
                                  v.row(t(f, 1)).cast<double>().transpose(),
                                  v.row(t(f, 2)).cast<double>().transpose()};
    r.volume += p[0].dot(p[1].cross(p[2])) / 6.0;
    double m = 180.0;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d a = p[(k + 1) % 3] - p[k], b = p[(k + 2) % 3] - p[k];
      m = std::min(m, std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / kPi);
    }
    r.min_angle_deg = std::min(r.min_angle_deg, m);
    if (m < 20.0) ++below;
  }
  r.fraction_below_20deg = nf > 0 ? static_cast<double>(below) / nf : 0.0;
  if (check_self_intersections) r.self_intersects = count_self_intersections(v, t) > 0;
  return r;
}

}  // namespace isokit::skinning
