// SPDX-License-Identifier: MIT
// The 2013 projector on real rigs (docs/performance.md, "implicit2013 per frame"): every .glb /
// .gltf / .fbx of ISOKIT_RIGS (default ../shared/data/rigs) and ../shared/data/Fox.glb when they
// exist, the first ISOKIT_BENCH_FRAMES (default 30) frames of each rig's first clip.
//  - BM_Implicit2013/<rig>/<rules>: the bake per frame (metrics off), with isokit's stopping rules
//    and secant steps (`isokit`) and with the paper preset's (`paper`: σ steps, tolerance 1e-4,
//    only the cap stops a vertex that makes no progress). Manual time = mean ms per frame; counters per
//    frame: Newton steps, field evaluations, and the share of calls at the cap.
//  - BM_FieldEval/<rig>/<path>: one evaluation of the composed field at every DQS vertex position
//    of the clip's frames, by the projector's path (`batch`: the sparse evaluator, up to 127
//    leaves) and by the instruction loop (`loop`); manual time = ns per point. Run it under
//    `perf record` for the evaluation's profile.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "bench_rigs.h"
#include "isokit/implicit/evaluators.h"
#include "isokit/skinning/animation.h"
#include "isokit/skinning/deform.h"
#include "isokit/skinning/pipeline.h"
#include "isokit/skinning/skin_field.h"

namespace {

using namespace isokit;
using namespace isokit::skinning;
namespace fs = std::filesystem;

/// A rig, its Skinner per rules and the poses of its first clip, loaded and fitted once.
struct Case {
  Rig rig;
  std::vector<Pose> poses;
  std::unique_ptr<Skinner> isokit, paper;
};

Case& load_case(const std::string& file) {
  static std::vector<std::pair<std::string, std::unique_ptr<Case>>> cache;
  for (auto& [f, c] : cache)
    if (f == file) return *c;
  auto c = std::make_unique<Case>();
  c->rig = open_rig(file);
  if (!c->rig.clips.empty()) c->poses = clip_animation(c->rig, c->rig.clips.front().name);
  const char* env = std::getenv("ISOKIT_BENCH_FRAMES");
  const std::size_t frames = env ? std::size_t(std::max(1, std::atoi(env))) : 30;
  if (c->poses.size() > frames) c->poses.resize(frames);
  c->isokit = std::make_unique<Skinner>(c->rig);
  SkinSetup paper;
  paper.projector.stall_steps = 0;  // the paper preset's projector (apply_paper_preset)
  paper.projector.secant = false;
  paper.projector.tolerance = 1e-4f;
  c->paper = std::make_unique<Skinner>(c->rig, paper);
  cache.emplace_back(file, std::move(c));
  return *cache.back().second;
}

/// The case of `file`, or null with the benchmark skipped and the loader's message.
Case* case_or_skip(benchmark::State& state, const std::string& file) {
  try {
    return &load_case(file);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return nullptr;
  }
}

void BM_Implicit2013(benchmark::State& state, const std::string& file, bool paper) {
  Case* c = case_or_skip(state, file);
  if (!c) return;
  if (c->poses.empty()) {
    state.SkipWithError("the rig has no clip");
    return;
  }
  BakeOptions o;
  o.metrics = false;
  double steps = 0, evaluations = 0, capped = 0, calls = 0;
  for (auto _ : state) {
    const BakeResult r = (paper ? c->paper : c->isokit)->bake(Method::kImplicit2013, c->poses, o);
    state.SetIterationTime(r.mean_ms * 1e-3);
    for (const FrameStats& s : r.stats) {
      steps += s.iterations;
      evaluations += s.field_evaluations;
      capped += s.capped_calls;
      calls += s.tracker_calls;
    }
  }
  const double frames = double(state.iterations()) * double(c->poses.size());
  state.counters["newton_steps_per_frame"] = steps / frames;
  state.counters["field_evaluations_per_frame"] = evaluations / frames;
  state.counters["capped_share"] = calls > 0 ? capped / calls : 0.0;
}

/// `loop`: the instruction loop (ScalarEvaluator, what programs of more than 63 leaves ran before
/// the two-word leaf mask), else the projector's path (the batch evaluator: sparse up to 127).
void BM_FieldEval(benchmark::State& state, const std::string& file, bool loop) {
  Case* c = case_or_skip(state, file);
  if (!c) return;
  SkinField& field = c->isokit->field(TreeKind::k2013);
  std::vector<std::vector<Vec3f>> points;
  std::vector<std::shared_ptr<const implicit::Pose>> poses;
  for (const Pose& pose : c->poses) {
    const std::vector<Affine> skin = skinning_matrices(c->rig, pose);
    track::Positions p;
    dual_quaternion_blend(c->rig.weights, skin, c->rig.rest, p, nullptr, 0);
    std::vector<Vec3f>& row = points.emplace_back(std::size_t(p.rows()));
    for (Eigen::Index v = 0; v < p.rows(); ++v) row[std::size_t(v)] = Vec3f{p(v, 0), p(v, 1), p(v, 2)};
    poses.push_back(field.pose_of(skin));
  }
  std::vector<float> values;
  std::vector<Vec3f> grads;
  std::vector<std::uint8_t> contact;
  double count = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    for (std::size_t f = 0; f < points.size(); ++f) {
      const std::size_t n = points[f].size();
      values.resize(n), grads.resize(n), contact.assign(n, 0);
      if (loop) {
        implicit::ScalarEvaluator eval(field.program(), *poses[f]);
        for (std::size_t k = 0; k < n; ++k) values[k] = eval.eval(points[f][k], nullptr, true).value;
      } else {
        field.function(poses[f])(points[f].data(), n, values.data(), grads.data(), contact.data());
      }
      benchmark::DoNotOptimize(values.data());
      count += double(n);
    }
    state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  state.counters["leaves"] = double(field.program().leaves().size());
  state.counters["sparse"] = field.program().sparse() ? 1 : 0;
  state.counters["ns_per_point"] =
      benchmark::Counter(count, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

}  // namespace

int main(int argc, char** argv) {
  for (const std::string& file : isokit::bench::real_rig_files()) {
    const std::string name = fs::path(file).stem().string();
    for (const bool paper : {false, true})
      benchmark::RegisterBenchmark(("BM_Implicit2013/" + name + (paper ? "/paper" : "/isokit")).c_str(),
                                   [file, paper](benchmark::State& s) { BM_Implicit2013(s, file, paper); })
          ->UseManualTime()
          ->Unit(benchmark::kMillisecond)
          ->Iterations(1)
          ->Repetitions(5)
          ->ReportAggregatesOnly(true);
    for (const bool loop : {false, true})
      benchmark::RegisterBenchmark(("BM_FieldEval/" + name + (loop ? "/loop" : "/batch")).c_str(),
                                   [file, loop](benchmark::State& s) { BM_FieldEval(s, file, loop); })
          ->UseManualTime()
          ->Unit(benchmark::kMillisecond);
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
