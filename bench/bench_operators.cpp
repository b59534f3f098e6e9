// SPDX-License-Identifier: MIT
// Operator generation and evaluation timings (docs/performance.md, "Operators"):
// one 128² slice (interactive editing) and a full 128³ operator, per scheme and backend; a 128³
// operator loaded from the disk cache and checked (docs/operators.md, "Using a designed operator
// in skinning").
#include <benchmark/benchmark.h>

#include <unistd.h>
#include <cmath>
#include <filesystem>

#include "isokit/operators/analytic.h"
#include "isokit/operators/biharmonic.h"
#include "isokit/operators/cache.h"
#include "isokit/operators/checks.h"
#include "isokit/operators/controller.h"

using namespace isokit::operators;

namespace {

BiharmonicOptions options(int scheme, int backend, int tasks) {
  BiharmonicOptions o;
  o.scheme = scheme == 0 ? SliceScheme::kSchur : SliceScheme::kRefactor;
  o.backend = backend == 0 ? SparseBackend::kCholmod : SparseBackend::kSparseLU;
  o.tasks = tasks;
  return o;
}

const char* preset_of(int i) {
  return i == 0 ? "contact" : (i == 1 ? "bulge" : "clean-union");
}

// One slice, generator already built (the interactive case: re-solve a slice at a new d).
// Args: preset, scheme (0 schur, 1 refactor), backend (0 cholmod, 1 sparselu), resolution.
void BM_Slice(benchmark::State& state) {
  const OperatorSpec spec = preset_spec(preset_of(int(state.range(0))), int(state.range(3)));
  BiharmonicOperatorGenerator gen(spec, options(int(state.range(1)), int(state.range(2)), 1));
  double d = 0.0;
  for (auto _ : state) {
    auto s = gen.solve_slice(d);
    benchmark::DoNotOptimize(s.data());
    d += 1.0 / 127.0;
    if (d > 1.0) d = 0.0;
  }
  state.SetLabel(std::string(preset_of(int(state.range(0)))) + "/" + gen.stats().scheme + "/" +
                 gen.stats().backend + " D=" + std::to_string(gen.stats().dynamic_nodes));
}

// Full operator from the spec, setup included. Args: preset, scheme, backend, tasks.
void BM_FullOperator(benchmark::State& state) {
  const OperatorSpec spec = preset_spec(preset_of(int(state.range(0))), 128);
  std::string label;
  for (auto _ : state) {
    BiharmonicOperatorGenerator gen(spec,
                                    options(int(state.range(1)), int(state.range(2)), int(state.range(3))));
    GridOperator g = gen.generate();
    benchmark::DoNotOptimize(g.data().data());
    label = std::string(preset_of(int(state.range(0)))) + "/" + gen.stats().scheme + "/" +
            gen.stats().backend + " tasks=" + std::to_string(state.range(3));
  }
  state.SetLabel(label);
}

// A 128³ preset loaded from the disk cache (a hit; the entry is stored before timing, in a
// temporary folder). Arg: preset.
void BM_CacheLoad(benchmark::State& state) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("isokit-bench-cache-" + std::to_string(::getpid()));
  const OperatorCache cache(dir.string());
  const OperatorSpec spec = preset_spec(preset_of(int(state.range(0))), 128);
  cache.get(spec);
  for (auto _ : state) {
    CachedGrid g = cache.get(spec);
    if (!g.hit) state.SkipWithError(("cache miss: " + (g.warnings.empty() ? "" : g.warnings[0])).c_str());
    benchmark::DoNotOptimize(g.grid.data().data());
  }
  fs::remove_all(dir);
  state.SetLabel(preset_of(int(state.range(0))));
}

// check_operator on a 128³ preset (what isokit-skin runs on every grid before use). Arg: preset.
void BM_CheckOperator(benchmark::State& state) {
  const OperatorSpec spec = preset_spec(preset_of(int(state.range(0))), 128);
  const GridOperator grid = generate_operator(spec);
  for (auto _ : state) {
    auto failure = check_operator(spec, grid);
    if (failure) state.SkipWithError(failure->message().c_str());
    benchmark::DoNotOptimize(&failure);
  }
  state.SetLabel(preset_of(int(state.range(0))));
}

