// SPDX-License-Identifier: MIT
// assimp in a child process (LoadOptions::isolate_importer, io/isolated.h): the same rig as in
// process, and assimp's aborts, crashes, hangs and runaway allocations on the fuzzing findings
// of docs/fuzzing.md end as InputErrors naming the file.
#include <catch2/catch.hpp>

#include <assimp/scene.h>
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <random>
#include <stdexcept>
#include <thread>

#include "io/isolated.h"
#include "isokit/core/error.h"
#include "isokit/skinning/procedural.h"
#include "isokit/skinning/rig_io.h"

using namespace isokit;
using namespace isokit::skinning;
namespace fs = std::filesystem;

namespace {

struct ScratchDir {
  fs::path path;
  ScratchDir() {
    std::random_device rd;
    path = fs::temp_directory_path() / ("isokit_isolated_" + std::to_string(rd()));
    fs::create_directories(path);
  }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string file(const std::string& name) const { return (path / name).string(); }
};

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

/// The cylinder (with a two-frame clip if `clip`), as glTF, then as `format` through assimp's
/// exporter. (assimp 5.2 cannot read back the animation of its own COLLADA export.)
std::string exported_rig(const ScratchDir& dir, const char* format, const char* ext, bool with_clip) {
  Rig rig = make_cylinder();
  Clip clip;
  clip.name = "bend";
  clip.local = {rest_pose(rig), rest_pose(rig)};
  clip.local[1].back() = clip.local[1].back() * Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitX());
  if (with_clip) rig.clips.push_back(clip);
  save_rig(rig, dir.file("rig.glb"));
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(dir.file("rig.glb"), 0);
  REQUIRE(scene != nullptr);
  Assimp::Exporter exporter;
  const std::string out = dir.file(std::string("rig.") + ext);
  REQUIRE(exporter.Export(scene, format, out) == AI_SUCCESS);
  return out;
}

bool same_affines(const std::vector<Affine>& a, const std::vector<Affine>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].matrix() != b[i].matrix()) return false;
  return true;
}

void check_same_rig(const Rig& a, const LoadReport& ra, const Rig& b, const LoadReport& rb) {
  CHECK(a.name == b.name);
  CHECK(a.rest == b.rest);
  CHECK(a.triangles == b.triangles);
  CHECK(a.weights.offsets == b.weights.offsets);
  CHECK(a.weights.joints == b.weights.joints);
  CHECK(a.weights.weights == b.weights.weights);
  REQUIRE(a.joints.size() == b.joints.size());
  for (std::size_t j = 0; j < a.joints.size(); ++j) {
    CHECK(a.joints[j].name == b.joints[j].name);
    CHECK(a.joints[j].file_name == b.joints[j].file_name);
    CHECK(a.joints[j].parent == b.joints[j].parent);
    CHECK(a.joints[j].rest_local.matrix() == b.joints[j].rest_local.matrix());
    CHECK(a.joints[j].inverse_bind.matrix() == b.joints[j].inverse_bind.matrix());
  }
  REQUIRE(a.clips.size() == b.clips.size());
  for (std::size_t c = 0; c < a.clips.size(); ++c) {
    CHECK(a.clips[c].name == b.clips[c].name);
    CHECK(a.clips[c].fps == b.clips[c].fps);
    CHECK((a.clips[c].keys == nullptr) == (b.clips[c].keys == nullptr));
    const auto fa = clip_frames(a.clips[c]);
    const auto fb = clip_frames(b.clips[c]);
    REQUIRE(fa.size() == fb.size());
    for (std::size_t f = 0; f < fa.size(); ++f) CHECK(same_affines(fa[f], fb[f]));
  }
  CHECK(a.output.to_welded == b.output.to_welded);
  CHECK(a.output.triangles == b.output.triangles);
  CHECK(a.output.primitive_offsets == b.output.primitive_offsets);
  CHECK(ra.format == rb.format);
  CHECK(ra.meshes == rb.meshes);
  CHECK(ra.file_vertices == rb.file_vertices);
  CHECK(ra.welded_vertices == rb.welded_vertices);
  CHECK(ra.max_influences == rb.max_influences);
  CHECK(ra.dropped_triangles == rb.dropped_triangles);
  CHECK(ra.weights_from_file == rb.weights_from_file);
  CHECK(ra.warnings == rb.warnings);
}

}  // namespace

