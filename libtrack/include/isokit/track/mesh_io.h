// SPDX-License-Identifier: MIT
/// \file
/// Triangle-mesh files through OpenMesh (OBJ, OFF, PLY, STL, OM), converted to the flat arrays
/// the tracker uses. OpenMesh stays out of this header (linked privately).
#pragma once

#include <string>

#include "isokit/track/mesh.h"

namespace isokit::track {

/// A mesh as flat arrays: `#V by 3` positions, `#F by 3` counter-clockwise triangles.
struct TriangleMesh {
  Positions vertices;
  Triangles triangles;
};

/// Reads a mesh file; polygons are fan-triangulated by OpenMesh. Faces OpenMesh cannot add
/// (non-manifold "complex" edges or vertices) are dropped by OpenMesh with a warning on stderr;
/// isolated vertices are kept.
/// \throw InputError naming the file if it cannot be read, has no triangles, or holds non-finite
/// coordinates.
TriangleMesh read_mesh(const std::string& path);

/// Writes a mesh file (format from the extension), through a temporary name then a rename.
/// \throw InputError naming the file on failure or invalid indices.
void write_mesh(const std::string& path, const Positions& vertices, const Triangles& triangles);

}  // namespace isokit::track
