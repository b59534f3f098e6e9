// SPDX-License-Identifier: MIT
// 2014 stage 2: Newton projection of the initial guess onto each vertex's iso-value
// (docs/tracking.md, step 1).
#include "stages.h"

namespace isokit::track::detail {

void project(TrackState& s) {
  for (int k = 0; k < s.m.options.initial_newton_steps && !s.active.empty(); ++k) {
    const float mx = sweep(s, false);
    if (mx <= s.tol) break;
  }
}

}  // namespace isokit::track::detail
