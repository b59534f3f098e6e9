// SPDX-License-Identifier: MIT
// No vertex without a field and the fit quality report (docs/skinning.md, "No vertex without a
// field", "Fit quality"): the capsule rig fits with small distances both ways; a rigid flat
// blade (a separate piece whose HRBF cannot be bounded) gets the capsule fallback.
#include <catch2/catch.hpp>

#include <cmath>

#include "isokit/skinning/animation.h"
#include "isokit/skinning/fit_quality.h"
#include "isokit/skinning/fitted_rig.h"
#include "isokit/skinning/pipeline.h"
#include "isokit/skinning/procedural.h"
#include "pipeline_fixture.h"

using namespace isokit;
using namespace isokit::skinning;

namespace {

/// The capsule rig plus a flat, one-sided blade (an open strip with no volume, as a sword or a
/// face patch) beside the tube, rigidly weighted to a third joint "Blade" under "Bone1".
Rig blade_rig() {
  Rig r = testing::capsule_rig();
  const int base = static_cast<int>(r.rest.rows());
  const int nx = 8, ny = 4;
  Eigen::MatrixXf rest(base + (nx + 1) * (ny + 1), 3);
  rest.topRows(base) = r.rest;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i)
      rest.row(base + j * (nx + 1) + i) << float(0.8 + 1.2 * i / nx), float(1.2 + 0.6 * j / ny), 0.f;
  Eigen::MatrixXi tris(r.triangles.rows() + 2 * nx * ny, 3);
  tris.topRows(r.triangles.rows()) = r.triangles;
  Eigen::Index f = r.triangles.rows();
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = base + j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;
      tris.row(f++) << a, b, d;
      tris.row(f++) << a, d, c;
    }
  r.rest = rest;
  r.triangles = tris;
  r.joints.push_back(
      {"Blade", 1, Affine(Eigen::Translation3d(0.8, 0.5, 0)), Affine(Eigen::Translation3d(-0.8, -1.5, 0))});
  for (int v = base; v < rest.rows(); ++v) {
    r.weights.joints.push_back(2);
    r.weights.weights.push_back(1.f);
    r.weights.offsets.push_back(static_cast<int>(r.weights.joints.size()));
  }
  return r;
}

/// The capsule rig with a third joint "Patch" under Bone1 that dominates a one-sided patch of
/// the tube (x > 0.12, 1.3 < y < 1.9): a part that is no limb, as a heat-weighted partition of a
/// real rig gives (CesiumMan's waist strip, a Testwuson back part holed by its neighbours).
Rig patch_rig() {
  Rig r = testing::capsule_rig();
  r.joints.push_back(
      {"Patch", 1, Affine(Eigen::Translation3d(0, 0.5, 0)), Affine(Eigen::Translation3d(0, -1.5, 0))});
  SkinWeights w;
  w.offsets.push_back(0);
  for (Eigen::Index v = 0; v < r.rest.rows(); ++v) {
    const float x = r.rest(v, 0), y = r.rest(v, 1);
    if (x > -0.1f && y > 1.45f && y < 1.56f) {
      w.joints.push_back(2);
      w.weights.push_back(1.f);
    } else {
      for (int k = r.weights.offsets[static_cast<std::size_t>(v)];
           k < r.weights.offsets[static_cast<std::size_t>(v) + 1]; ++k) {
        w.joints.push_back(r.weights.joints[static_cast<std::size_t>(k)]);
        w.weights.push_back(r.weights.weights[static_cast<std::size_t>(k)]);
      }
    }
    w.offsets.push_back(static_cast<int>(w.joints.size()));
  }
  r.weights = w;
  return r;
}

}  // namespace

TEST_CASE("fit quality: the capsule rig's primitives match their parts both ways", "[skinning][fit]") {
  const FittedRig fitted(testing::capsule_rig(), SkinSetup{});
  const FitQuality q = fit_quality(fitted);
  REQUIRE(q.parts.size() == 2);
  CHECK(q.diagonal == Approx(std::sqrt(0.5 * 0.5 + 2.5 * 2.5 + 0.5 * 0.5)).epsilon(0.01));
  CHECK(q.vertices_without_field == 0);
  CHECK(q.unrelated_inside() == 0);
  for (const PartQuality& p : q.parts) {
    INFO("joint " << p.joint << ": vertex->surface p95 " << p.distances.to_surface_p95 / q.diagonal << " max "
                  << p.distances.to_surface_max / q.diagonal << ", surface->vertex p95 "
                  << p.distances.from_surface_p95 / q.diagonal << " max "
                  << p.distances.from_surface_max / q.diagonal);
    CHECK(fitted.bones()[static_cast<std::size_t>(p.joint)].rule == FitRule::hrbf);
    CHECK(p.distances.surface_points > 100);
    // The limb (Bone1) meets the targets (p95 <= 1 %, max <= 3 % of the diagonal; measured
    // 0.29 / 0.49 % and 0.27 / 1.25 %). The root's free end is a cap whose samples the culling
    // planes drop (2013 eq. 2): its HRBF rounds the end off short (measured 3.0 / 6.0 % and
    // 4.2 / 6.3 %), which this report exists to show.
    const double p95 = p.joint == 0 ? 0.05 : 0.01, max = p.joint == 0 ? 0.08 : 0.03;
    CHECK(p.distances.to_surface_p95 <= p95 * q.diagonal);
    CHECK(p.distances.to_surface_max <= max * q.diagonal);
    CHECK(p.distances.from_surface_p95 <= p95 * q.diagonal);
    CHECK(p.distances.from_surface_max <= max * q.diagonal);
  }
  CHECK(q.worst_to_surface_max() <= 0.09);
  CHECK(std::isfinite(q.worst_from_surface_max()));
}

