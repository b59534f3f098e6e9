// SPDX-License-Identifier: MIT
#include "fit_caps.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "isokit/core/math.h"

namespace isokit::implicit::detail {

namespace {

/// Appends the simple cycles of the closed walk `walk` to `loops` (three vertices or more):
/// where a walk visits a vertex twice (two holes touching at a vertex), each stretch between
/// the visits is a loop of its own.
void split_at_repeats(const std::vector<int>& walk, std::vector<std::vector<int>>& loops) {
  std::map<int, std::size_t> seen;
  std::vector<int> rest;
  for (int v : walk) {
    auto it = seen.find(v);
    if (it == seen.end()) {
      seen[v] = rest.size();
      rest.push_back(v);
      continue;
    }
    std::vector<int> loop(rest.begin() + std::ptrdiff_t(it->second), rest.end());
    for (std::size_t k = 1; k < loop.size(); ++k) seen.erase(loop[k]);
    rest.resize(it->second + 1);
    if (loop.size() >= 3) loops.push_back(std::move(loop));
  }
  if (rest.size() >= 3) loops.push_back(std::move(rest));
}

using Edge = std::pair<int, int>;
Edge key(int a, int b) {
  return {std::min(a, b), std::max(a, b)};
}

/// The triangle-fan walk around `v`: from the border edge `u → v` of triangle `t`, turn about
/// `v` through the triangles that share an edge at `v` until an edge `v → x` used by one
/// triangle: that border edge follows `u → v` on the same hole, also where a vertex sits on
/// several holes (a band one triangle wide). \return x, or -1 when the fan is not a simple one.
int next_on_border(const std::vector<std::array<int, 3>>& triangles,
                   const std::map<Edge, std::vector<int>>& uses, int t, int v, int u) {
  int from = u;
  for (std::size_t guard = 0; guard <= triangles.size(); ++guard) {
    const auto& tri = triangles[static_cast<std::size_t>(t)];
    int w = -1;
    for (int k = 0; k < 3; ++k)
      if (tri[k] != v && tri[k] != from) w = tri[k];
    if (w < 0) return -1;
    const std::vector<int>& across = uses.at(key(v, w));
    if (across.size() == 1) return w;
    if (across.size() != 2) return -1;
    t = across[0] == t ? across[1] : across[0];
    from = w;
  }
  return -1;
}

}  // namespace

std::vector<std::vector<int>> boundary_loops(const std::vector<std::array<int, 3>>& triangles, int vertices) {
  std::map<Edge, std::vector<int>> uses;  // undirected edge -> its triangles
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)
      uses[key(triangles[t][k], triangles[t][(k + 1) % 3])].push_back(static_cast<int>(t));
  // Directed border edges a -> b (as their triangle runs them), with that triangle.
  std::map<Edge, int> border;
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = triangles[t][k], b = triangles[t][(k + 1) % 3];
      if (a != b && uses[key(a, b)].size() == 1) border[{a, b}] = static_cast<int>(t);
    }
  std::vector<std::vector<int>> loops;
  while (!border.empty()) {
    Edge edge = border.begin()->first;
    int t = border.begin()->second;
    border.erase(border.begin());
    std::vector<int> loop{edge.first};
    bool closed = false;
    for (std::size_t guard = 0; guard <= static_cast<std::size_t>(vertices); ++guard) {
      const int v = edge.second;
      if (v == loop.front()) {
        closed = true;
        break;
      }
      loop.push_back(v);
      const int x = next_on_border(triangles, uses, t, v, edge.first);
      auto it = x < 0 ? border.end() : border.find({v, x});
      if (it == border.end()) break;
      edge = it->first;
      t = it->second;
      border.erase(it);
    }
    if (closed) split_at_repeats(loop, loops);
  }
  return loops;
}

std::vector<HrbfSample> loop_cap(const std::vector<Vec3d>& v, const std::vector<int>& loop, double height,
                                 double spacing, const Vec3d& axis) {
  const std::size_t n = loop.size();
  // Centroid of the loop's edges (length-weighted), Newell normal and perimeter.
  Vec3d c{}, newell{};
  double perimeter = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d& a = v[static_cast<std::size_t>(loop[i])];
    const Vec3d& b = v[static_cast<std::size_t>(loop[(i + 1) % n])];
    const double l = norm(b - a);
    c += (a + b) * (0.5 * l);
    perimeter += l;
    newell += cross(a, b);
  }
  if (!(perimeter > 0)) return {};
  c = c / perimeter;
  const double area = 0.5 * norm(newell);
  if (!(area > 0.05 * perimeter * perimeter / (4 * kPi))) return {};
  const Vec3d out = newell * (-1.0 / norm(newell));
  // The rim in the loop's plane, relative to the centre, and its mean radius.
  std::vector<Vec3d> rim(n);
  double radius = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d d = v[static_cast<std::size_t>(loop[i])] - c;
    rim[i] = d - out * dot(d, out);
    radius += norm(rim[i]) / double(n);
  }
  // Arc-length positions along the rim, to place ring points evenly.
  std::vector<double> arc(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) arc[i + 1] = arc[i] + norm(rim[(i + 1) % n] - rim[i]);
  auto rim_at = [&](double s) {
    const std::size_t i = std::min<std::size_t>(
        std::size_t(std::upper_bound(arc.begin(), arc.end(), s) - arc.begin()) - 1, n - 1);
    const double seg = arc[i + 1] - arc[i], t = seg > 0 ? (s - arc[i]) / seg : 0;
    return rim[i] * (1 - t) + rim[(i + 1) % n] * t;
  };
  const double h = height * radius * std::abs(dot(out, axis));
  std::vector<HrbfSample> cap{{c + out * h, out}};
  const int rings = std::max(1, int(std::lround(radius / std::max(spacing, 1e-12 * radius))));
  for (int k = 1; k <= rings; ++k) {
    const double t = double(k) / double(rings + 1);
    const int m = std::max(3, int(std::lround(2 * kPi * t * radius / std::max(spacing, 1e-12 * radius))));
    for (int i = 0; i < m; ++i) {
      const Vec3d r = rim_at(arc[n] * (double(i) + 0.5 * (k % 2)) / double(m));
      const double rl = norm(r);
      const Vec3d radial = rl > 0 ? r / rl : Vec3d{};
      // Dome z(ρ) = h (1 − ρ² / R²): normal ∝ out + 2 h ρ / R² radial.
      Vec3d nrm = out + radial * (2 * h * t * rl / std::max(radius * radius, 1e-300));
      cap.push_back({c + r * t + out * (h * (1 - t * t)), nrm / norm(nrm)});
    }
  }
  return cap;
}

void close_with_fans(std::vector<Vec3d>& vertices, std::vector<std::array<int, 3>>& triangles) {
  for (const std::vector<int>& loop : boundary_loops(triangles, int(vertices.size()))) {
    Vec3d c{};
    for (int v : loop) c += vertices[static_cast<std::size_t>(v)];
    const int centre = int(vertices.size());
    vertices.push_back(c / double(loop.size()));
    for (std::size_t i = 0; i < loop.size(); ++i)
      triangles.push_back({loop[(i + 1) % loop.size()], loop[i], centre});
  }
}

}  // namespace isokit::implicit::detail
