// SPDX-License-Identifier: MIT
#include "isokit/skinning/fit_quality.h"

#include <algorithm>
#include <array>

#include "isokit/core/mesh_quality.h"
#include "isokit/core/parallel.h"
#include "isokit/implicit/program_field.h"
#include "isokit/skinning/mesh_closure.h"

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

namespace {

std::vector<Vec3d> rest_points(const Rig& r) {
  std::vector<Vec3d> p(static_cast<std::size_t>(r.rest.rows()));
  for (Eigen::Index v = 0; v < r.rest.rows(); ++v)
    p[static_cast<std::size_t>(v)] = {r.rest(v, 0), r.rest(v, 1), r.rest(v, 2)};
  return p;
}

std::vector<std::array<int, 3>> triangle_list(const Rig& r) {
  std::vector<std::array<int, 3>> t(static_cast<std::size_t>(r.triangles.rows()));
  for (Eigen::Index f = 0; f < r.triangles.rows(); ++f)
    t[static_cast<std::size_t>(f)] = {r.triangles(f, 0), r.triangles(f, 1), r.triangles(f, 2)};
  return t;
}

}  // namespace

std::vector<std::uint8_t> open_panel_vertices(const Rig& rig, int* panels) {
  const MeshClosure closure = mesh_closure(rig.triangles, rig.rest.rows());
  const std::vector<Vec3d> p = rest_points(rig);
  std::vector<Vec3d> vector_area(closure.components.size());
  std::vector<double> area(closure.components.size(), 0);
  for (Eigen::Index f = 0; f < rig.triangles.rows(); ++f) {
    const std::size_t c = static_cast<std::size_t>(closure.component[static_cast<std::size_t>(f)]);
    const Vec3d n = cross(p[rig.triangles(f, 1)] - p[rig.triangles(f, 0)],
                          p[rig.triangles(f, 2)] - p[rig.triangles(f, 0)]);
    vector_area[c] += n * 0.5;
    area[c] += 0.5 * norm(n);
  }
  std::vector<char> panel(closure.components.size(), 0);
  int count = 0;
  for (std::size_t c = 0; c < panel.size(); ++c) {
    panel[c] = closure.components[c].border_edges > 0 && norm(vector_area[c]) >= 0.3 * area[c] ? 1 : 0;
    count += panel[c];
  }
  if (panels) *panels = count;
  std::vector<std::uint8_t> out(p.size(), 0);
  for (Eigen::Index f = 0; f < rig.triangles.rows(); ++f)
    if (panel[static_cast<std::size_t>(closure.component[static_cast<std::size_t>(f)])])
      for (int k = 0; k < 3; ++k) out[static_cast<std::size_t>(rig.triangles(f, k))] = 1;
  return out;
}

std::vector<std::uint8_t> hidden_vertices(const Rig& rig) {
  const MeshClosure closure = mesh_closure(rig.triangles, rig.rest.rows());
  const std::vector<Vec3d> p = rest_points(rig);
  const std::size_t nc = closure.components.size();
  std::vector<std::uint8_t> out(p.size(), 0);
  if (nc < 2) return out;
  std::vector<int> component(p.size(), -1);
  std::vector<Box3d> box(nc);
  for (Eigen::Index f = 0; f < rig.triangles.rows(); ++f) {
    const int c = closure.component[static_cast<std::size_t>(f)];
    for (int k = 0; k < 3; ++k) {
      component[static_cast<std::size_t>(rig.triangles(f, k))] = c;
      box[static_cast<std::size_t>(c)].extend(p[static_cast<std::size_t>(rig.triangles(f, k))]);
    }
  }
  parallel_for(p.size(), 64, [&](std::size_t begin, std::size_t end) {
    std::vector<double> winding(nc);
    for (std::size_t v = begin; v < end; ++v) {
      std::fill(winding.begin(), winding.end(), 0.0);
      for (Eigen::Index f = 0; f < rig.triangles.rows(); ++f) {
        const int c = closure.component[static_cast<std::size_t>(f)];
        if (c == component[v] || !box[static_cast<std::size_t>(c)].contains(p[v])) continue;
        // Solid angle of the triangle seen from the vertex (Van Oosterom and Strackee 1983).
        const Vec3d a = p[rig.triangles(f, 0)] - p[v], b = p[rig.triangles(f, 1)] - p[v],
                    d = p[rig.triangles(f, 2)] - p[v];
        const double la = norm(a), lb = norm(b), ld = norm(d);
        const double num = dot(a, cross(b, d));
        const double den = la * lb * ld + dot(a, b) * ld + dot(b, d) * la + dot(d, a) * lb;
        winding[static_cast<std::size_t>(c)] += 2 * std::atan2(num, den) / (4 * kPi);
      }
      for (double w : winding)
        if (w > 0.5) out[v] = 1;
    }
  });
  return out;
}

RestAgreement rest_agreement(const FittedRig& fitted, const SkinField& field) {
  const Rig& r = fitted.rig();
  RestAgreement out;
  const std::vector<std::uint8_t> panel = open_panel_vertices(r, &out.open_panels);
  const std::vector<Vec3d> p = rest_points(r);
  const std::vector<std::array<int, 3>> tris = triangle_list(r);
  const std::vector<Vec3d> normals = implicit::area_weighted_normals(p, tris);
  const std::vector<std::uint8_t> hidden = hidden_vertices(r);
  std::vector<Vec3d> kept, kept_normals, visible, visible_normals;
  for (std::size_t v = 0; v < p.size(); ++v) {
    if (panel[v]) {
      ++out.panel_vertices;
      continue;
    }
    kept.push_back(p[v]);
    kept_normals.push_back(normals[v]);
    if (hidden[v]) {
      ++out.hidden_vertices;
      continue;
    }
    visible.push_back(p[v]);
    visible_normals.push_back(normals[v]);
  }
  const implicit::ProgramField composed(field.shared_program(), field.rest_pose());
  out.composed = implicit::field_agreement(composed, Rigid3d{}, kept, kept_normals);
  out.visible = implicit::field_agreement(composed, Rigid3d{}, visible, visible_normals);
  for (const auto& t : tris) {
    if (panel[static_cast<std::size_t>(t[0])]) continue;
    ++out.triangles;
    const Vec3d c = (p[t[0]] + p[t[1]] + p[t[2]]) * (1.0 / 3.0);
    const Vec3d n = cross(p[t[1]] - p[t[0]], p[t[2]] - p[t[0]]);
    const implicit::FieldSample s = composed.eval({float(c.x), float(c.y), float(c.z)});
    if (n.x * s.gradient.x + n.y * s.gradient.y + n.z * s.gradient.z > 0) ++out.inverted_triangles;
  }
  for (const PrimitiveCoverage& c : primitive_coverage(fitted)) out.unrelated_inside += c.unrelated;
  return out;
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
  const std::vector<Vec3d> all_points = rest_points(r);
  const std::vector<Vec3d> all_normals = implicit::area_weighted_normals(all_points, triangle_list(r));
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
    std::vector<Vec3d> own, own_normals;
    for (std::size_t v = 0; v < all_points.size(); ++v)
      if (fitted.partition()[v] == b.joint)
        own.push_back(all_points[v]), own_normals.push_back(all_normals[v]);
    q.agreement = implicit::field_agreement(*b.fit.field(), b.fit.local_to_world, own, own_normals);
    out.parts.push_back(q);
  }
  return out;
}

}  // namespace isokit::skinning
