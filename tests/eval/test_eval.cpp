// SPDX-License-Identifier: MIT
// The real-rig evaluation (bench/eval): which joints it bends and how, rows read from the metrics
// JSON with and without the optional fields, and a whole run over a rig folder written here (a
// capsule with a clip, and a broken file) — no shared data needed.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "eval_joints.h"
#include "eval_run.h"
#include "isokit/skinning/procedural.h"
#include "isokit/skinning/rig_io.h"
#include "skinning/pipeline_fixture.h"

using namespace isokit::skinning;
using namespace isokit::eval;
namespace fs = std::filesystem;

namespace {

std::vector<std::string> names(const Rig& rig, const std::vector<BendSpec>& bends) {
  std::vector<std::string> out;
  for (const BendSpec& b : bends) out.push_back(rig.joints[static_cast<std::size_t>(b.joint)].name);
  return out;
}

/// Distance between the parent of `joint` and its farthest child joint at a pose.
double span(const Rig& rig, const Pose& pose, int joint) {
  const std::vector<Affine> world = world_transforms(rig, pose);
  double best = 0;
  const int parent = rig.joints[static_cast<std::size_t>(joint)].parent;
  for (std::size_t c = 0; c < rig.joints.size(); ++c)
    if (rig.joints[c].parent == joint)
      best = std::max(
          best, (world[c].translation() - world[static_cast<std::size_t>(parent)].translation()).norm());
  return best;
}

}  // namespace

TEST_CASE("eval: elbows and knees of the humanoid by name, each folded", "[eval]") {
  const Rig rig = make_procedural("humanoid?vertices=2000&fingers=0");
  const std::vector<BendSpec> bends = fold_joints(rig, 120);
  CHECK(names(rig, bends) == std::vector<std::string>{"LeftForeArm", "RightForeArm", "LeftLeg", "RightLeg"});
  const std::vector<Pose> poses = bend_animation(rig, bends, 3);
  for (const BendSpec& b : bends) {
    CHECK(std::abs(b.degrees) == 120);
    CHECK(span(rig, poses[1], b.joint) < 0.8 * span(rig, poses[0], b.joint));  // the limb folds
  }
}

TEST_CASE("eval: a straight two-bone limb without limb names bends its middle joint about local x",
          "[eval]") {
  const Rig rig = make_procedural("cylinder");
  const std::vector<BendSpec> bends = fold_joints(rig, 120);
  REQUIRE(names(rig, bends) == std::vector<std::string>{"Bone1"});
  CHECK(bends[0].axis == 0);
  CHECK(bends[0].degrees == 120);
}

