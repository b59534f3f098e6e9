// SPDX-License-Identifier: MIT
// The bake as the CLI runs it, step by step (bake_job.h): animation requests, fit warnings, the
// peak frame, the written result, the outputs.
#include <catch2/catch.hpp>

#include <filesystem>

#include "isokit/core/error.h"
#include "isokit/skinning/bake_job.h"
#include "pipeline_fixture.h"

using namespace isokit::skinning;
namespace fs = std::filesystem;

TEST_CASE("bake job: an animation request names at most one source", "[skinning][bake_job]") {
  const Rig r = testing::capsule_rig(8, 8, 2);
  AnimationRequest none;
  CHECK_NOTHROW(check_animation_request(none));
  CHECK_THROWS_WITH(make_animation(r, none), Catch::Contains("has no clip") && Catch::Contains("--bend"));
  AnimationRequest two;
  two.clip = "walk";
  two.bends = {"Bone1:z:90"};
  CHECK_THROWS_WITH(make_animation(r, two),
                    Catch::Contains("at most one of --clip, --bend or --pose-script"));
  AnimationRequest few = none;
  few.frames = 2;
  CHECK_THROWS_WITH(check_animation_request(few), Catch::Contains("--frames") && Catch::Contains("got 2"));
  AnimationRequest bend;
  bend.bends = {"Bone1:z:90"};
  bend.frames = 5;
  const Animation a = make_animation(r, bend, 0.05);
  CHECK(a.poses.size() == 5);
  REQUIRE(a.bends.size() == 1);
  CHECK(a.description == "--bend Bone1:z:90 (5 frames), tracking sub-steps <= 0.05 rad");
  CHECK(make_animation(r, bend).description == "--bend Bone1:z:90 (5 frames)");
  AnimationRequest clip;
  clip.clip = "no such clip";
  CHECK_THROWS_AS(make_animation(r, clip), isokit::InputError);
}

TEST_CASE("bake job: no animation option plays the rig's only clip; several are listed",
          "[skinning][bake_job]") {
  Rig r = testing::with_turn_clip(testing::capsule_rig(8, 8, 2), 4, 0.2);
  const Animation a = make_animation(r, AnimationRequest{});
  CHECK(a.poses.size() == 4);
  CHECK(a.description == "clip animation_0");
  r.clips.push_back(r.clips[0]);
  r.clips[1].name = "walk";
  CHECK_THROWS_WITH(make_animation(r, AnimationRequest{}), Catch::Contains("2 clips") &&
                                                               Catch::Contains("animation_0, walk") &&
                                                               Catch::Contains("--clip"));
}

TEST_CASE("bake job: the peak frame is the pose rotated farthest from the first", "[skinning][bake_job]") {
  const Rig r = testing::capsule_rig(8, 8, 2);
  for (int frames : {3, 5, 9, 31}) {
    const std::vector<Pose> poses = bend_animation(r, {parse_bend("Bone1:x:120", r)}, frames);
    CHECK(peak_frame(poses) == frames / 2);  // rest, peak, rest
  }
  CHECK(peak_frame(std::vector<Pose>(1, rest_pose(r))) == 0);
}

TEST_CASE("bake job: the written result is the chosen method's", "[skinning][bake_job]") {
  std::vector<BakeResult> results(2);
  results[0].method = Method::kDqs;
  results[1].method = Method::kTracking2014;
  CHECK(&main_result(results, Method::kTracking2014) == &results[1]);
  CHECK(&main_result(results, Method::kDqs) == &results[0]);
  CHECK_THROWS_AS(main_result(results, Method::kLbs), isokit::InputError);
}

TEST_CASE("bake job: fit warnings name under-resolved parts; outputs are written where asked",
          "[skinning][bake_job]") {
  SkinSetup setup;
  setup.fold_repair_min_part_vertices = 100000;  // every part is "small"
  Skinner sk(testing::capsule_rig(), setup);
  const std::vector<std::string> w = fit_warnings(sk.fitted(), setup);
  REQUIRE(w.size() == 1);
  CHECK_THAT(w[0], Catch::Contains("of fewer than 100000 vertices") && Catch::Contains("--method dqs"));
  setup.fold_repair_min_part_vertices = 0;
  CHECK(fit_warnings(sk.fitted(), setup).empty());

  const std::vector<Pose> poses = bend_animation(sk.rig(), {parse_bend("Bone1:z:60", sk.rig())}, 3);
  BakeOptions o;
  o.self_intersections = false;
  const std::vector<BakeResult> results{sk.bake(Method::kDqs, poses, o)};
  const fs::path dir = fs::temp_directory_path() / "isokit-test-bake-job";
  fs::remove_all(dir);
  BakeOutputs out{(dir / "a" / "x.glb").string(), (dir / "m.json").string(), "", (dir / "ply").string()};
  const ReportContext ctx{"test", 30, 1, 0};
  const std::vector<std::string> written = write_bake_outputs(sk.rig(), results, results[0], ctx, {}, out);
  CHECK(written.size() == 3);
  CHECK(fs::file_size(out.glb) > 0);
  CHECK(fs::file_size(out.metrics) > 0);
  CHECK(fs::exists(dir / "ply" / "frame_0002.ply"));
  fs::remove_all(dir);
}

TEST_CASE("bake job: --device names cpu or cuda; cuda is refused with its reason", "[skinning][bake_job]") {
  CHECK(device_from_string("cpu") == Device::kCpu);
  CHECK(device_from_string("cuda") == Device::kCuda);
  CHECK_THROWS_WITH(device_from_string("gpu"), Catch::Contains("use cpu or cuda"));
  CHECK_NOTHROW(check_device(Device::kCpu));
  // No device tracker exists yet: without a CUDA build, without a device, or with one, the reason
  // is named and the fix is --device cpu.
  CHECK_THROWS_WITH(check_device(Device::kCuda),
                    Catch::Contains("--device cuda: ") && Catch::Contains("use --device cpu"));
}