TEST_CASE("no vertex without a field: a blade whose HRBF cannot be bounded gets a documented rule",
          "[skinning][fit]") {
  const FittedRig fitted(blade_rig(), SkinSetup{});
  const BonePart& blade = fitted.bones()[2];
  INFO("blade: rule " << to_string(blade.rule) << ", error " << blade.error);
  CHECK(blade.rule == FitRule::capsule);           // a separate piece shares no neighbour's primitive
  CHECK(fitted.bones()[1].rule == FitRule::hrbf);  // Bone1 keeps its own fit, not bloated over the blade
  const FitQuality q = fit_quality(fitted);
  CHECK(q.vertices_without_field == 0);
  for (const BonePart& b : fitted.bones()) {
    CHECK(b.rule != FitRule::none);
    if (b.rule == FitRule::shared) CHECK(fitted.bones()[static_cast<std::size_t>(b.merged_into)].fitted);
  }
  for (const PartQuality& p : q.parts) {
    CHECK(std::isfinite(p.distances.to_surface_max));
    CHECK(std::isfinite(p.distances.from_surface_max));
  }
}

// The 4k humanoid's toe (a short, flat part) has no HRBF that vanishes on its box. Sharing the
// foot's primitive (the default) distorts its edges more than DQS when bent 90° (edge distortion
// max 0.74 against 0.61); with `capsule_match` a capsule matches it (vertex -> surface p95 0.43 r)
// and keeps it moving with its own joint: 0.55. (Off by default: on the Fox the capsules cost
// more inverted triangles and volume; docs/skinning.md.)
TEST_CASE(
    "a part without an HRBF follows its own joint: the humanoid's toe bent 90 degrees, no worse than DQS",
    "[skinning][fit][slow]") {
  SkinSetup setup;
  setup.operator_resolution = 64;
  setup.operator_slices = 32;
  setup.capsule_match = 0.5;
  Skinner sk(make_humanoid({4000, true}), setup);
  int toe = -1;
  for (std::size_t j = 0; j < sk.rig().joints.size(); ++j)
    if (sk.rig().joints[j].name == "LeftToeBase") toe = static_cast<int>(j);
  REQUIRE(toe >= 0);
  const BonePart& b = sk.fitted().bones()[static_cast<std::size_t>(toe)];
  REQUIRE(b.rule == FitRule::capsule);
  CHECK(fit_quality(sk.fitted()).vertices_without_field == 0);
  const auto poses = bend_animation(sk.rig(), {parse_bend("LeftToeBase:x:90", sk.rig())}, 9);
  const BakeResult dqs = sk.bake(Method::kDqs, poses);
  const BakeResult trk = sk.bake(Method::kTracking2014, poses);
  INFO("edge distortion max: dqs " << dqs.worst.edge_distortion_max << ", tracking2014 "
                                   << trk.worst.edge_distortion_max);
  CHECK(trk.worst.edge_distortion_max <= dqs.worst.edge_distortion_max);
}

TEST_CASE("a poor fit counts as failed: a patch that is no limb shares its neighbour's primitive",
          "[skinning][fit]") {
  const FittedRig kept(patch_rig(), SkinSetup{});
  const BonePart& patch = kept.bones()[2];
  INFO("max_error 0: rule " << to_string(patch.rule) << ", fit error " << patch.fit.error << ", r "
                            << patch.fit.r << ", error " << patch.error);
  REQUIRE(patch.fitted);
  CHECK(patch.fit.error > patch.fit.r);  // the patch's own HRBF bulges out of it
  const FitQuality qk = fit_quality(kept);

  SkinSetup closer;  // the rule is off by default (docs/skinning.md, "Decision: rejecting poor fits")
  closer.max_fit_error = 1;
  const FittedRig fitted(patch_rig(), closer);
  const BonePart& shared = fitted.bones()[2];
  const BonePart& limb = fitted.bones()[1];
  INFO("default: rule " << to_string(shared.rule) << ", error " << shared.error << "; Bone1: rule "
                        << to_string(limb.rule) << ", fit error " << limb.fit.error << ", r " << limb.fit.r);
  CHECK(shared.rule == FitRule::shared);
  CHECK(shared.merged_into == 1);
  // The limb, holed by the patch, failed too (its own HRBF is no better); with the patch's
  // vertices back it is a whole tube and fits.
  CHECK(limb.rule == FitRule::hrbf);
  CHECK(limb.fit.error <= limb.fit.r);
  CHECK_THAT(shared.error, Catch::Contains("poor fit") && Catch::Contains("fit.max_error"));
  const FitQuality q = fit_quality(fitted);
  CHECK(q.vertices_without_field == 0);
  INFO("unrelated inside: kept " << qk.unrelated_inside() << ", shared " << q.unrelated_inside()
                                 << "; worst surface -> vertex p95: kept " << qk.worst_from_surface_p95()
                                 << ", shared " << q.worst_from_surface_p95());
  CHECK(q.worst_from_surface_p95() < qk.worst_from_surface_p95());
  CHECK(q.unrelated_inside() <= qk.unrelated_inside());
}
