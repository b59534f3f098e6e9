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

TEST_CASE("fuzz: a clip too long to sample is skipped with a warning, quickly", "[skinning][io][fuzz]") {
  // Two keys about 13 hours apart (the 15-minute glb run, after 840 s: a libFuzzer timeout):
  // sampling them at 30 fps took 26 s and 1.8 GB before the mesh was even checked. A clip of more
  // than 2^22 joint transforms is now skipped with a warning naming it.
  const std::string path = std::string(ISOKIT_TEST_SOURCE_DIR) + "/data/fuzz/glb-clip-13-hours.glb";
  LoadOptions o;
  o.skeleton_only = true;
  LoadReport report;
  std::string error;
  try {
    load_rig(path, o, &report);
  } catch (const InputError& e) {
    error = e.what();
  }
  bool skipped = false;
  for (const auto& w : report.warnings)
    skipped = skipped || w.find("skipped (sample it at a lower --fps") != std::string::npos;
  CHECK(skipped);
  // Its only clip skipped, the clip-file read has nothing to play.
  CHECK_THAT(error, Catch::Contains("has no animation that moves its skeleton"));
  CHECK_THROWS_AS(load_rig(path), InputError);  // its mesh has no triangles
}
