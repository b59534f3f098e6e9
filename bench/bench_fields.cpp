// SPDX-License-Identifier: MIT
// Field evaluation throughput (value + gradient) on one thread: analytic capsule vs the same
// capsule through a 32^3 grid, random points inside the grid box; and 32^3 grid sampling time.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "isokit/implicit/grid_field.h"
#include "isokit/implicit/primitives.h"

namespace {

using namespace isokit;
using namespace isokit::implicit;

const CapsuleField& capsule() {
  static const CapsuleField c({0, 0, 0}, {0, 0, 1}, 0.25f);
  return c;
}

std::vector<Vec3f> points_in(const Box3f& b, std::size_t n) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> ux(b.lo.x, b.hi.x), uy(b.lo.y, b.hi.y), uz(b.lo.z, b.hi.z);
  std::vector<Vec3f> p(n);
  for (auto& q : p) q = {ux(rng), uy(rng), uz(rng)};
  return p;
}

void run_batch(benchmark::State& state, const Field& f) {
  const auto pts = points_in(f.support(), 1 << 16);
  std::vector<FieldSample> out(pts.size());
  for (auto _ : state) {
    f.eval_batch(pts.data(), pts.size(), out.data(), 0);  // grain 0: one core
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(pts.size()));
}

void BM_CapsuleEval(benchmark::State& state) {
  run_batch(state, capsule());
}

void BM_GridEval(benchmark::State& state) {
  const GridField grid(capsule(), Box3f{}, GridFieldOptions{static_cast<int>(state.range(0))});
  run_batch(state, grid);
}

void BM_GridSample(benchmark::State& state) {
  for (auto _ : state) {
    GridField grid(capsule(), Box3f{}, GridFieldOptions{static_cast<int>(state.range(0)), 0});
    benchmark::DoNotOptimize(grid.nodes().data());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0) * state.range(0) * state.range(0));
}

}  // namespace

BENCHMARK(BM_CapsuleEval)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GridEval)->Arg(32)->Arg(128)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GridSample)->Arg(32)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
