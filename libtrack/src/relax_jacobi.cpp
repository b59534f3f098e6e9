// SPDX-License-Identifier: MIT
// The Jacobi relaxation strategy (2014 §5.2), Chebyshev-accelerated (Wang 2015, "A Chebyshev
// semi-iterative approach for accelerating projective and position-based dynamics"); the
// per-vertex step is in jacobi_step.h.
#include "stages.h"

namespace isokit::track::detail {

namespace {

class JacobiRelaxation final : public RelaxationStrategy {
 public:
  // Chebyshev weights: ω = 2 / (2 - ρ²) at the first accelerated iteration, then
  // ω <- 4 / (4 - ρ² ω); plain Jacobi (ω = 1) before, or when ρ = 0.
  void before_sweep(TrackState& s, int k) override {
    if (s.rho2 > 0.f && k >= kChebyshevDelay)
      s.omega = k == kChebyshevDelay ? 2.f / (2.f - s.rho2) : 4.f / (4.f - s.rho2 * s.omega);
  }
  void after_sweep(TrackState&) override {}
};

}  // namespace

std::unique_ptr<RelaxationStrategy> jacobi_relaxation() {
  return std::make_unique<JacobiRelaxation>();
}

}  // namespace isokit::track::detail
