// SPDX-License-Identifier: MIT
// CGAL Mesh_3 surface meshing of an implicit shape (the procedural humanoid's polygonizer).
// The only translation unit that includes the Mesh_3 headers (they are slow to compile).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Random.h>
#include <CGAL/make_mesh_3.h>
#include <CGAL/refine_mesh_3.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <utility>

#include "isokit/core/error.h"
#include "rig/polygonize.h"

namespace isokit::skinning::detail {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using FT = K::FT;
using Point = K::Point_3;
using Function = std::function<FT(const Point&)>;
using Domain = CGAL::Labeled_mesh_domain_3<K>;
using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr>;
using Criteria = CGAL::Mesh_criteria_3<Tr>;
using FacetCriteria = Criteria::Facet_criteria;
using CellCriteria = Criteria::Cell_criteria;

Eigen::Vector3d to_eigen(const Point& p) {
  return {p.x(), p.y(), p.z()};
}

/// Mesh_3 sizing field (MeshDomainField_3): `scale * min(global, local_size(p))`.
struct SizeField {
  using FT = K::FT;
  using Point_3 = K::Point_3;
  using Index = Domain::Index;
  const ImplicitShape* shape;
  double global;
  double scale;
  FT operator()(const Point_3& p, const int, const Index&) const {
    return scale * std::min(global, shape->local_size(to_eigen(p)));
  }
};

/// Orients every connected component consistently (breadth-first over shared edges), then
/// outward (positive enclosed volume). Throws if an edge is not shared by exactly two triangles
/// or a component cannot be oriented.
void orient_outward(const track::Positions& v, track::Triangles& t) {
  const int nf = static_cast<int>(t.rows());
  std::map<std::pair<int, int>, std::vector<int>> edge_faces;
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = t(f, k), b = t(f, (k + 1) % 3);
      edge_faces[{std::min(a, b), std::max(a, b)}].push_back(f);
    }
  for (const auto& [e, fs] : edge_faces)
    require(fs.size() == 2, "procedural polygonizer", "produced a non-manifold or open edge",
            "report this shape/size; try another vertex count");
  auto has_directed = [&](int f, int a, int b) {
    for (int k = 0; k < 3; ++k)
      if (t(f, k) == a && t(f, (k + 1) % 3) == b) return true;
    return false;
  };
  std::vector<int> comp(static_cast<std::size_t>(nf), -1);
  int ncomp = 0;
  std::vector<int> queue;
  for (int seed = 0; seed < nf; ++seed) {
    if (comp[seed] >= 0) continue;
    comp[seed] = ncomp;
    queue.assign(1, seed);
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const int f = queue[q];
      for (int k = 0; k < 3; ++k) {
        const int a = t(f, k), b = t(f, (k + 1) % 3);
        const auto& fs = edge_faces[{std::min(a, b), std::max(a, b)}];
        const int g = fs[0] == f ? fs[1] : fs[0];
        if (comp[g] >= 0) {
          require(!has_directed(g, a, b), "procedural polygonizer", "produced a non-orientable surface",
                  "report this shape/size");
          continue;
        }
        if (has_directed(g, a, b)) std::swap(t(g, 1), t(g, 2));
        comp[g] = ncomp;
        queue.push_back(g);
      }
    }
    ++ncomp;
  }
  std::vector<double> volume(static_cast<std::size_t>(ncomp), 0.0);
  for (int f = 0; f < nf; ++f) {
    const Eigen::Vector3d a = v.row(t(f, 0)).cast<double>(), b = v.row(t(f, 1)).cast<double>(),
                          c = v.row(t(f, 2)).cast<double>();
    volume[comp[f]] += a.dot(b.cross(c)) / 6.0;
  }
  for (int f = 0; f < nf; ++f)
    if (volume[comp[f]] < 0) std::swap(t(f, 1), t(f, 2));
}

}  // namespace

TriangleMesh mesh_implicit_surface(const ImplicitShape& shape, double size, double distance_ratio) {
  require(size > 0 && std::isfinite(size), "procedural polygonizer: facet size", "must be > 0",
          "pass a positive size");
  const Function f = [&shape](const Point& p) { return shape.sdf(to_eigen(p)); };
  CGAL::Random rng(0);
  const K::Sphere_3 sphere(Point(shape.center.x(), shape.center.y(), shape.center.z()),
                           shape.radius * shape.radius);
  namespace params = CGAL::parameters;
  Domain domain = Domain::create_implicit_mesh_domain(f, sphere, params::relative_error_bound = 1e-5,
                                                      params::p_rng = &rng);

  C3t3 c3t3;
  Tr& tr = c3t3.triangulation();
  // Seeds: the surface crossing of each inside -> outside segment.
  auto intersect = domain.construct_intersection_object();
  for (const auto& [in, out] : shape.seeds) {
    if (!(shape.sdf(in) < 0 && shape.sdf(out) > 0)) continue;
    const K::Segment_3 seg(Point(in.x(), in.y(), in.z()), Point(out.x(), out.y(), out.z()));
    const auto hit = intersect(seg);
    const Point p = std::get<0>(hit);
    const Tr::Vertex_handle vh = tr.insert(Tr::Point(p, 0));
    if (vh == Tr::Vertex_handle()) continue;
    c3t3.set_dimension(vh, 2);
    c3t3.set_index(vh, std::get<1>(hit));
  }
  const SizeField radius{&shape, size, 1.0};
  const SizeField distance{&shape, size, distance_ratio};
  const Criteria criteria(FacetCriteria(30.0, radius, distance, CGAL::FACET_VERTICES_ON_SURFACE),
                          CellCriteria(0.0, 0.0));
  if (tr.dimension() != 3) CGAL::Mesh_3::internal::init_c3t3(c3t3, domain, criteria, 20);
  CGAL::refine_mesh_3(c3t3, domain, criteria, params::no_perturb(), params::no_exude(), params::manifold());

  // Extract: vertices in triangulation order (deterministic), facets in complex order.
  std::map<Tr::Vertex_handle, int> index;
  std::vector<Eigen::Vector3d> pts;
  std::vector<std::array<int, 3>> tris;
  tris.reserve(c3t3.number_of_facets_in_complex());
  for (auto fit = c3t3.facets_in_complex_begin(); fit != c3t3.facets_in_complex_end(); ++fit) {
    const Tr::Cell_handle c = fit->first;
    const int i = fit->second;
    std::array<int, 3> tri{};
    for (int k = 0; k < 3; ++k) {
      const Tr::Vertex_handle vh = c->vertex((i + 1 + k) % 4);
      auto [it, inserted] = index.emplace(vh, static_cast<int>(pts.size()));
      if (inserted) pts.push_back(to_eigen(tr.point(vh).point()));
      tri[k] = it->second;
    }
    tris.push_back(tri);
  }
  require(!tris.empty(), "procedural polygonizer", "found no surface",
          "check the shape's seeds and bounding sphere");
  TriangleMesh out;
  out.vertices.resize(static_cast<Eigen::Index>(pts.size()), 3);
  for (std::size_t k = 0; k < pts.size(); ++k)
    out.vertices.row(static_cast<Eigen::Index>(k)) = pts[k].cast<float>();
  out.triangles.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (std::size_t k = 0; k < tris.size(); ++k)
    out.triangles.row(static_cast<Eigen::Index>(k)) << tris[k][0], tris[k][1], tris[k][2];
  orient_outward(out.vertices, out.triangles);
  return out;
}

}  // namespace isokit::skinning::detail
