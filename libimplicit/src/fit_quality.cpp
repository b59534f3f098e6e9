// SPDX-License-Identifier: MIT
#include "isokit/implicit/fit_quality.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "isokit/core/error.h"

namespace isokit::implicit {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double point_segment_distance(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
  const Vec3d ab = b - a;
  const double l2 = squared_norm(ab);
  const double t = l2 > 0 ? std::clamp(dot(p - a, ab) / l2, 0.0, 1.0) : 0.0;
  return norm(p - (a + ab * t));
}

/// p95 (nearest rank) and max of `d`; both 0 when empty.
void p95_max(std::vector<double> d, double& p95, double& max) {
  p95 = max = 0;
  if (d.empty()) return;
  std::sort(d.begin(), d.end());
  const std::size_t rank = static_cast<std::size_t>(std::ceil(0.95 * double(d.size())));
  p95 = d[std::max<std::size_t>(rank, 1) - 1];
  max = d.back();
}

/// The 0.5 iso-surface points of `field` where it crosses the edges of a `n`³ lattice over its
/// support box (local frame), by linear interpolation along the edge.
std::vector<Vec3d> iso_points(const Field& field, int n, double& spacing) {
  const Box3f box = field.support();
  spacing = 0;
  std::vector<Vec3d> out;
  if (box.empty()) return out;
  const Vec3f size = box.size();
  const Vec3f step{size.x / float(n - 1), size.y / float(n - 1), size.z / float(n - 1)};
  spacing = std::max({double(step.x), double(step.y), double(step.z)});
  std::vector<Vec3f> nodes;
  nodes.reserve(std::size_t(n) * n * n);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        nodes.push_back(
            {box.lo.x + step.x * float(i), box.lo.y + step.y * float(j), box.lo.z + step.z * float(k)});
  std::vector<FieldSample> f(nodes.size());
  field.eval_batch(nodes.data(), nodes.size(), f.data());
  auto at = [n](int i, int j, int k) { return std::size_t((k * n + j) * n + i); };
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const std::size_t a = at(i, j, k);
        const std::size_t next[3] = {i + 1 < n ? at(i + 1, j, k) : a, j + 1 < n ? at(i, j + 1, k) : a,
                                     k + 1 < n ? at(i, j, k + 1) : a};
        for (std::size_t b : next) {
          const double fa = double(f[a].value) - 0.5, fb = double(f[b].value) - 0.5;
          if (b == a || (fa > 0) == (fb > 0)) continue;
          const double t = fa / (fa - fb);
          const Vec3d pa{nodes[a].x, nodes[a].y, nodes[a].z}, pb{nodes[b].x, nodes[b].y, nodes[b].z};
          out.push_back(pa + (pb - pa) * t);
        }
      }
  return out;
}

/// Newton steps on `f − 0.5` from `p` (local frame), each at most `max_step` long.
/// \return the distance from `p` to where they end on the 0.5 level, or infinity.
double newton_distance(const Field& field, const Vec3d& p, int steps, double max_step) {
  Vec3d x = p;
  for (int s = 0; s <= steps; ++s) {
    const FieldSample fs = field.eval(Vec3f{float(x.x), float(x.y), float(x.z)});
    const double g2 = double(squared_norm(fs.gradient));
    const double e = double(fs.value) - 0.5;
    if (std::abs(e) < 1e-4) return norm(x - p);
    if (!(g2 > 0) || s == steps) break;
    Vec3d dx = Vec3d{fs.gradient.x, fs.gradient.y, fs.gradient.z} * (-e / g2);
    if (norm(dx) > max_step) dx = dx * (max_step / norm(dx));
    x = x + dx;
  }
  return kInf;
}

}  // namespace

double point_triangle_distance(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d ab = b - a, ac = c - a, n = cross(ab, ac);
  const double n2 = squared_norm(n);
  const double edges = std::min(
      {point_segment_distance(p, a, b), point_segment_distance(p, b, c), point_segment_distance(p, c, a)});
  if (!(n2 > 1e-24 * std::max(squared_norm(ab), squared_norm(ac)))) return edges;
  // Projection onto the plane; inside the triangle when its barycentric coordinates are >= 0.
  const Vec3d ap = p - a;
  const double h = dot(ap, n) / n2;
  const Vec3d q = ap - n * h;
  const double w1 = dot(cross(q, ac), n) / n2, w2 = dot(cross(ab, q), n) / n2;
  if (w1 >= 0 && w2 >= 0 && w1 + w2 <= 1) return std::abs(h) * std::sqrt(n2);
  return edges;
}

