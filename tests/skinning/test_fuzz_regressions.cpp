// SPDX-License-Identifier: MIT
// Inputs found while fuzzing the skinning readers (docs/fuzzing.md), stored in tests/data/fuzz/.
#include <catch2/catch.hpp>

#include <string>

#include "fuzz_input.h"
#include "isokit/core/error.h"
#include "isokit/skinning/animation.h"
#include "isokit/skinning/procedural.h"
#include "isokit/skinning/rig_io.h"
#include "isokit/skinning/setup.h"

using namespace isokit;
using namespace isokit::skinning;

using isokit::test::fuzz_input;

TEST_CASE("fuzz: setup numbers out of their type's range are refused", "[skinning][setup][fuzz]") {
  // {"fit":{"seed":1e300}}: nlohmann's get<uint64_t> converted it with undefined behaviour
  // (UBSan: float-cast-overflow) and the setup loaded with a garbage seed.
  const std::string text = fuzz_input("setup-float-into-integer.json");
  CHECK_THROWS_WITH(setup_from_json(text, "s.json"),
                    Catch::Contains("s.json.fit.seed") && Catch::Contains("must be an integer"));
  CHECK_THROWS_AS(setup_from_json(R"({"fit": {"samples": 1e300}})", "s.json"), InputError);
  CHECK_THROWS_AS(setup_from_json(R"({"fit": {"samples": 3000000000}})", "s.json"), InputError);
  CHECK_THROWS_AS(setup_from_json(R"({"fit": {"seed": -1}})", "s.json"), InputError);
  CHECK_THROWS_AS(setup_from_json(R"({"joints": {"a": {"relaxation": 1e300}}})", "s.json"), InputError);
  CHECK_THROWS_AS(setup_from_json(R"({"version": 1.5})", "s.json"), InputError);
  // In-range values still read.
  const SkinSetup s = setup_from_json(R"({"fit": {"seed": 18446744073709551615, "samples": 40}})", "s.json");
  CHECK(s.fit.seed == 18446744073709551615ull);
  CHECK(s.fit.target_samples == 40);
}

TEST_CASE("fuzz: a JSON number too large for a double is an InputError", "[skinning][setup][fuzz]") {
  // {"version": 1e999}: nlohmann::json::parse threw out_of_range (not parse_error), which escaped
  // setup_from_json (and the pose-script reader) as a non-InputError exception.
  const std::string text = fuzz_input("setup-number-overflow.json");
  CHECK_THROWS_AS(setup_from_json(text, "s.json"), InputError);
  CHECK_THROWS_WITH(setup_from_json(text, "s.json"), Catch::Contains("not valid JSON"));
  const Rig rig = make_cylinder();
  CHECK_THROWS_AS(pose_script_from_json(rig, text, "p.json"), InputError);
}

TEST_CASE("fuzz: glTF indices with float components are refused", "[skinning][io][fuzz]") {
  // A FLOAT indices accessor holding 1e35 was converted to unsigned with undefined behaviour
  // (UBSan: float-cast-overflow in gltf_scene.cpp); glTF allows unsigned integer indices only.
  const std::string path = std::string(ISOKIT_TEST_SOURCE_DIR) + "/data/fuzz/gltf-float-indices.gltf";
  CHECK_THROWS_WITH(load_rig(path), Catch::Contains("indices") && Catch::Contains("componentType 5126"));
}

TEST_CASE("fuzz: a clip key time far beyond any animation is refused, not sampled", "[skinning][io][fuzz]") {
  // An animation whose last key lies at 1.4e32 s made the frame count overflow an int (UBSan:
  // float-cast-overflow in rig_io_load.cpp's sample_clip, found by the 15-minute glb run) and
  // would have allocated without bound. The loader now refuses a clip of more than 10 M frames.
  const std::string path = std::string(ISOKIT_TEST_SOURCE_DIR) + "/data/fuzz/glb-clip-key-time-1e32.glb";
  CHECK_THROWS_WITH(load_rig(path), Catch::Contains("animation") && Catch::Contains("frames at") &&
                                        Catch::Contains("fix the key times"));
}

TEST_CASE("fuzz: a clip too long to sample loads at once and is refused only when sampled",
          "[skinning][io][fuzz]") {
  // Two keys about 13 hours apart (the 15-minute glb run, after 840 s: a libFuzzer timeout):
  // sampling them at 30 fps at load took 26 s and 1.8 GB before the mesh was even checked. Clips
  // now keep their keys and are sampled when a command needs the frames (clip_frames), within
  // kMaxClipSamples joint transforms.
  const std::string path = std::string(ISOKIT_TEST_SOURCE_DIR) + "/data/fuzz/glb-clip-13-hours.glb";
  LoadOptions o;
  o.skeleton_only = true;
  LoadReport report;
  const Rig clips = load_rig(path, o, &report);
  REQUIRE(clips.clips.size() == 1);
  CHECK(clips.clips[0].frame_count() > 1000000);
  CHECK(clips.clips[0].local.empty());
  bool warned = false;
  for (const auto& w : report.warnings)
    warned = warned || w.find("refuse it (sample it at a lower --fps") != std::string::npos;
  CHECK(warned);
  CHECK_THROWS_WITH(clip_frames(clips.clips[0]), Catch::Contains("clip '") && Catch::Contains("lower --fps"));
  CHECK_THROWS_AS(load_rig(path), InputError);  // its mesh has no triangles
}

TEST_CASE("fuzz: an accessor count its buffer view does not hold is refused before allocating",
          "[skinning][io][fuzz]") {
  // The one-hour gltf run, at 662 s: inverseBindMatrices claims 333,333,332 MAT4 over a 128-byte
  // view; the reader allocated 42.6 GB of doubles before checking the view (std::bad_alloc).
  const std::string path = std::string(ISOKIT_TEST_SOURCE_DIR) + "/data/fuzz/gltf-accessor-count-42GB.gltf";
  CHECK_THROWS_WITH(load_rig(path), Catch::Contains("inverseBindMatrices (accessor 5)") &&
                                        Catch::Contains("declares 333333332 elements of 64 bytes") &&
                                        Catch::Contains("holds 128 bytes"));
}

TEST_CASE("fuzz: a valid clip of 14 hours is listed without sampling, and sampled on demand within the bound",
          "[skinning][io][fuzz]") {
  // The one-hour glb run, at 1,794 s: a 3.5 KB file whose clip spans 14 hours was resampled at
  // load into 1,545,762 frames (463 MB, 2.2 s for `info`).
  const std::string path = std::string(ISOKIT_TEST_SOURCE_DIR) + "/data/fuzz/glb-clip-1.5M-frames.glb";
  const Rig rig = load_rig(path);
  REQUIRE(rig.clips.size() == 1);
  CHECK(rig.clips[0].frame_count() == 1545762);
  CHECK(rig.clips[0].seconds() == Approx(1545761.0 / 30));
  // 1.5 M frames x 2 joints is within 2^22 transforms: sampled at a lower rate it is small.
  Clip slow = rig.clips[0];
  slow.fps = 0.01;
  const auto frames = clip_frames(slow);
  CHECK(frames.size() == slow.frame_count());
  for (const auto& pose : frames) CHECK(pose.size() == rig.joints.size());
}
