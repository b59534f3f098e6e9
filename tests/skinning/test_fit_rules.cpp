// SPDX-License-Identifier: MIT
// No vertex without a field and the fit quality report (docs/skinning.md, "No vertex without a
// field", "Fit quality"): the capsule rig fits with small distances both ways; a rigid flat
// blade (a separate piece whose HRBF cannot be bounded) gets the capsule fallback.
#include <catch2/catch.hpp>

#include <cmath>

#include <nlohmann/json.hpp>
#include "isokit/skinning/animation.h"
#include "isokit/skinning/fit_quality.h"
#include "isokit/skinning/fitted_rig.h"
#include "isokit/skinning/pipeline.h"
#include "isokit/skinning/procedural.h"
#include "isokit/skinning/report.h"
#include "isokit/skinning/skin_field.h"
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
    // The limb (Bone1) meets the issue's targets (p95 <= 1 %, max <= 3 % of the diagonal; measured
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

namespace {

SkinSetup distance_setup() {
  SkinSetup s;
  s.fit.field = isokit::implicit::PartFitOptions::FieldKind::distance;
  return s;
}

/// The capsule rig with a small closed box sunk into the tube at mid length (a hidden piece, as
/// an eyeball in its socket or a robot's limb in its torso), weighted to Bone1.
Rig hidden_box_rig() {
  Rig r = testing::capsule_rig();
  const int base = static_cast<int>(r.rest.rows());
  const float c[8][3] = {{-.1f, 1.4f, -.1f}, {.1f, 1.4f, -.1f}, {.1f, 1.6f, -.1f}, {-.1f, 1.6f, -.1f},
                         {-.1f, 1.4f, .1f},  {.1f, 1.4f, .1f},  {.1f, 1.6f, .1f},  {-.1f, 1.6f, .1f}};
  Eigen::MatrixXf rest(base + 8, 3);
  rest.topRows(base) = r.rest;
  for (int k = 0; k < 8; ++k) rest.row(base + k) << c[k][0], c[k][1], c[k][2];
  const int quads[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                           {2, 3, 7, 6}, {1, 2, 6, 5}, {0, 4, 7, 3}};
  Eigen::MatrixXi tris(r.triangles.rows() + 12, 3);
  tris.topRows(r.triangles.rows()) = r.triangles;
  for (int q = 0; q < 6; ++q) {
    tris.row(r.triangles.rows() + 2 * q) << base + quads[q][0], base + quads[q][1], base + quads[q][2];
    tris.row(r.triangles.rows() + 2 * q + 1) << base + quads[q][0], base + quads[q][2], base + quads[q][3];
  }
  r.rest = rest;
  r.triangles = tris;
  for (int v = 0; v < 8; ++v) {
    r.weights.joints.push_back(1);
    r.weights.weights.push_back(1.f);
    r.weights.offsets.push_back(static_cast<int>(r.weights.joints.size()));
  }
  return r;
}

}  // namespace

TEST_CASE("distance fields: the capsule rig's parts and their composition agree with the mesh at rest",
          "[skinning][fit][distance]") {
  const Rig rig = testing::capsule_rig();
  Skinner skinner(rig, distance_setup());
  const FittedRig& fitted = skinner.fitted();
  for (const BonePart& b : fitted.bones()) {
    CHECK(b.rule == FitRule::distance);
    REQUIRE(b.fit.grid);
    CHECK(b.fit.grid->resolution() >= 32);
    CHECK(b.fit.grid->resolution() <= 64);
  }
  const FitQuality q = fit_quality(fitted);
  for (const PartQuality& p : q.parts) {
    INFO("joint " << p.joint << ": angle p95 " << p.agreement.angle_p95 << " max " << p.agreement.angle_max);
    CHECK(p.agreement.points > 100);
    CHECK(p.agreement.over_limit == 0);
    CHECK(p.agreement.angle_p95 <= 20.0);
  }
  const RestAgreement a = rest_agreement(fitted, skinner.field(TreeKind::k2014));
  CHECK(a.composed.points == int(rig.rest.rows()));
  CHECK(a.composed.over_limit == 0);
  CHECK(a.composed.angle_p95 <= 20.0);
  CHECK(a.composed.distance_p95 <= 0.01 * q.diagonal);
  CHECK(a.inverted_triangles <= 0.005 * a.triangles);
  CHECK(a.unrelated_inside == 0);
  CHECK(a.open_panels == 0);
  CHECK(a.hidden_vertices == 0);
  // The paper's HRBF on the same rig, for comparison: it agrees less closely.
  SkinSetup hrbf;
  hrbf.fit.field = isokit::implicit::PartFitOptions::FieldKind::hrbf;
  Skinner paper(rig, hrbf);
  const RestAgreement h = rest_agreement(paper.fitted(), paper.field(TreeKind::k2014));
  CHECK(a.composed.distance_p95 < h.composed.distance_p95);
}