TEST_CASE("rig_load: FBX and COLLADA read in a child process give the rig read in process, bit for bit",
          "[skinning][io][isolated]") {
  if (!io::isolation_available()) return;
  ScratchDir dir;
  for (const auto& [format, ext] : {std::pair{"collada", "dae"}, std::pair{"fbxa", "fbx"}}) {
    INFO(format);
    const bool with_clip = std::string(ext) == "fbx";
    const std::string path = exported_rig(dir, format, ext, with_clip);
    LoadOptions in_process;
    in_process.isolate_importer = false;
    LoadReport ra, rb;
    const Rig a = load_rig(path, in_process, &ra);
    const Rig b = load_rig(path, LoadOptions{}, &rb);
    CHECK(a.rest.rows() > 100);
    CHECK(a.clips.size() == (with_clip ? 1u : 0u));
    check_same_rig(a, ra, b, rb);
    // The skeleton-only read (clip files) too.
    in_process.skeleton_only = true;
    LoadOptions skeleton;
    skeleton.skeleton_only = true;
    if (with_clip)
      check_same_rig(load_rig(path, in_process, &ra), ra, load_rig(path, skeleton, &rb), rb);
    else  // no clip: the same InputError both ways
      CHECK(error_of([&] { load_rig(path, skeleton); }) == error_of([&] { load_rig(path, in_process); }));
  }
  // An InputError of the child (here: a garbage file) comes back with the same message.
  const std::string garbage = dir.file("garbage.dae");
  std::FILE* f = std::fopen(garbage.c_str(), "wb");
  std::fputs("<COLLADA> not really </COLLADA>", f);
  std::fclose(f);
  LoadOptions in_process;
  in_process.isolate_importer = false;
  const std::string expected = error_of([&] { load_rig(garbage, in_process); });
  CHECK(expected.find(garbage) != std::string::npos);
  CHECK(error_of([&] { load_rig(garbage); }) == expected);
}

TEST_CASE(
    "rig_load: assimp's aborts, crashes, hangs and runaway allocations end as InputErrors (fuzzing findings)",
    "[skinning][io][isolated][fuzz]") {
  if (!io::isolation_available()) return;
  // Found by the fbx and dae fuzz targets (docs/fuzzing.md, findings 6-9): each ended the whole
  // process inside assimp 5.2.5 (ai_assert abort, null dereference, > 4 GB, > 10 s).
  LoadOptions o;
  o.importer_timeout_seconds = 4;
  o.importer_memory_mib = 512;
  const std::string dir = std::string(ISOKIT_TEST_SOURCE_DIR) + "/data/fuzz/assimp/";
  for (const char* name : {"fbx-assimp-ai-assert.fbx", "dae-assimp-ai-assert.dae", "dae-assimp-segv.dae",
                           "dae-assimp-4gb.dae", "dae-assimp-slow.dae"}) {
    INFO(name);
    const std::string path = dir + name;
    const auto t0 = std::chrono::steady_clock::now();
    const std::string msg = error_of([&] { load_rig(path, o); });
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    CHECK(msg.rfind(path + ":", 0) == 0);
    CHECK(msg.find("assimp") != std::string::npos);
    CHECK(s < o.importer_timeout_seconds + 2.0);
  }
}

TEST_CASE("run_isolated: the child's result, its InputError, and how it ended", "[skinning][io][isolated]") {
  if (!io::isolation_available()) return;
  const io::IsolationLimits limits{5, 0};
  CHECK(io::run_isolated([] { return std::string("abc\0def", 7); }, limits, "w", "fix") ==
        std::string("abc\0def", 7));
  CHECK(io::run_isolated([] { return std::string(); }, limits, "w", "fix").empty());
  const std::string big(3 << 20, 'x');  // larger than a pipe's buffer
  CHECK(io::run_isolated([&] { return big; }, limits, "w", "fix") == big);
  auto msg = [&](const std::function<std::string()>& work, const io::IsolationLimits& l) {
    return error_of([&] { io::run_isolated(work, l, "WORK", "FIX"); });
  };
  CHECK(msg([]() -> std::string { throw InputError("file.x: bad thing; do this"); }, limits) ==
        "file.x: bad thing; do this");
  CHECK_THAT(msg([]() -> std::string { throw std::runtime_error("boom"); }, limits),
             Catch::StartsWith("WORK failed: boom") && Catch::EndsWith("FIX"));
  CHECK_THAT(
      msg(
          []() -> std::string {
            std::fputs("some noise\nassertion X failed\n", stderr);
            std::abort();
          },
          limits),
      Catch::StartsWith("WORK aborted") && Catch::Contains("[assertion X failed]") && Catch::EndsWith("FIX"));
  CHECK_THAT(msg(
                 []() -> std::string {
                   std::raise(SIGSEGV);
                   return "";
                 },
                 limits),
             Catch::StartsWith("WORK crashed (signal " + std::to_string(SIGSEGV)));
  const auto t0 = std::chrono::steady_clock::now();
  CHECK_THAT(msg(
                 []() -> std::string {
                   std::this_thread::sleep_for(std::chrono::seconds(30));
                   return "";
                 },
                 {0.5, 0}),
             Catch::StartsWith("WORK took longer than 0.5 s"));
  CHECK(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < 5.0);
  CHECK_THROWS_AS(io::run_isolated([] { return std::string(); }, {0, 0}, "w", "fix"), InputError);
}
