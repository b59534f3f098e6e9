// SPDX-License-Identifier: MIT
// The whole fit of a rig (QUALITY.md "Preprocessing": every part's field, the partition, the
// retries and fallbacks — FittedRig), per rig and per field kind: `hrbf` (2013 §4.1) and
// `distance` (the part's own closed surface; docs/decisions/part-fields-from-the-mesh.md). Rigs:
// every .glb / .gltf / .fbx of ISOKIT_RIGS (default ../shared/data/rigs) and ../shared/data/Fox.glb
// when they exist, and the procedural humanoid (13k vertices) always. Manual time = the fit's
// wall time (loading excluded); counters: fitted joints, and the largest grid resolution.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "bench_rigs.h"
#include "isokit/skinning/fitted_rig.h"
#include "isokit/skinning/pipeline.h"
#include "isokit/skinning/procedural.h"

namespace {

using namespace isokit::skinning;
namespace fs = std::filesystem;

std::vector<std::string> rig_specs() {
  std::vector<std::string> out{"procedural:humanoid"};
  const std::vector<std::string> files = isokit::bench::real_rig_files();
  out.insert(out.end(), files.begin(), files.end());
  return out;
}

void BM_FitRig(benchmark::State& state, const std::string& spec,
               isokit::implicit::PartFitOptions::FieldKind kind) {
  Rig rig;
  try {
    rig = spec == "procedural:humanoid" ? make_humanoid({13000, true}) : open_rig(spec);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  SkinSetup setup;
  setup.fit.field = kind;
  int fitted = 0, resolution = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const FittedRig f(rig, setup);
    state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    fitted = f.fitted_count();
    for (const BonePart& b : f.bones())
      if (b.fitted && b.fit.grid) resolution = std::max(resolution, b.fit.grid->resolution());
  }
  state.counters["fitted_joints"] = fitted;
  state.counters["max_grid_resolution"] = resolution;
}

}  // namespace

int main(int argc, char** argv) {
  using Kind = isokit::implicit::PartFitOptions::FieldKind;
  for (const std::string& spec : rig_specs()) {
    const std::string name = fs::path(spec).stem().string();
    for (const auto& [kind, label] : {std::pair{Kind::hrbf, "hrbf"}, std::pair{Kind::distance, "distance"}})
      benchmark::RegisterBenchmark(("BM_FitRig/" + name + "/" + label).c_str(),
                                   [spec, kind = kind](benchmark::State& s) { BM_FitRig(s, spec, kind); })
          ->UseManualTime()
          ->Unit(benchmark::kMillisecond)
          ->Iterations(1);
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
