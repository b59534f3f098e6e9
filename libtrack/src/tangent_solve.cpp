// SPDX-License-Identifier: MIT
// Preconditioned conjugate gradient on the tangential ARAP system of the 2014 tracker (§5.2:
// "Higher performance may be achieved using the conjugate-gradient method").
#include <algorithm>
#include <cmath>

#include "tangent_solve.h"

namespace isokit::track::detail {

namespace {

// The unknowns are 3D displacements filtered per vertex by S_i = I - n_i n_iᵀ (tangent plane) or
// S_i = I (contact or free vertex): CG on S K S stays in the filtered subspace when every vector it builds is
// filtered (Baraff & Witkin's filtered PCG), so no tangent frames are needed.
inline Vec3f filter(const TangentProblem& p, std::size_t i, const Vec3f& v) {
  if (p.free3d[i] || (p.free_vertices && p.free_vertices[i])) return v;
  const Vec3f n = p.normals[i];
  return v - n * dot(v, n);
}

}  // namespace

int solve_tangential_cg(const TangentProblem& p, const std::vector<int>& unknowns, std::vector<int>& local,
                        std::vector<Vec3f>& d) {
  const std::size_t m = unknowns.size();
  d.assign(m, Vec3f{});
  if (m == 0) return 0;
  const int* off = p.adj->offsets.data();
  const int* nb = p.adj->neighbors.data();
  for (std::size_t a = 0; a < m; ++a) local[std::size_t(unknowns[a])] = int(a);
  std::vector<float> diag(m);
  std::vector<Vec3f> r(m), z(m), dir(m), q(m);
  // Right-hand side: the filtered ARAP residual Σ wij ((pj - pi) + tij) of every unknown, the
  // other vertices held at their positions; diagonal Σ wij / si (si = mask × damping, so that with
  // fixed neighbours the solution is si times the Jacobi step).
  for (std::size_t a = 0; a < m; ++a) {
    const std::size_t i = std::size_t(unknowns[a]);
    const Vec3f pi = p.positions[i];
    Vec3f acc{};
    for (int k = off[i]; k < off[i + 1]; ++k)
      acc += ((p.positions[nb[k]] - pi) + p.targets[k]) * p.weights[k];
    diag[a] = p.weight_sums[i] / p.scale[i];
    if (p.anchor_k && p.anchor_k[i] > 0.f) {
      const float pull = p.weight_sums[i] * p.anchor_k[i] / (1.f - p.anchor_k[i]);
      diag[a] += pull;
      acc += (p.anchors[i] - pi) * pull;
    }
    r[a] = filter(p, i, acc);
  }
  auto converged = [&] {
    float mx = 0.f;
    for (std::size_t a = 0; a < m; ++a) mx = std::max(mx, squared_norm(r[a]) / (diag[a] * diag[a]));
    return mx <= p.tolerance * p.tolerance;
  };
  int it = 0;
  if (!converged()) {
    double rz = 0;
    for (std::size_t a = 0; a < m; ++a) {
      z[a] = r[a] / diag[a];
      dir[a] = z[a];
      rz += double(dot(r[a], z[a]));
    }
    while (it < p.max_iterations) {
      ++it;
      double pq = 0;
      for (std::size_t a = 0; a < m; ++a) {
        const std::size_t i = std::size_t(unknowns[a]);
        Vec3f acc = dir[a] * diag[a];
        for (int k = off[i]; k < off[i + 1]; ++k) {
          const int b = local[std::size_t(nb[k])];
          if (b >= 0) acc = acc - dir[std::size_t(b)] * p.weights[k];
        }
        q[a] = filter(p, i, acc);
        pq += double(dot(dir[a], q[a]));
      }
      if (!(pq > 0.0)) break;  // no descent left (round-off): keep the current solution
      const float alpha = float(rz / pq);
      for (std::size_t a = 0; a < m; ++a) {
        d[a] += dir[a] * alpha;
        r[a] = r[a] - q[a] * alpha;
      }
      if (converged()) break;
      double rz_next = 0;
      for (std::size_t a = 0; a < m; ++a) {
        z[a] = r[a] / diag[a];
        rz_next += double(dot(r[a], z[a]));
      }
      const float beta = float(rz_next / rz);
      rz = rz_next;
      for (std::size_t a = 0; a < m; ++a) dir[a] = z[a] + dir[a] * beta;
    }
  }
  for (int i : unknowns) local[std::size_t(i)] = -1;
  return it;
}

}  // namespace isokit::track::detail