TEST_CASE("rest agreement: open panels and hidden pieces are found and counted apart",
          "[skinning][fit][distance]") {
  {
    // The blade is an open sheet: left out.
    const Rig rig = blade_rig();
    Skinner skinner(rig, distance_setup());
    int panels = 0;
    const std::vector<std::uint8_t> panel = open_panel_vertices(rig, &panels);
    CHECK(panels == 1);
    int marked = 0;
    for (std::uint8_t p : panel) marked += p;
    CHECK(marked == 45);
    const RestAgreement a = rest_agreement(skinner.fitted(), skinner.field(TreeKind::k2014));
    CHECK(a.open_panels == 1);
    CHECK(a.panel_vertices == 45);
    CHECK(a.composed.points == int(rig.rest.rows()) - 45);
  }
  {
    // The box inside the tube: hidden, the rest visible.
    const Rig rig = hidden_box_rig();
    const std::vector<std::uint8_t> hidden = hidden_vertices(rig);
    int n = 0;
    for (Eigen::Index v = 0; v < rig.rest.rows(); ++v) {
      n += hidden[static_cast<std::size_t>(v)];
      if (v >= rig.rest.rows() - 8) CHECK(hidden[static_cast<std::size_t>(v)] == 1);
    }
    CHECK(n == 8);
    Skinner skinner(rig, distance_setup());
    const RestAgreement a = rest_agreement(skinner.fitted(), skinner.field(TreeKind::k2014));
    CHECK(a.hidden_vertices == 8);
    CHECK(a.visible.points == a.composed.points - 8);
    CHECK(a.visible.over_limit == 0);
    // The metrics JSON carries the totals.
    BakeResult dqs;
    dqs.method = Method::kDqs;
    const nlohmann::json j =
        nlohmann::json::parse(metrics_json(rig, {dqs}, ReportContext{"test", 30, 1, 0, a}));
    REQUIRE(j.contains("rest_agreement"));
    CHECK(j["rest_agreement"]["hidden_vertices"] == 8);
    CHECK(j["rest_agreement"]["over_60_deg"] == a.composed.over_limit);
    CHECK(j["rest_agreement"]["vertices"] == a.composed.points);
  }
}

TEST_CASE("distance fields: setup keys and their errors", "[skinning][fit][distance]") {
  using Kind = isokit::implicit::PartFitOptions::FieldKind;
  const SkinSetup d = setup_from_json(
      R"({"fit": {"field": "distance", "distance": {"cells_per_feature": 4, "max_resolution": 80,
          "overlap_rings": 2, "overlap_sink": 0.3, "cap_height": 0.5, "feature_percentile": 0.2,
          "width_percentile": 0.8, "min_resolution": 24, "smoothing_passes": 2}}})",
      "s.json");
  CHECK(d.fit.field == Kind::distance);
  CHECK(d.fit.distance.cells_per_feature == 4.0);
  CHECK(d.fit.distance.max_resolution == 80);
  CHECK(d.fit.distance.min_resolution == 24);
  CHECK(d.fit.distance.overlap_rings == 2);
  CHECK(d.fit.distance.overlap_sink == 0.3);
  CHECK(d.fit.distance.cap_height == 0.5);
  CHECK(d.fit.distance.smoothing_passes == 2);
  CHECK_THROWS_WITH(setup_from_json(R"({"fit": {"distance": {"smoothing_passes": -1}}})", "s.json"),
                    Catch::Contains("s.json.fit.distance.smoothing_passes") && Catch::Contains("[0, 8]"));
  CHECK(setup_from_json(R"({"preset": "paper"})", "s.json").fit.field == Kind::hrbf);
  CHECK_THROWS_WITH(setup_from_json(R"({"fit": {"field": "sdf"}})", "s.json"),
                    Catch::Contains("s.json.fit.field") && Catch::Contains("\"hrbf\""));
  CHECK_THROWS_WITH(setup_from_json(R"({"fit": {"distance": {"max_resolution": 1000}}})", "s.json"),
                    Catch::Contains("s.json.fit.distance.min_resolution / max_resolution"));
  CHECK_THROWS_WITH(setup_from_json(R"({"fit": {"distance": {"overlap_sink": 2}}})", "s.json"),
                    Catch::Contains("s.json.fit.distance.overlap_sink") && Catch::Contains("[0, 1]"));
  CHECK_THROWS_WITH(setup_from_json(R"({"fit": {"distance": {"rings": 2}}})", "s.json"),
                    Catch::Contains("s.json.fit.distance.rings") && Catch::Contains("unknown key"));
}

