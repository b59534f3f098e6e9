// SPDX-License-Identifier: MIT
// The geometric methods' cost (issue 43; docs/performance.md, "Geometric skinning"):
// - BM_GeometricFrame: per-frame time of lbs, dqs, ddm and cor on the procedural humanoid (46
//   joints) with its left elbow and knee bent 0 -> 150 -> 0 degrees in 9 frames, after the
//   precomputation (the bake's setup), on the machine's cores (parallel_for, grain 1024).
//   Manual time = mean deformation time per frame.
// - BM_DdmPrecompute / BM_CorPrecompute: the precomputation of a rig: the humanoid without
//   fingers at ~6k vertices (22 joints) solved for 24 bones (two more, empty, so the solve count
//   is that of a 24-bone rig), and the same humanoid with fingers (46 joints).
#include <benchmark/benchmark.h>

#include <map>
#include <memory>

#include "isokit/skinning/animation.h"
#include "isokit/skinning/cor.h"
#include "isokit/skinning/ddm.h"
#include "isokit/skinning/pipeline.h"
#include "isokit/skinning/procedural.h"

namespace {

using namespace isokit::skinning;

const Rig& humanoid(int vertices, bool fingers) {
  static std::map<std::pair<int, bool>, Rig> rigs;
  auto it = rigs.find({vertices, fingers});
  if (it == rigs.end())
    it = rigs.emplace(std::make_pair(vertices, fingers), make_humanoid({vertices, fingers})).first;
  return it->second;
}

void BM_GeometricFrame(benchmark::State& state) {
  const Method method = all_methods()[static_cast<std::size_t>(state.range(0))];
  static std::unique_ptr<Skinner> sk;
  if (!sk) sk = std::make_unique<Skinner>(humanoid(13000, true));
  const std::vector<Pose> poses = bend_animation(
      sk->rig(), {parse_bend("LeftForeArm:x:150", sk->rig()), parse_bend("LeftLeg:x:150", sk->rig())}, 9);
  BakeOptions o;
  o.metrics = false;
  (void)sk->bake(method, poses, o);  // the precomputation (cached in the process) and a warm-up
  for (auto _ : state) state.SetIterationTime(sk->bake(method, poses, o).mean_ms * 1e-3);
  state.SetLabel(std::string(to_string(method)) + " " + std::to_string(sk->rig().rest.rows()) + " vertices");
}
// Args: method index in all_methods() (0 lbs, 1 dqs, 4 ddm, 5 cor).
BENCHMARK(BM_GeometricFrame)
    ->Arg(0)
    ->Arg(1)
    ->Arg(4)
    ->Arg(5)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(20)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);

void BM_DdmPrecompute(benchmark::State& state) {
  const bool fingers = state.range(0) != 0;
  const Rig& rig = humanoid(6000, fingers);
  const int bones = fingers ? static_cast<int>(rig.joints.size()) : 24;
  std::size_t pairs = 0;
  for (auto _ : state) {
    const DirectDeltaMush ddm(rig.rest, rig.triangles, rig.weights, bones);
    state.SetIterationTime(ddm.precompute_seconds());
    pairs = ddm.stored_pairs();
  }
  state.counters["bones_per_vertex"] = double(pairs) / double(rig.rest.rows());
  state.SetLabel(std::to_string(rig.rest.rows()) + " vertices, " + std::to_string(bones) + " bones");
}
BENCHMARK(BM_DdmPrecompute)
    ->Arg(0)
    ->Arg(1)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);

void BM_CorPrecompute(benchmark::State& state) {
  const Rig& rig = humanoid(static_cast<int>(state.range(0)), true);
  for (auto _ : state) {
    const CorSkinning cor(rig.rest, rig.triangles, rig.weights);
    state.SetIterationTime(cor.precompute_seconds());
  }
  state.SetLabel(std::to_string(rig.rest.rows()) + " vertices, " + std::to_string(rig.joints.size()) +
                 " joints");
}
BENCHMARK(BM_CorPrecompute)
    ->Arg(6000)
    ->Arg(13000)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(3)
    ->ReportAggregatesOnly(true);

}  // namespace

BENCHMARK_MAIN();
