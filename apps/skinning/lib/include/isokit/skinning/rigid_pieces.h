// SPDX-License-Identifier: MIT
/// \file
/// Rigid pieces of a rig: the connected components of the welded mesh that move as one solid
/// with their bone — armour panels, a separate sword, a helmet — found from the skin weights
/// alone. A component is rigid when every vertex has the same influences (the same joints with
/// the same weights, within a tolerance): skinning then moves all of it by one transform. A
/// connected skin whose vertices follow different bones (even with one influence each, 2014
/// Fig. 8) is skin, not a rigid piece.
#pragma once

#include <vector>

#include "isokit/skinning/rig.h"

namespace isokit::skinning {

struct RigidPiece {
  std::vector<int> vertices;   ///< welded vertex indices, ascending
  std::vector<int> joints;     ///< the influences every vertex shares (ascending joint indices)
  std::vector<float> weights;  ///< their weights, aligned with `joints`
  int triangles{0};            ///< triangles of the component
};

/// The rig's rigid pieces (rigid_pieces.h), in the order of their first vertex. `tolerance`:
/// largest difference of a shared weight between two vertices of a piece (default 1e-4, the
/// normalisation's float rounding with room). A rig without weights has none.
/// \throw InputError for a negative or non-finite tolerance.
std::vector<RigidPiece> find_rigid_pieces(const Rig& rig, double tolerance = 1e-4);

}  // namespace isokit::skinning
