// SPDX-License-Identifier: MIT
#include "isokit/skinning/fit_quality.h"

#include <algorithm>
#include <array>

#include "isokit/core/mesh_quality.h"

namespace isokit::skinning {

namespace {

/// The mesh a joint's fit sees: its triangles (a triangle belongs to the joint of at least two
/// of its vertices, else to its first vertex's) over their locally numbered rest vertices.
void part_triangles(const Rig& r, const std::vector<int>& partition, int j, std::vector<Vec3d>& vertices,
                    std::vector<std::array<int, 3>>& triangles) {
  std::vector<int> local(static_cast<std::size_t>(r.rest.rows()), -1);
  for (Eigen::Index f = 0; f < r.triangles.rows(); ++f) {
    const int a = partition[r.triangles(f, 0)], b = partition[r.triangles(f, 1)],
              c = partition[r.triangles(f, 2)];
    if (((b == c) ? b : a) != j) continue;
    std::array<int, 3> t{};
    for (int k = 0; k < 3; ++k) {
      const int v = r.triangles(f, k);
      if (local[v] < 0) {
        local[v] = static_cast<int>(vertices.size());
        vertices.push_back({r.rest(v, 0), r.rest(v, 1), r.rest(v, 2)});
      }
      t[static_cast<std::size_t>(k)] = local[v];
    }
    triangles.push_back(t);
  }
}

bool inside(const BonePart& b, const Vec3d& world) {
  const Vec3d q = b.fit.local_to_world.apply_inverse(world);
  return b.fit.field()->eval(Vec3f{float(q.x), float(q.y), float(q.z)}).value > 0.5f;
}

double worst(const FitQuality& q, double implicit::FitDistances::*member) {
  double w = 0;
  for (const PartQuality& p : q.parts) w = std::max(w, p.distances.*member);
  return q.diagonal > 0 ? w / q.diagonal : w;
}

}  // namespace

double FitQuality::worst_to_surface_p95() const {
  return worst(*this, &implicit::FitDistances::to_surface_p95);
}
double FitQuality::worst_to_surface_max() const {
  return worst(*this, &implicit::FitDistances::to_surface_max);
}
double FitQuality::worst_from_surface_p95() const {
  return worst(*this, &implicit::FitDistances::from_surface_p95);
}
double FitQuality::worst_from_surface_max() const {
  return worst(*this, &implicit::FitDistances::from_surface_max);
}
int FitQuality::unrelated_inside() const {
  int n = 0;
  for (const PartQuality& p : parts) n += p.coverage.unrelated;
  return n;
}

FitQuality fit_quality(const FittedRig& fitted, const implicit::FitDistanceOptions& options) {
  const Rig& r = fitted.rig();
  const std::vector<BonePart>& bones = fitted.bones();
  FitQuality out;
  out.diagonal = bbox_diagonal<double>(static_cast<std::size_t>(r.rest.rows()), [&](std::size_t v) {
    const Eigen::Index i = static_cast<Eigen::Index>(v);
    return Vec3d{r.rest(i, 0), r.rest(i, 1), r.rest(i, 2)};
  });
  for (int j : fitted.partition())
    if (!bones[static_cast<std::size_t>(j)].fitted) ++out.vertices_without_field;
  const std::vector<PrimitiveCoverage> coverage = primitive_coverage(fitted);
  std::size_t k = 0;
  for (const BonePart& b : bones) {
    if (!b.fitted) continue;
    std::vector<const BonePart*> related;
    for (const BonePart& o : bones)
      if (o.fitted && o.joint != b.joint &&
          (fitted.primitive_parent(b.joint) == o.joint || fitted.primitive_parent(o.joint) == b.joint))
        related.push_back(&o);
    PartQuality q;
    q.joint = b.joint;
    q.r = b.fit.r;
    q.coverage = coverage[k++];
    std::vector<Vec3d> vertices;
    std::vector<std::array<int, 3>> triangles;
    part_triangles(r, fitted.partition(), b.joint, vertices, triangles);
    q.distances = implicit::fit_distances(
        *b.fit.field(), b.fit.local_to_world, vertices, triangles,
        [&](const Vec3d& w) {
          return std::any_of(related.begin(), related.end(),
                             [&](const BonePart* o) { return inside(*o, w); });
        },
        options);
    out.parts.push_back(q);
  }
  return out;
}

}  // namespace isokit::skinning
