// SPDX-License-Identifier: MIT
/// \file
/// Whether a triangle mesh is closed, per connected component: open borders, non-manifold and
/// misoriented edges. The volume metrics (metrics.h) cover the closed components only.
#pragma once

#include <vector>

#include "isokit/track/mesh.h"

namespace isokit::skinning {

/// One connected component of a triangle mesh (triangles joined through shared vertices) and its
/// edges' defects. Edges of degenerate index triples (`a == b`) are ignored.
struct MeshComponent {
  int triangles{0};
  int border_edges{0};        ///< edges used by one triangle (an open border)
  int non_manifold_edges{0};  ///< edges used by three or more triangles
  /// Edges of two triangles that traverse them the same way (inconsistent orientation).
  int misoriented_edges{0};
  /// A closed, consistently oriented surface: every edge used by exactly two triangles, once in
  /// each direction (what `enclosed_volume` needs to be meaningful).
  bool closed() const { return border_edges == 0 && non_manifold_edges == 0 && misoriented_edges == 0; }
};

/// The components of a mesh and which triangle belongs to which.
struct MeshClosure {
  std::vector<int> component;             ///< `#F`: component of each triangle
  std::vector<MeshComponent> components;  ///< in order of their first triangle
  /// True when the mesh has triangles and every component is closed.
  bool closed() const;
  int closed_components() const;
};

/// Connected components and their closedness.
/// \throw InputError naming the triangle for an index outside `[0, num_vertices)`.
MeshClosure mesh_closure(const track::Triangles& triangles, Eigen::Index num_vertices);

}  // namespace isokit::skinning