FitDistances fit_distances(const Field& field, const Rigid3d& local_to_world,
                           const std::vector<Vec3d>& vertices,
                           const std::vector<std::array<int, 3>>& triangles,
                           const std::function<bool(const Vec3d&)>& exclude, const FitDistanceOptions& o) {
  require(o.resolution >= 8 && o.resolution <= 256, "fit distances: resolution",
          "must be in [8, 256] (got " + std::to_string(o.resolution) + ")", "use the default 40");
  require(o.newton_steps >= 0 && o.newton_steps <= 100, "fit distances: newton_steps",
          "must be in [0, 100] (got " + std::to_string(o.newton_steps) + ")", "use the default 10");
  const int nv = static_cast<int>(vertices.size());
  for (const auto& t : triangles)
    for (int k : t)
      require(k >= 0 && k < nv, "fit distances: triangle",
              "indexes vertex " + std::to_string(k) + " of " + std::to_string(nv), "fix the indices");
  FitDistances out;
  out.vertices = nv;
  double spacing = 0;
  const std::vector<Vec3d> iso = iso_points(field, o.resolution, spacing);
  // Vertex -> surface (local frame: the frame is rigid, distances are the same).
  std::vector<double> to(vertices.size(), kInf);
  parallel_for(vertices.size(), 16, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      const Vec3d p = local_to_world.apply_inverse(vertices[v]);
      double d = newton_distance(field, p, o.newton_steps, 2 * spacing);
      for (const Vec3d& q : iso) d = std::min(d, norm(q - p));
      to[v] = d;
    }
  });
  p95_max(to, out.to_surface_p95, out.to_surface_max);
  // Surface -> nearest part triangle.
  std::vector<Vec3d> kept;
  for (const Vec3d& q : iso) {
    const Vec3d w = local_to_world.apply(q);
    if (!exclude || !exclude(w)) kept.push_back(w);
  }
  std::vector<double> from(kept.size(), kInf);
  parallel_for(kept.size(), 16, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      double d = kInf;
      for (const auto& t : triangles)
        d = std::min(d, point_triangle_distance(kept[i], vertices[t[0]], vertices[t[1]], vertices[t[2]]));
      from[i] = d;
    }
  });
  out.surface_points = static_cast<int>(kept.size());
  p95_max(from, out.from_surface_p95, out.from_surface_max);
  return out;
}

namespace {

double nearest_rank(std::vector<double>& v, double q) {
  if (v.empty()) return 0;
  const std::size_t rank = std::max<std::size_t>(std::size_t(std::ceil(q * double(v.size()))), 1);
  const std::size_t i = std::min(v.size(), rank) - 1;
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(i), v.end());
  return v[i];
}

/// Distance along the field from `x` to the level `iso` (Newton steps), infinite when the steps
/// do not reach it.
double distance_to_level(const Field& field, Vec3f x, float iso, const AgreementOptions& o) {
  const Vec3f x0 = x;
  for (int s = 0; s <= o.newton_steps; ++s) {
    const FieldSample f = field.eval(x);
    if (std::abs(f.value - iso) < o.tolerance) return double(norm(x - x0));
    const float g2 = dot(f.gradient, f.gradient);
    if (s == o.newton_steps || !(g2 > 1e-20f) || !std::isfinite(g2)) break;
    x = x + f.gradient * ((iso - f.value) / g2);
  }
  return std::numeric_limits<double>::infinity();
}

}  // namespace

std::vector<Vec3d> area_weighted_normals(const std::vector<Vec3d>& vertices,
                                         const std::vector<std::array<int, 3>>& triangles) {
  std::vector<Vec3d> n(vertices.size());
  const int nv = int(vertices.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const auto& tri = triangles[t];
    for (int k = 0; k < 3; ++k)
      require(tri[k] >= 0 && tri[k] < nv, "area_weighted_normals: triangle " + std::to_string(t),
              "indexes vertex " + std::to_string(tri[k]) + " of " + std::to_string(nv), "fix the indices");
    const Vec3d c = cross(vertices[tri[1]] - vertices[tri[0]], vertices[tri[2]] - vertices[tri[0]]);
    for (int k = 0; k < 3; ++k) n[static_cast<std::size_t>(tri[k])] += c;
  }
  return n;
}

FieldAgreement field_agreement(const Field& field, const Rigid3d& local_to_world,
                               const std::vector<Vec3d>& points, const std::vector<Vec3d>& normals, float iso,
                               const AgreementOptions& o) {
  require(points.size() == normals.size(), "field_agreement",
          std::to_string(points.size()) + " points but " + std::to_string(normals.size()) + " normals",
          "pass one normal per point");
  require(o.angle_limit_deg > 0 && o.angle_limit_deg <= 180, "AgreementOptions::angle_limit_deg",
          "must be in (0, 180]", "use the default 60");
  require(o.newton_steps >= 1 && o.newton_steps <= 100, "AgreementOptions::newton_steps",
          "must be in [1, 100]", "use the default 8");
  require(o.tolerance > 0, "AgreementOptions::tolerance", "must be > 0", "use the default 1e-4");
  std::vector<double> angles, distances;
  FieldAgreement out;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3d n = local_to_world.rotate_inverse(normals[i]);
    const double nl = norm(n);
    if (!(nl > 0)) continue;
    const Vec3d l = local_to_world.apply_inverse(points[i]);
    const Vec3f p{float(l.x), float(l.y), float(l.z)};
    const FieldSample f = field.eval(p);
    const Vec3d g{f.gradient.x, f.gradient.y, f.gradient.z};
    const double gl = norm(g);
    double angle = 180;
    if (gl > 1e-20 && std::isfinite(gl))
      angle = std::acos(std::clamp(-dot(g, n) / (gl * nl), -1.0, 1.0)) * 180.0 / kPi;
    angles.push_back(angle);
    if (angle > o.angle_limit_deg) ++out.over_limit;
    distances.push_back(distance_to_level(field, p, iso, o));
  }
  out.points = int(angles.size());
  if (angles.empty()) return out;
  out.angle_max = *std::max_element(angles.begin(), angles.end());
  out.distance_max = *std::max_element(distances.begin(), distances.end());
  out.angle_p95 = nearest_rank(angles, 0.95);
  out.angle_p50 = nearest_rank(angles, 0.5);
  out.distance_p95 = nearest_rank(distances, 0.95);
  out.distance_p50 = nearest_rank(distances, 0.5);
  return out;
}

}  // namespace isokit::implicit
