// SPDX-License-Identifier: MIT
#include "isokit/track/mesh_io.h"

#include <cmath>
#include <vector>

// GCC 12 reports -Wmaybe-uninitialized inside OpenMesh's property containers when they are
// instantiated here (a false positive in third-party templates); silence it for this file only.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include "isokit/core/atomic_file.h"
#include "isokit/core/error.h"

namespace isokit::track {

namespace {
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;
}  // namespace

TriangleMesh read_mesh(const std::string& path) {
  OmMesh mesh;
  OpenMesh::IO::Options opt;
  require(OpenMesh::IO::read_mesh(mesh, path, opt), "mesh file " + path, "cannot be read",
          "check the path and use OBJ, OFF, PLY, STL or OM");
  require(mesh.n_faces() > 0, "mesh file " + path, "has no triangles", "pass a triangle mesh");
  TriangleMesh out;
  out.vertices.resize(static_cast<Eigen::Index>(mesh.n_vertices()), 3);
  for (const auto vh : mesh.vertices()) {
    const auto& p = mesh.point(vh);
    for (int a = 0; a < 3; ++a) {
      require(std::isfinite(p[a]), "mesh file " + path + " vertex " + std::to_string(vh.idx()),
              "is not finite", "fix the coordinates");
      out.vertices(vh.idx(), a) = p[a];
    }
  }
  out.triangles.resize(static_cast<Eigen::Index>(mesh.n_faces()), 3);
  for (const auto fh : mesh.faces()) {
    int k = 0;
    for (const auto vh : mesh.fv_range(fh)) out.triangles(fh.idx(), k++) = vh.idx();
  }
  return out;
}

void write_mesh(const std::string& path, const Positions& vertices, const Triangles& triangles) {
  vertex_adjacency(triangles, static_cast<int>(vertices.rows()));  // validates the indices
  OmMesh mesh;
  std::vector<OmMesh::VertexHandle> vh;
  vh.reserve(static_cast<std::size_t>(vertices.rows()));
  for (Eigen::Index i = 0; i < vertices.rows(); ++i)
    vh.push_back(mesh.add_vertex(OmMesh::Point(vertices(i, 0), vertices(i, 1), vertices(i, 2))));
  for (Eigen::Index f = 0; f < triangles.rows(); ++f) {
    const auto fh = mesh.add_face(vh[triangles(f, 0)], vh[triangles(f, 1)], vh[triangles(f, 2)]);
    require(fh.is_valid(), "triangle " + std::to_string(f), "makes the mesh non-manifold",
            "fix the connectivity before writing");
  }
  write_file_atomically(path, [&](const std::string& tmp) {  // the temporary name keeps the extension
    require(OpenMesh::IO::write_mesh(mesh, tmp), "mesh file " + path, "cannot be written",
            "check the directory and the extension");
  });
}

}  // namespace isokit::track
