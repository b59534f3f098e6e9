// SPDX-License-Identifier: MIT
// A plain triangle mesh for the skinning tests that build their own shapes (metrics, renders).
#pragma once

#include "isokit/track/mesh.h"

namespace isokit::skinning::testing {

inline constexpr double kPi = 3.14159265358979323846;

struct Mesh {
  track::Positions v;
  track::Triangles f;
};

}  // namespace isokit::skinning::testing
