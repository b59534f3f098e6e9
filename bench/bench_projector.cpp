// SPDX-License-Identifier: MIT
// The 2013 projector on real rigs (docs/performance.md, "implicit2013 per frame"): every .glb /
// .gltf / .fbx of ISOKIT_RIGS (default ../shared/data/rigs) and ../shared/data/Fox.glb when they
// exist, the first ISOKIT_BENCH_FRAMES (default 30) frames of each rig's first clip.
//  - BM_Implicit2013/<rig>/<rules>: the bake per frame (metrics off), with isokit's stopping rules
//    and secant steps (`isokit`) and with the paper preset's (`paper`: σ steps, tolerance 1e-4,
//    only the cap stops a vertex that makes no progress). Manual time = mean ms per frame; counters per
//    frame: Newton steps, field evaluations, and the share of calls at the cap.
//  - BM_FieldEval/<rig>/<path>: one evaluation of the composed field at every DQS vertex position
//    of the clip's frames, in the projector's batches; manual time = ns per point, counters: the
//    leaves and the field's memory (MiB). Paths, A/B in one run:
//      `fixed16`: fixed16 grids and grid operators (fit.grid_storage, operators.storage), leaves
//        culled per block of points; counters: its difference from `float32` at the same points;
//      `float32`: the same evaluator over float32 grids and grid operators;
//      `ops32`: fixed16 grids, float32 grid operators;
//      `plain`: fixed16 grids, no cull;
//      `loop`: the instruction loop (ScalarEvaluator) over the default grids.
//    Repeated leaves are evaluated once and max operands that cannot win are skipped on every
//    path but `loop`. The evaluator before these
//    changes is measured by the same benchmark built at an earlier commit (docs/performance.md).
//    Run it under `perf record` for the evaluation's profile.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
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
#include "isokit/track/projector2013.h"

