// SPDX-License-Identifier: MIT
// Rig loading (docs/fuzzing.md, finding 7): FBX and COLLADA read by assimp in a child process
// (LoadOptions::isolate_importer, the default) against in process. The files are the procedural
// humanoid (13k vertices, 46 joints, a 31-frame bend clip) saved as glTF and exported by assimp as
// ASCII FBX and COLLADA (the clip only in the FBX: assimp 5.2 cannot read back its own COLLADA
// animation). Arg 0: format (0 FBX, 1 COLLADA); arg 1: isolated (1) or in process (0).
#include <benchmark/benchmark.h>

#include <assimp/scene.h>
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "isokit/skinning/animation.h"
#include "isokit/skinning/procedural.h"
#include "isokit/skinning/rig_io.h"

namespace {

using namespace isokit::skinning;
namespace fs = std::filesystem;

std::string exported(const char* format, const char* ext, bool with_clip) {
  const fs::path dir = fs::temp_directory_path() / "isokit_bench_io";
  fs::create_directories(dir);
  const fs::path out = dir / (std::string("humanoid.") + ext);
  if (fs::exists(out)) return out.string();
  Rig rig = make_humanoid();
  if (with_clip) {
    Clip clip;
    clip.name = "bend";
    clip.local = bend_animation(rig, {parse_bend("LeftForeArm:x:150", rig)}, 31);
    rig.clips.push_back(clip);
  }
  const fs::path glb = dir / "humanoid.glb";
  save_rig(rig, glb.string());
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(glb.string(), 0);
  Assimp::Exporter exporter;
  if (scene == nullptr || exporter.Export(scene, format, out.string()) != AI_SUCCESS)
    throw std::runtime_error("assimp could not export " + out.string());
  return out.string();
}

void BM_LoadRig(benchmark::State& state) {
  const bool fbx = state.range(0) == 0;
  static const std::string fbx_path = exported("fbxa", "fbx", true);
  static const std::string dae_path = exported("collada", "dae", false);
  LoadOptions o;
  o.isolate_importer = state.range(1) != 0;
  for (auto _ : state) benchmark::DoNotOptimize(load_rig(fbx ? fbx_path : dae_path, o));
  state.SetLabel(std::string(fbx ? "fbx" : "dae") + (o.isolate_importer ? " isolated" : " in process"));
}

}  // namespace

BENCHMARK(BM_LoadRig)->ArgsProduct({{0, 1}, {0, 1}})->Unit(benchmark::kMillisecond)->MinTime(2.0);

BENCHMARK_MAIN();
