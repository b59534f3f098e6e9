// SPDX-License-Identifier: MIT
// A plain triangle mesh for the skinning tests that build their own shapes (metrics, renders).
#pragma once

#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <utility>
#include <vector>

#include "isokit/core/math.h"
#include "isokit/track/mesh.h"

namespace isokit::skinning::testing {

using isokit::kPi;

struct Mesh {
  track::Positions v;
  track::Triangles f;
};

inline Mesh from_lists(const std::vector<Eigen::Vector3d>& v, const std::vector<std::array<int, 3>>& f) {
  Mesh m;
  m.v.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i)
    m.v.row(static_cast<Eigen::Index>(i)) = v[i].cast<float>().transpose();
  m.f.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (std::size_t i = 0; i < f.size(); ++i)
    m.f.row(static_cast<Eigen::Index>(i)) << f[i][0], f[i][1], f[i][2];
  return m;
}

/// Concatenation (indices of `b` shifted).
inline Mesh join(const Mesh& a, const Mesh& b) {
  Mesh m;
  m.v.resize(a.v.rows() + b.v.rows(), 3);
  m.v << a.v, b.v;
  m.f.resize(a.f.rows() + b.f.rows(), 3);
  m.f << a.f, (b.f.array() + static_cast<int>(a.v.rows())).matrix();
  return m;
}

inline Eigen::Vector3d vtx(const Mesh& m, Eigen::Index i) {
  return m.v.row(i).cast<double>().transpose();
}

/// Turns every triangle so that its normal points away from `inside(centroid)`.
inline void orient_outward(Mesh& m, const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& inside) {
  for (Eigen::Index f = 0; f < m.f.rows(); ++f) {
    const Eigen::Vector3d a = vtx(m, m.f(f, 0)), b = vtx(m, m.f(f, 1)), c = vtx(m, m.f(f, 2));
    const Eigen::Vector3d centroid = (a + b + c) / 3;
    if ((b - a).cross(c - a).dot(centroid - inside(centroid)) < 0) std::swap(m.f(f, 1), m.f(f, 2));
  }
}

/// Icosphere: an icosahedron subdivided `level` times, projected on the sphere.
inline Mesh icosphere(int level, double radius = 1, const Eigen::Vector3d& centre = Eigen::Vector3d::Zero()) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                    {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                    {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& p : v) p.normalize();
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[static_cast<std::size_t>(a)] + v[static_cast<std::size_t>(b)]).normalized());
      const int id = static_cast<int>(v.size()) - 1;
      mid.emplace(key, id);
      return id;
    };
    std::vector<std::array<int, 3>> next;
    for (const auto& tri : f) {
      const int ab = midpoint(tri[0], tri[1]), bc = midpoint(tri[1], tri[2]), ca = midpoint(tri[2], tri[0]);
      next.push_back({tri[0], ab, ca});
      next.push_back({tri[1], bc, ab});
      next.push_back({tri[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    f = std::move(next);
  }
  for (auto& p : v) p = centre + radius * p;
  Mesh m = from_lists(v, f);
  orient_outward(m, [&](const Eigen::Vector3d&) { return centre; });
  return m;
}

}  // namespace isokit::skinning::testing
