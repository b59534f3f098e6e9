// SPDX-License-Identifier: MIT
/// \file
/// Interpenetration measured as a volume: the space a triangle mesh encloses twice.
///
/// The winding number w(x) of a closed, consistently oriented mesh counts how many times the
/// surface wraps around x: 1 inside one body, 0 outside, 2 where two parts of the skin pass into
/// each other. Two skins pressed onto one contact surface (what the 2014 contact operators make)
/// enclose nothing twice, however many of their triangles cross; two skins that interpenetrate
/// enclose their common volume twice. So the volume where |w| >= 2 is the measure of
/// interpenetration that matches what a viewer sees, where a count of intersecting triangle pairs
/// also counts touching skins (docs/skinning-metrics.md, "Self-overlap").
///
/// How it is computed: columns parallel to z, on a square grid of `resolution` cells across the
/// largest side of the mesh's bounding box, are cast through the mesh; each column's crossings
/// are sorted along z and swept, the winding number changing by -1 or +1 at each crossing by the
/// sign of the triangle's normal along z. Lengths along a column are exact; the grid only
/// samples the (x, y) cross-section, so the error is of the order of one cell times the
/// silhouette of the overlapped region. A column centre on a shared edge counts that edge once
/// (a tie rule on a canonical edge function).
///
/// Open meshes: the winding number of a surface with holes is not an integer. Each connected
/// piece of the mesh's border (the edges its triangles do not run both ways, with their net
/// count) is closed first by a cone to the centroid of its vertices in the measured pose, so an
/// open mesh is measured as the closed surface it bounds with those caps: a sleeve open at the
/// wrist counts as closed by a flat-ish lid there. The caps move with the pose; compare an open
/// mesh's frames with its rest frame (`self_overlap_new`). A column that still does not close
/// (a border through which a column passes exactly on an edge of a non-manifold fan) counts each
/// segment from below and from above and takes the smaller count, and is reported in
/// `open_columns`.
#pragma once

#include <cstddef>
#include <vector>

#include "isokit/track/mesh.h"

namespace isokit::skinning {

struct SelfOverlapOptions {
  /// Grid cells across the largest side of the mesh's bounding box (the columns' spacing is that
  /// side / `resolution`). Default 160: the resolution issue 42 and QUALITY.md ask for at least.
  /// Must be in [1, 4096].
  int resolution{160};
  /// Triangles (and columns) per parallel task; 0 = one serial pass. The result does not depend on
  /// it, bit for bit.
  std::size_t grain{512};
  /// Fill `SelfOverlap::overlap_triangles` (the triangles that bound the region enclosed twice).
  bool mark_triangles{false};
};

struct SelfOverlap {
  double overlap{0};    ///< volume where |w| >= 2, mesh units³
  double enclosed{0};   ///< volume where |w| >= 1, mesh units³
  double cell{0};       ///< column spacing, mesh units
  int columns{0};       ///< columns of the grid
  int open_columns{0};  ///< columns whose crossings still do not sum to 0 after the borders are closed
  /// With `mark_triangles`: the triangles whose crossing of some column borders a segment with
  /// |w| >= 2, ascending (the overlay the viewer and the renders colour).
  std::vector<int> overlap_triangles;
};

/// The volume a mesh encloses twice (and once), see the file comment.
/// \throw InputError naming the triangle for an index out of range or a non-finite coordinate,
/// or naming the option for a resolution outside [1, 4096].
SelfOverlap self_overlap(const track::Positions& positions, const track::Triangles& triangles,
                         const SelfOverlapOptions& options = {});

/// The triangles bounding a region `posed` encloses twice that are not among those of `rest`
/// (by identity), ascending: what the renders and the viewer colour.
/// \throw InputError as `self_overlap`, or when the two poses have different vertex counts.
std::vector<int> new_overlap_triangles(const track::Positions& rest, const track::Positions& posed,
                                       const track::Triangles& triangles);

}  // namespace isokit::skinning