TEST_CASE("eval: rows use the optional metrics when present and show — when absent", "[eval]") {
  nlohmann::json m =
      nlohmann::json::parse(R"({"methods": {"tracking2014": {"mean_ms": 2.5, "rest_recovery": null,
    "worst": {"self_intersections": 7, "new_inverted_triangles": 3, "edge_distortion_max": 0.5,
              "edge_distortion_mean": 0.1, "iso_residual_max": 0.01},
    "frames": [{"ms": 2, "volume_ratio": 0.9}, {"ms": 3, "volume_ratio": 1.1}]}}})");
  std::vector<Row> rows = rows_from_metrics(m, "r", "a", true);
  REQUIRE(rows.size() == 1);
  CHECK(rows[0]["self_intersections_new"].is_null());
  CHECK(rows[0]["capped_share"].is_null());
  CHECK(rows[0]["iterations_median"].is_null());
  CHECK(rows[0]["worst_ms"] == 3);
  CHECK(rows[0]["volume_ratio_min"] == 0.9);
  CHECK(markdown_table(rows).find("— (7)") != std::string::npos);
  CHECK(rows[0]["skin_overlap_new"].is_null());
  CHECK(rows[0]["folded_new"].is_null());

  m["closed"] = false;
  m["methods"]["tracking2014"]["frames"] = nlohmann::json::parse(R"([
    {"ms": 2, "volume_ratio": 0.9, "self_intersections_new": 1, "tracker_calls": 10, "capped_calls": 1,
     "call_iterations": [5, 1, 9], "self_overlap_new": 0.00125, "skin_overlap_new": 0.0008, "folded_new": 2},
    {"ms": 3, "volume_ratio": 1.1, "self_intersections_new": 4, "tracker_calls": 30, "capped_calls": 1,
     "call_iterations": [2, 7, 3, 100], "self_overlap_new": 0.0005, "skin_overlap_new": 0.0001, "folded_new": 6}])");
  rows = rows_from_metrics(m, "r", "a", true);
  CHECK(rows[0]["self_intersections_new"] == 4);
  CHECK(rows[0]["self_overlap_new"] == 0.00125);  // the worst frame's, shown in percent
  CHECK(rows[0]["skin_overlap_new"] == 0.0008);
  CHECK(rows[0]["folded_new"] == 6);
  CHECK(markdown_table(rows).find("| 0.1250 | 0.0800 | 4 (") != std::string::npos);
  CHECK(markdown_table(rows).find(") | 6 | 3 |") != std::string::npos);  // folded new, then new inverted
  CHECK(rows[0]["capped_share"] == 0.05);
  // Iterations per call over both frames (1 2 3 5 7 9 100): median 5, nearest-rank p95 100.
  CHECK(rows[0]["iterations_median"] == 5);
  CHECK(rows[0]["iterations_p95"] == 100);
  CHECK(markdown_table(rows).find("| 5 / 100 |") != std::string::npos);
  CHECK(rows[0]["volume_ratio_min"].is_null());
  CHECK(markdown_table(rows).find("(open)") != std::string::npos);
}

TEST_CASE("eval: a rig folder (a capsule with a clip, a broken file) gives every row", "[eval][slow]") {
  const fs::path dir = fs::temp_directory_path() / "isokit-test-eval";
  fs::remove_all(dir);
  fs::create_directories(dir / "rigs");
  Rig rig = testing::capsule_rig();
  BendSpec wave;
  wave.joint = rig.joint_index("Bone1");
  wave.degrees = 60;
  rig.clips.push_back(Clip{"wave", 30, bend_animation(rig, {wave}, 9), nullptr});
  save_rig(rig, (dir / "rigs" / "capsule.glb").string());
  std::ofstream(dir / "rigs" / "broken.glb") << "not a glTF file";

  EvalOptions options;
  options.folders = {(dir / "rigs").string()};
  options.max_frames = 4;
  options.bend_frames = 5;
  options.out = (dir / "out").string();
  const std::vector<Row> rows = run_evaluation(options);
  // Rows are sorted by rig, animation and method name.
  const std::vector<std::string> methods{"cor", "ddm", "dqs", "implicit2013", "tracking2014"};
  const std::size_t nm = methods.size();
  REQUIRE(rows.size() == 1 + 2 * nm);
  CHECK(rows[0]["rig"] == "broken");
  CHECK(rows[0]["error"].is_string());
  for (std::size_t k = 0; k < 2 * nm; ++k) {
    const Row& r = rows[1 + k];
    INFO(r.dump());
    CHECK(r["rig"] == "capsule");
    CHECK(r["error"].is_null());
    CHECK(r["animation"] == (k < nm ? "bend" : "wave"));
    CHECK(r["method"] == methods[k % nm]);
    CHECK(r["frames"] == (k < nm ? 5 : 4));
    CHECK(r["edge_distortion_max"].is_number());
    CHECK(r["rest_recovery"].is_number() ==
          (k < nm));  // the bend returns to rest; 4 frames of the wave do not
  }
  for (const char* f : {"eval.json", "eval.md", "capsule/bend.metrics.json", "capsule/wave.metrics.json",
                        "capsule/contact_sheet.png", "capsule/wave.png"})
    CHECK(fs::exists(dir / "out" / f));
  fs::remove_all(dir);
}