// Setup alone (matrix, analysis, Schur complement).
void BM_Setup(benchmark::State& state) {
  const OperatorSpec spec = preset_spec(preset_of(int(state.range(0))), 128);
  for (auto _ : state) {
    BiharmonicOperatorGenerator gen(spec, options(int(state.range(1)), 0, 1));
    benchmark::DoNotOptimize(&gen);
  }
}

// Interactive editing: the contact line's end and the boundary corner are dragged by up to
// a cell per frame; each frame re-solves one 128² slice. Arg: band in cells.
void BM_EditSlice(benchmark::State& state) {
  const OperatorSpec spec = preset_spec("contact", 128);
  BiharmonicOptions o;
  o.edit_band_cells = int(state.range(0));
  o.tasks = 1;
  BiharmonicOperatorGenerator gen(spec, o);
  int frame = 0, schur = 0;
  for (auto _ : state) {
    OperatorSpec e = spec;
    const double t = 0.01 * std::sin(0.1 * frame), u = 0.01 * std::cos(0.13 * frame);
    e.curves[0].keyframes[0].points[1] = {0.5 + t, 0.5 + u};
    e.curves[1].keyframes[0].points = {{0.5 + t, 0.5 + u}, {0.5 + t, 0.5 + u}};
    e.curves[1].keyframes[1].points = {{0.5 + t, 0.5 + u}, {0.88 + u, 0.88 + t}};
    auto s = gen.solve_edited(0.7, e);
    benchmark::DoNotOptimize(s.data());
    schur += gen.last_edit_was_schur();
    ++frame;
  }
  state.SetLabel("D=" + std::to_string(gen.stats().dynamic_nodes) + " schur " + std::to_string(schur) + "/" +
                 std::to_string(frame) + " setup " + std::to_string(gen.stats().setup_seconds) + " s");
}

void BM_GridEval(benchmark::State& state) {
  const GridOperator g = generate_operator(preset_spec("contact", 32));
  const GridOperatorView v = g.view();
  float f = 0.f, acc = 0.f;
  for (auto _ : state) {
    const OpSample s = v.eval(f, 1.f - f, 0.37f);
    acc += s.g + s.dg1;
    f += 0.000123f;
    if (f > 1.f) f = 0.f;
  }
  benchmark::DoNotOptimize(acc);
}

void BM_GradientBlend2013(benchmark::State& state) {
  float f = 0.f, acc = 0.f;
  for (auto _ : state) {
    const OpSample s = gradient_blend_2013(0.3f + 0.4f * f, 0.6f - 0.3f * f, 0.8f);
    acc += s.g;
    f += 0.000123f;
    if (f > 1.f) f = 0.f;
  }
  benchmark::DoNotOptimize(acc);
}

// The 2013 blend sampled into a grid operator (operators.blend_grid): once per 2013 field.
void BM_SampleBlend2013(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(sampled_gradient_blend_2013(n, n).data().data());
}

}  // namespace

BENCHMARK(BM_Slice)
    ->ArgsProduct({{0, 1}, {0, 1}, {0}, {128}})
    ->Args({0, 1, 1, 128})
    ->Args({0, 0, 0, 64})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Setup)->ArgsProduct({{0, 1}, {0, 1}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FullOperator)
    ->Args({0, 0, 0, 1})
    ->Args({0, 0, 0, 2})
    ->Args({1, 0, 0, 2})
    ->Args({1, 1, 0, 2})
    ->Args({2, 0, 0, 2})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);
BENCHMARK(BM_CacheLoad)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CheckOperator)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EditSlice)->Arg(0)->Arg(3)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GridEval);
BENCHMARK(BM_GradientBlend2013);
BENCHMARK(BM_SampleBlend2013)->Arg(64)->Arg(128)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