namespace {

using namespace isokit;
using namespace isokit::skinning;
namespace fs = std::filesystem;

/// A rig, its Skinner per rules and the poses of its first clip, loaded and fitted once.
struct Case {
  Rig rig;
  std::vector<Pose> poses;
  std::unique_ptr<Skinner> isokit, paper;
  /// By path: the Skinner of each storage pair other than `isokit`'s, made on first use.
  std::vector<std::pair<std::string, std::unique_ptr<Skinner>>> storages;
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

void storage_error(benchmark::State& state, Case& c, SkinField& field,
                   const std::vector<std::vector<Vec3f>>& points,
                   const std::vector<std::shared_ptr<const implicit::Pose>>& poses);

/// The field of the path: its leaves' and operators' storage (fixed16 or float32), made on first
/// use; `plain` and `loop` use the default setup's.
SkinField& path_field(Case& c, const std::string& path) {
  if (path != "float32" && path != "fixed16" && path != "ops32") return c.isokit->field(TreeKind::k2013);
  for (auto& [p, skinner] : c.storages)
    if (p == path) return skinner->field(TreeKind::k2013);
  SkinSetup s;
  s.fit.grid_storage = path == "float32" ? implicit::GridStorage::float32 : implicit::GridStorage::fixed16;
  s.operator_storage = path == "fixed16" ? implicit::GridStorage::fixed16 : implicit::GridStorage::float32;
  c.storages.emplace_back(path, std::make_unique<Skinner>(c.rig, s));
  return c.storages.back().second->field(TreeKind::k2013);
}

void BM_FieldEval(benchmark::State& state, const std::string& file, const std::string& path) {
  Case* c = case_or_skip(state, file);
  if (!c) return;
  if (c->poses.empty()) {
    state.SkipWithError("the rig has no clip");
    return;
  }
  SkinField& field = path_field(*c, path);
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
  implicit::BatchOptions options;
  options.cull = path != "plain";
  const std::size_t batch = track::ProjectorOptions{}.grain;  // the projector's batch size
  std::vector<float> values;
  std::vector<Vec3f> grads;
  double count = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    for (std::size_t f = 0; f < points.size(); ++f) {
      const std::size_t n = points[f].size();
      values.resize(n), grads.resize(n);
      if (path == "loop") {
        implicit::ScalarEvaluator eval(field.program(), *poses[f]);
        for (std::size_t k = 0; k < n; ++k) values[k] = eval.eval(points[f][k], nullptr, true).value;
      } else {
        implicit::BatchEvaluator eval(field.program(), *poses[f], options);
        for (std::size_t b = 0; b < n; b += batch)
          eval.eval(points[f].data() + b, std::min(batch, n - b), values.data() + b, grads.data() + b);
      }
      benchmark::DoNotOptimize(values.data());
      count += double(n);
    }
    state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  state.counters["leaves"] = double(field.program().leaves().size());
  state.counters["field_MiB"] = double(field.program().memory_bytes()) / double(1 << 20);
  state.counters["ns_per_point"] =
      benchmark::Counter(count, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  if (path == "fixed16") storage_error(state, *c, field, points, poses);
}

/// The fixed16 field against the float32 one at the same points (counters): the value's
/// difference and the gradient's angle (degrees, where both gradients are at least 1 % of the
/// largest), worst and 99th percentile.
void storage_error(benchmark::State& state, Case& c, SkinField& field,
                   const std::vector<std::vector<Vec3f>>& points,
                   const std::vector<std::shared_ptr<const implicit::Pose>>& poses) {
  SkinField& reference = path_field(c, "float32");
  std::vector<double> value, angle;
  std::vector<implicit::FieldSample> a, b;
  double largest = 0;
  for (std::size_t f = 0; f < points.size(); ++f) {
    const std::size_t n = points[f].size();
    a.resize(n), b.resize(n);
    implicit::BatchEvaluator(field.program(), *poses[f]).eval(points[f].data(), n, a.data());
    const std::vector<Affine> skin = skinning_matrices(c.rig, c.poses[f]);
    implicit::BatchEvaluator(reference.program(), *reference.pose_of(skin))
        .eval(points[f].data(), n, b.data());
    for (std::size_t k = 0; k < n; ++k) {
      value.push_back(std::fabs(double(a[k].value) - double(b[k].value)));
      largest = std::max(largest, double(norm(b[k].gradient)));
    }
    for (std::size_t k = 0; k < n; ++k) {
      const double na = norm(a[k].gradient), nb = norm(b[k].gradient);
      if (na < 0.01 * largest || nb < 0.01 * largest) continue;
      const double cosine = std::clamp(double(dot(a[k].gradient, b[k].gradient)) / (na * nb), -1.0, 1.0);
      angle.push_back(std::acos(cosine) * 180.0 / 3.14159265358979);
    }
  }
  auto worst_and_p99 = [](std::vector<double>& v, double& worst, double& p99) {
    worst = p99 = 0;
    if (v.empty()) return;
    std::sort(v.begin(), v.end());
    worst = v.back();
    p99 = v[std::min(v.size() - 1, std::size_t(0.99 * double(v.size())))];
  };
  double vw, vp, aw, ap;
  worst_and_p99(value, vw, vp);
  worst_and_p99(angle, aw, ap);
  state.counters["value_err_max"] = vw;
  state.counters["value_err_p99"] = vp;
  state.counters["angle_deg_max"] = aw;
  state.counters["angle_deg_p99"] = ap;
  state.counters["float32_MiB"] = double(reference.program().memory_bytes()) / double(1 << 20);
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
    for (const std::string path : {"fixed16", "ops32", "float32", "plain", "loop"})
      benchmark::RegisterBenchmark(("BM_FieldEval/" + name + "/" + path).c_str(),
                                   [file, path](benchmark::State& s) { BM_FieldEval(s, file, path); })
          ->UseManualTime()
          ->Unit(benchmark::kMillisecond);
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
