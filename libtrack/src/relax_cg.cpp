// SPDX-License-Identifier: MIT
// The conjugate-gradient relaxation strategy (2014 §5.2: "higher performance may be achieved
// using the conjugate-gradient method"; docs/tracking.md, "Conjugate-gradient relaxation"): per
// iteration, the tangential ARAP system of the active vertices grown by cg_rings - 1 rings (their
// neighbours outside held in place) is solved by CG; the sweep then applies the displacements and
// takes one Newton step per active vertex.
#include "jacobi_step.h"
#include "stages.h"
#include "tangent_solve.h"

namespace isokit::track::detail {

namespace {

class CgRelaxation final : public RelaxationStrategy {
 public:
  explicit CgRelaxation(TrackState& s) : local_(s.n, -1), scale_(s.n, 1.f) {
    s.disp.assign(s.n, Vec3f{});
    problem_.adj = &s.m.adj;
    problem_.weights = s.m.weights.data();
    problem_.weight_sums = s.m.weight_sum.data();
    problem_.targets = s.targets.data();
    problem_.normals = s.normal.data();
    problem_.free3d = s.flags.contact.data();
    problem_.free_vertices = s.flags.free.data();
    problem_.scale = scale_.data();
    problem_.tolerance = s.tol;
    problem_.max_iterations = s.m.options.cg_max_iterations;
  }

  void before_sweep(TrackState& s, int) override {
    for (int r = 1; r < s.m.options.cg_rings; ++r) s.set.dilate(s.active);
    unknowns_.clear();
    const JacobiTerms t = jacobi_terms(s);
    for (int i : s.active)
      if (relaxes(s, t, std::size_t(i)) && s.normal[i] != Vec3f{}) {
        unknowns_.push_back(i);
        scale_[i] = s.m.mask[i] * s.damping[i];
      }
    problem_.positions = s.cur.data();
    problem_.anchor_k = s.m.anchor_k.empty() ? nullptr : s.m.anchor_k.data();
    problem_.anchors = s.anchors.empty() ? nullptr : s.anchors.data();
    s.stats.solver_iterations += solve_tangential_cg(problem_, unknowns_, local_, d_);
    for (std::size_t a = 0; a < unknowns_.size(); ++a) s.disp[std::size_t(unknowns_[a])] = d_[a];
  }

  void after_sweep(TrackState& s) override {
    for (int i : unknowns_) s.disp[std::size_t(i)] = Vec3f{};
  }

 private:
  std::vector<int> local_, unknowns_;
  std::vector<float> scale_;
  std::vector<Vec3f> d_;
  TangentProblem problem_;
};

}  // namespace

std::unique_ptr<RelaxationStrategy> cg_relaxation(TrackState& s) {
  return std::make_unique<CgRelaxation>(s);
}

}  // namespace isokit::track::detail
