// SPDX-License-Identifier: MIT
// The bake as the CLI runs it, step by step (bake_job.h): animation requests, fit warnings, the
// peak frame, the written result, the outputs.
#include <catch2/catch.hpp>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "isokit/core/error.h"
#include "isokit/skinning/bake_job.h"
#include "isokit/skinning/rig_io.h"
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

TEST_CASE("bake job: no animation option plays the rig's only clip, several are listed",
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

TEST_CASE("bake job: fit warnings name under-resolved parts, outputs are written where asked",
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
  BakeOutputs out{(dir / "a" / "x.glb").string(), (dir / "m.json").string(), "", (dir / "ply").string(), ""};
  const ReportContext ctx{"test", 30, 1, 0, std::nullopt};
  const std::vector<std::string> written = write_bake_outputs(sk.rig(), results, results[0], ctx, {}, out);
  CHECK(written.size() == 3);
  CHECK(fs::file_size(out.glb) > 0);
  CHECK(fs::file_size(out.metrics) > 0);
  CHECK(fs::exists(dir / "ply" / "frame_0002.ply"));
  fs::remove_all(dir);
}

TEST_CASE("bake job: --device names cpu or cuda, cuda is refused with its reason", "[skinning][bake_job]") {
  CHECK(device_from_string("cpu") == Device::kCpu);
  CHECK(device_from_string("cuda") == Device::kCuda);
  CHECK_THROWS_WITH(device_from_string("gpu"), Catch::Contains("use cpu or cuda"));
  CHECK_NOTHROW(check_device(Device::kCpu));
  // No device tracker exists yet: without a CUDA build, without a device, or with one, the reason
  // is named and the fix is --device cpu.
  CHECK_THROWS_WITH(check_device(Device::kCuda),
                    Catch::Contains("--device cuda: ") && Catch::Contains("use --device cpu"));
}

namespace {

/// A PC2 point cache as read back: its header fields and positions[sample][point * 3 + axis].
struct Pc2 {
  std::string signature;
  std::int32_t version{0}, points{0}, samples{0};
  float start{0}, rate{0};
  std::vector<std::vector<float>> positions;
};

// Little-endian reads of the header and the samples (independent of the writer's code).
Pc2 read_pc2(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::vector<unsigned char> b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  REQUIRE(b.size() >= 32);
  auto u32 = [&](std::size_t at) {
    return static_cast<std::uint32_t>(b[at]) | static_cast<std::uint32_t>(b[at + 1]) << 8 |
           static_cast<std::uint32_t>(b[at + 2]) << 16 | static_cast<std::uint32_t>(b[at + 3]) << 24;
  };
  auto f32 = [&](std::size_t at) {
    const std::uint32_t u = u32(at);
    float x;
    std::memcpy(&x, &u, 4);
    return x;
  };
  Pc2 pc;
  pc.signature.assign(b.begin(), b.begin() + 12);
  pc.version = static_cast<std::int32_t>(u32(12));
  pc.points = static_cast<std::int32_t>(u32(16));
  pc.start = f32(20);
  pc.rate = f32(24);
  pc.samples = static_cast<std::int32_t>(u32(28));
  REQUIRE(b.size() == 32 + 12 * static_cast<std::size_t>(pc.points) * static_cast<std::size_t>(pc.samples));
  for (std::int32_t s = 0; s < pc.samples; ++s) {
    std::vector<float> p(3 * static_cast<std::size_t>(pc.points));
    for (std::size_t i = 0; i < p.size(); ++i)
      p[i] = f32(32 + 4 * (static_cast<std::size_t>(s) * p.size() + i));
    pc.positions.push_back(p);
  }
  return pc;
}

/// The capsule with an output mesh unlike its welded one: output vertices in reverse order, then
/// a second copy of the first 10 welded vertices (split normals), as a loaded file has.
Rig reordered_capsule() {
  Rig r = testing::capsule_rig(8, 8, 2);
  const int n = static_cast<int>(r.rest.rows());
  for (int i = 0; i < n; ++i) r.output.to_welded.push_back(n - 1 - i);
  for (int i = 0; i < 10; ++i) r.output.to_welded.push_back(i);
  r.output.triangles = r.triangles;
  for (Eigen::Index f = 0; f < r.triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k) r.output.triangles(f, k) = n - 1 - r.triangles(f, k);
  r.output.primitive_offsets = {0, static_cast<int>(r.triangles.rows())};
  validate(r);
  return r;
}

}  // namespace

TEST_CASE("bake job: --pc2 writes the baked positions in the file's vertex order", "[skinning][bake_job]") {
  Skinner sk(reordered_capsule(), SkinSetup{});
  const Rig& rig = sk.rig();
  const std::vector<Pose> poses = bend_animation(rig, {parse_bend("Bone1:z:60", rig)}, 5);
  BakeOptions o;
  o.self_intersections = false;
  const std::vector<BakeResult> results{sk.bake(Method::kDqs, poses, o)};
  const fs::path dir = fs::temp_directory_path() / "isokit-test-bake-pc2";
  fs::remove_all(dir);
  BakeOutputs out;
  out.pc2 = (dir / "sub" / "bend.pc2").string();
  const ReportContext ctx{"test", 30, 1, 0, std::nullopt};
  const std::vector<std::string> written = write_bake_outputs(rig, results, results[0], ctx, {}, out);
  REQUIRE(written.size() == 1);
  CHECK(written[0] == out.pc2 + " (5 frames)");

  const Pc2 pc = read_pc2(out.pc2);
  CHECK(pc.signature == std::string("POINTCACHE2\0", 12));
  CHECK(pc.version == 1);
  CHECK(pc.points == static_cast<std::int32_t>(rig.output.to_welded.size()));
  CHECK(pc.start == 0.0f);
  CHECK(pc.rate == 1.0f);
  REQUIRE(pc.samples == 5);
  bool equal = true;
  for (std::size_t k = 0; k < 5; ++k)
    for (std::size_t i = 0; i < rig.output.to_welded.size(); ++i)
      for (int c = 0; c < 3; ++c)
        equal = equal && pc.positions[k][3 * i + static_cast<std::size_t>(c)] ==
                             results[0].frames[k](rig.output.to_welded[i], c);
  CHECK(equal);
  CHECK(results[0].frames[2] != results[0].frames[0]);  // the bend moved the mesh

  // Bad paths: one line naming the path and the fix, and no file written.
  auto error_of = [&](const std::string& path) {
    BakeOutputs bad;
    bad.pc2 = path;
    try {
      write_bake_outputs(rig, results, results[0], ctx, {}, bad);
    } catch (const isokit::InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::ofstream(dir / "file") << "x";
  fs::create_directories(dir / "folder.pc2");
  const std::string wrong_ext = error_of((dir / "bend.txt").string());
  const std::string folder = error_of((dir / "folder.pc2").string());
  const std::string under_file = error_of((dir / "file" / "bend.pc2").string());
  CHECK_THAT(wrong_ext, Catch::Contains("bend.txt") && Catch::Contains("extension must be .pc2"));
  CHECK_THAT(folder, Catch::Contains("is a folder"));
  CHECK_THAT(under_file, Catch::Contains("cannot create the folder"));
  for (const std::string& e : {wrong_ext, folder, under_file}) CHECK(e.find('\n') == std::string::npos);
  CHECK_FALSE(fs::exists(dir / "bend.txt"));
  CHECK(fs::is_empty(dir / "folder.pc2"));
  fs::remove_all(dir);
}
