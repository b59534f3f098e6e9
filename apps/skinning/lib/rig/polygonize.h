// SPDX-License-Identifier: MIT
// Internal: the polygonizer behind the procedural humanoid (CGAL Mesh_3 surface meshing of an
// implicit shape by Delaunay refinement). No CGAL header leaks out of polygonize_mesh3.cpp.
#pragma once

#include <functional>
#include <vector>

#include <Eigen/Core>

#include "isokit/track/mesh.h"

namespace isokit::skinning::detail {

/// A closed implicit shape for `mesh_implicit_surface`.
struct ImplicitShape {
  /// Signed distance-like function, < 0 inside, > 0 outside; Lipschitz, smooth near the surface.
  std::function<double(const Eigen::Vector3d&)> sdf;
  /// Local facet-size bound at a point (the mesher uses `min(global size, local_size(p))`); keeps
  /// thin parts (fingers) resolved whatever the global size. Should be 1/2-Lipschitz or so.
  std::function<double(const Eigen::Vector3d&)> local_size;
  Eigen::Vector3d center{Eigen::Vector3d::Zero()};  ///< bounding sphere holding the whole shape
  double radius{1.0};
  /// Seed segments, each from a point inside to a point outside: their surface crossings start
  /// the Delaunay refinement, so every part (each finger) is found whatever its size.
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> seeds;
};

struct TriangleMesh {
  track::Positions vertices;
  track::Triangles triangles;
};

/// Meshes the 0-level of `shape.sdf` with CGAL Mesh_3 (surface only, manifold, facet angle
/// bound 30°, facet size `min(size, local_size)`, facet distance `distance_ratio` × that size),
/// sequentially and with a fixed random seed: the result is deterministic. Triangles are
/// oriented counter-clockwise seen from outside (outward = increasing sdf).
/// \throw InputError if the result is not a closed, consistently orientable surface.
TriangleMesh mesh_implicit_surface(const ImplicitShape& shape, double size, double distance_ratio);

}  // namespace isokit::skinning::detail
