// SPDX-License-Identifier: MIT
// The cost of the per-frame skin metrics (docs/performance.md, "Interpenetration volume"): the
// volume enclosed twice (self_overlap.h, 160 cells across the largest side) against the exact
// self-intersection count, on the procedural humanoid posed by DQS with its left elbow and knee at
// 150° (where DQS folds into itself), at about 10k and 26k triangles, serial and on every core.
#include <benchmark/benchmark.h>

#include <map>

#include "isokit/skinning/animation.h"
#include "isokit/skinning/deform.h"
#include "isokit/skinning/metrics.h"
#include "isokit/skinning/procedural.h"
#include "isokit/skinning/self_overlap.h"

namespace {

using namespace isokit::skinning;

struct Posed {
  Rig rig;
  isokit::track::Positions dqs;
};

/// The humanoid of about `vertices` vertices, bent by DQS (built once per size).
const Posed& posed(int vertices) {
  static std::map<int, Posed> cache;
  auto it = cache.find(vertices);
  if (it != cache.end()) return it->second;
  Posed p{make_humanoid({vertices, true}), {}};
  const std::vector<Pose> poses =
      bend_animation(p.rig, {parse_bend("LeftForeArm:x:150", p.rig), parse_bend("LeftLeg:x:150", p.rig)}, 3);
  dual_quaternion_blend(p.rig.weights, skinning_matrices(p.rig, poses[1]), p.rig.rest, p.dqs, nullptr, 1024);
  return cache.emplace(vertices, std::move(p)).first->second;
}

void label(benchmark::State& state, const Posed& p) {
  state.SetLabel(std::to_string(p.rig.triangles.rows()) + " triangles" + (state.range(1) ? "" : ", serial"));
}

void BM_SelfOverlap(benchmark::State& state) {
  const Posed& p = posed(static_cast<int>(state.range(0)));
  SelfOverlapOptions o;
  o.grain = state.range(1) ? o.grain : 0;
  double overlap = 0;
  for (auto _ : state) overlap = self_overlap(p.dqs, p.rig.triangles, o).overlap;
  state.counters["overlap"] = overlap;
  label(state, p);
}

void BM_SelfIntersections(benchmark::State& state) {
  const Posed& p = posed(static_cast<int>(state.range(0)));
  SelfIntersectionOptions o;
  o.grain = state.range(1) ? o.grain : 0;
  int pairs = 0;
  for (auto _ : state) pairs = count_self_intersections(p.dqs, p.rig.triangles, nullptr, o);
  state.counters["pairs"] = pairs;
  label(state, p);
}

// Args: humanoid vertices (5000 gives ~10k triangles), parallel (0 serial, 1 every core).
BENCHMARK(BM_SelfOverlap)->ArgsProduct({{5000, 13000}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SelfIntersections)
    ->ArgsProduct({{5000, 13000}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