TEST_CASE("grid storage: the setup key, the paper preset's float32, and what a fitted rig's grids use",
          "[skinning][fit]") {
  using isokit::implicit::GridStorage;
  CHECK(SkinSetup{}.fit.grid_storage == GridStorage::fixed16);
  CHECK(setup_from_json(R"({"fit": {"grid_storage": "float32"}})", "s.json").fit.grid_storage ==
        GridStorage::float32);
  CHECK(setup_from_json(R"({"preset": "paper"})", "s.json").fit.grid_storage == GridStorage::float32);
  CHECK_THROWS_WITH(setup_from_json(R"({"fit": {"grid_storage": "half"}})", "s.json"),
                    Catch::Contains("s.json.fit.grid_storage") && Catch::Contains("\"fixed16\""));
  // Every grid leaf of the fitted field takes the setup's storage; fixed16 halves the leaves.
  const Rig rig = make_cylinder();
  std::size_t bytes[2] = {0, 0};
  for (const GridStorage storage : {GridStorage::fixed16, GridStorage::float32}) {
    SkinSetup s;
    s.fit.grid_storage = storage;
    Skinner sk(rig, s);
    const isokit::implicit::Program& p = sk.field(TreeKind::k2013).program();
    int grids = 0;
    for (const auto& leaf : p.leaves()) {
      if (!leaf.grid.valid()) continue;
      ++grids;
      CHECK((leaf.grid.packed != nullptr) == (storage == GridStorage::fixed16));
      bytes[storage == GridStorage::fixed16 ? 0 : 1] += leaf.grid.node_bytes();
    }
    CHECK(grids > 0);
  }
  CHECK(bytes[0] * 2 == bytes[1]);
}

TEST_CASE("operator storage: auto is fixed16 for the 2013 tree and float32 for the 2014 tree",
          "[skinning][fit]") {
  using isokit::implicit::GridStorage;
  CHECK(!SkinSetup{}.operator_storage.has_value());
  CHECK(setup_from_json(R"({"operators": {"storage": "float32"}})", "s.json").operator_storage ==
        GridStorage::float32);
  CHECK(!setup_from_json(R"({"operators": {"storage": "auto"}})", "s.json").operator_storage.has_value());
  CHECK(setup_from_json(R"({"preset": "paper"})", "s.json").operator_storage == GridStorage::float32);
  CHECK_THROWS_WITH(setup_from_json(R"({"operators": {"storage": "half"}})", "s.json"),
                    Catch::Contains("s.json.operators.storage") && Catch::Contains("\"auto\""));
  // What each tree's program reads its grid operators from (the 2013 blend grid; the 2014
  // tree's contact operators).
  const Rig rig = make_cylinder();
  auto storage_of = [&](const SkinSetup& s, TreeKind kind) {
    Skinner sk(rig, s);
    const isokit::implicit::Program& p = sk.field(kind).program();
    int packed = 0, padded = 0;
    for (const auto& g : p.grids()) {
      packed += g.packed != nullptr;
      padded += g.padded != nullptr;
      CHECK(g.data == nullptr);
    }
    REQUIRE(packed + padded > 0);
    return packed > 0 && padded == 0 ? GridStorage::fixed16 : GridStorage::float32;
  };
  SkinSetup s;
  CHECK(storage_of(s, TreeKind::k2013) == GridStorage::fixed16);
  CHECK(storage_of(s, TreeKind::k2014) == GridStorage::float32);
  s.operator_storage = GridStorage::fixed16;
  CHECK(storage_of(s, TreeKind::k2014) == GridStorage::fixed16);
  s.operator_storage = GridStorage::float32;
  CHECK(storage_of(s, TreeKind::k2013) == GridStorage::float32);
}
