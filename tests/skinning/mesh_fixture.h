// SPDX-License-Identifier: MIT
// A plain triangle mesh for the skinning tests that build their own shapes (metrics, renders).
#pragma once

#include "isokit/core/math.h"
#include "isokit/track/mesh.h"

namespace isokit::skinning::testing {

using isokit::kPi;

struct Mesh {
  track::Positions v;
  track::Triangles f;
};

}  // namespace isokit::skinning::testing
