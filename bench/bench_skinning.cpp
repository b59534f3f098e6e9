// SPDX-License-Identifier: MIT
// isokit-skin per-frame cost (QUALITY.md "Speed"): the procedural humanoid (46 joints) with its
// left elbow and knee bent 0 -> 150 -> 0 degrees in 9 frames, per method, at several vertex
// counts and tracking sub-step sizes (--max-step-rad). Manual time = mean deformation time per
// frame (metrics excluded); counters: tracker iterations per frame, sub-steps per frame,
// vertex updates (tracker active-set sizes summed over iterations) per frame and per second. The ratio to dqs
// is printed by isokit-bench-report.
#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <memory>
#include <tuple>

#include "isokit/core/math.h"
#include "isokit/skinning/animation.h"
#include "isokit/skinning/pipeline.h"
#include "isokit/skinning/procedural.h"

namespace {

using namespace isokit::skinning;

Skinner& skinner(int vertices, double step, bool energy = false) {
  // The humanoid is polygonised once per vertex count (~50 s CPU at 170k); each sub-step size
  // gets its own Skinner (fit + trees, well under a second).
  static std::map<int, Rig> rigs;
  static std::map<std::tuple<int, double, bool>, std::unique_ptr<Skinner>> cache;
  auto& s = cache[{vertices, step, energy}];
  if (!s) {
    auto it = rigs.find(vertices);
    if (it == rigs.end()) it = rigs.emplace(vertices, make_humanoid({vertices, true})).first;
    SkinSetup setup;
    setup.substeps.max_step_rad = step;
    if (energy) setup.tracker.relaxation = isokit::track::Relaxation::kEnergy;
    s = std::make_unique<Skinner>(it->second, setup);
  }
  return *s;
}

/// Bakes `poses` once per benchmark iteration (metrics off); manual time = mean ms per frame;
/// counters per frame: tracker iterations, sub-steps, vertex updates, field evaluations, and
/// updates per second.
void bake_and_count(benchmark::State& state, Skinner& sk, Method method, const std::vector<Pose>& poses) {
  BakeOptions o;
  o.metrics = false;
  double iterations = 0, substeps = 0, updates = 0, evaluations = 0, vips = 0;
  for (auto _ : state) {
    const BakeResult r = sk.bake(method, poses, o);
    state.SetIterationTime(r.mean_ms * 1e-3);
    for (const FrameStats& s : r.stats) {
      iterations += s.iterations;
      substeps += s.substeps;
      updates += s.vertex_updates;
      evaluations += s.field_evaluations;
    }
    vips = r.vertex_iterations_per_second;
  }
  const double frames = double(state.iterations()) * double(poses.size());
  state.counters["iterations_per_frame"] = iterations / frames;
  state.counters["substeps_per_frame"] = substeps / frames;
  state.counters["vertex_updates_per_frame"] = updates / frames;
  state.counters["field_evaluations_per_frame"] = evaluations / frames;
  state.counters["vertex_updates_per_s"] = vips;
}

void BM_SkinFrame(benchmark::State& state) {
  const Method method = all_methods()[static_cast<std::size_t>(state.range(0))];
  const int vertices = static_cast<int>(state.range(1));
  const double step = double(state.range(2)) / 1000.0;
  Skinner& sk = skinner(vertices, step);
  const std::vector<Pose> poses = bend_animation(
      sk.rig(), {parse_bend("LeftForeArm:x:150", sk.rig()), parse_bend("LeftLeg:x:150", sk.rig())}, 9);
  bake_and_count(state, sk, method, poses);
  state.SetLabel(std::string(to_string(method)) + " " + std::to_string(sk.rig().rest.rows()) + " vertices, " +
                 (step > 0 ? "step " + std::to_string(step).substr(0, 5) + " rad" : "paper rule"));
}

// Args: method (0 lbs, 1 dqs, 2 implicit2013, 3 tracking2014), vertices, step in milliradians
// (issue 6: every method at ~13k, ~31k and ~170k vertices; tracking2014 at 0.5, 0.05 and
// 0.005 rad).
void args(benchmark::internal::Benchmark* b) {
  for (int v : {13000, 31000, 170000}) {
    for (int m = 0; m < 4; ++m) b->Args({m, v, 50});
    for (int step : {500, 5}) b->Args({3, v, step});
  }
}
BENCHMARK(BM_SkinFrame)->Apply(args)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(1);

// tracking2014 with the energy solve (tracker.relaxation "energy", docs/tracking.md "The energy
// solve") on BM_SkinFrame's bend, beside BM_SkinFrame/1/13000/50 (dqs) in the same run.
// Args: vertices, step in milliradians.
void BM_SkinFrameEnergy(benchmark::State& state) {
  const int vertices = static_cast<int>(state.range(0));
  const double step = double(state.range(1)) / 1000.0;
  Skinner& sk = skinner(vertices, step, true);
  const std::vector<Pose> poses = bend_animation(
      sk.rig(), {parse_bend("LeftForeArm:x:150", sk.rig()), parse_bend("LeftLeg:x:150", sk.rig())}, 9);
  bake_and_count(state, sk, Method::kTracking2014, poses);
  state.SetLabel("tracking2014 energy " + std::to_string(sk.rig().rest.rows()) + " vertices, step " +
                 std::to_string(step).substr(0, 5) + " rad");
}
BENCHMARK(BM_SkinFrameEnergy)
    ->Args({13000, 50})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

// The 2014 paper's Table 1 protocol ("all joints are animated simultaneously"; time step =
// radians per animation step): spine, neck, head, shoulders, elbows, wrists, fingers, hips,
// knees and ankles bend together from rest to a full-body pose and back, with every joint
// turning by at most `step` between two frames (frames = 2 ceil(90° / step) + 1), sub-stepped
// by the library's default rule (2014 §5.2): `crouch_bends`. Manual time = mean deformation
// time per frame.
void BM_SkinStep(benchmark::State& state) {
  const Method method = all_methods()[static_cast<std::size_t>(state.range(0))];
  const int vertices = static_cast<int>(state.range(1));
  const double step = double(state.range(2)) / 1000.0;
  Skinner& sk = skinner(vertices, 0.0);               // library defaults: the paper's sub-step rule only
  const double max_rad = 90.0 * isokit::kPi / 180.0;  // the largest bend of crouch_bends
  const int frames = 2 * static_cast<int>(std::ceil(max_rad / step - 1e-9)) + 1;
  const std::vector<BendSpec> bends = crouch_bends(sk.rig());
  const std::vector<Pose> poses = bend_animation(sk.rig(), bends, frames);
  bake_and_count(state, sk, method, poses);
  state.counters["bent_joints"] = double(bends.size());
  state.SetLabel(std::string(to_string(method)) + " " + std::to_string(sk.rig().rest.rows()) +
                 " vertices, Table 1 protocol, time step " + std::to_string(step).substr(0, 5) + " rad, " +
                 std::to_string(frames) + " frames");
}

// Args: method, vertices, time step in milliradians (2014 Table 1: 0.5, 0.05, 0.005 rad).
void step_args(benchmark::internal::Benchmark* b) {
  for (int v : {13000, 31000, 170000}) {
    b->Args({1, v, 50});
    for (int step : {500, 50, 5}) b->Args({3, v, step});
  }
}
BENCHMARK(BM_SkinStep)->Apply(step_args)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
