// SPDX-License-Identifier: MIT
// 2014 tracker throughput: vertex-iterations per second (one Jacobi step of the tangential
// ARAP energy + one Newton projection per vertex-iteration) on capsule meshes of ~10k, 50k and
// 200k vertices, with a cheap analytic field (one capsule) and per-vertex rotations.
// Args: {vertices class (0: 10k, 1: 50k, 2: 200k), grain (0 = serial)}.
// BM_TrackIterations: default options (Chebyshev-accelerated Jacobi); BM_TrackIterationsJacobi:
// `chebyshev_rho = 0` (plain Jacobi, as in 2014), to read the per-iteration cost of the
// acceleration in the same run.
#include <benchmark/benchmark.h>

#include <vector>

#include "isokit/implicit/field_math.h"
#include "isokit/track/tracker.h"
#include "track/track_fixtures.h"

namespace {

using namespace isokit;
using namespace isokit::track;

constexpr int kIterations = 50;

test::Mesh bench_mesh(int size_class) {
  // around x (segments + 1 + 10 cap rings) + 2 vertices.
  static const int around[] = {64, 128, 256};
  static const int segments[] = {150, 380, 770};
  return test::capsule_mesh(0.3f, 1.0f, around[size_class], segments[size_class], 6);
}

void track_iterations(benchmark::State& state, float chebyshev_rho) {
  const test::Mesh mesh = bench_mesh(static_cast<int>(state.range(0)));
  const Mat3f r = test::rot_z(0.05f);
  const implicit::CapsuleParamsT<float> rest_cap{{0, -1, 0}, {0, 1, 0}, 0.3f, 0.3f};
  const implicit::CapsuleParamsT<float> cap{r * Vec3f{0, -1, 0}, r * Vec3f{0, 1, 0}, 0.3f, 0.3f};
  auto make = [](implicit::CapsuleParamsT<float> c) -> FieldFunction {
    return [c](const Vec3f* p, std::size_t n, float* v, Vec3f* g, std::uint8_t*) {
      for (std::size_t k = 0; k < n; ++k) {
        const implicit::FieldSample s = implicit::eval_capsule(c, p[k]);
        v[k] = s.value;
        g[k] = s.gradient;
      }
    };
  };
  const std::vector<float> iso = sample_iso_values(make(rest_cap), mesh.V);
  TrackerOptions o;
  o.initial_newton_steps = 0;
  o.max_iterations = kIterations;
  o.tolerance = 0.f;  // always run every iteration
  o.smoothing.smoothing_steps = 0;
  o.fold_repair.rounds = 0;  // the relaxation alone is measured
  o.grain = static_cast<std::size_t>(state.range(1));
  o.chebyshev_rho = chebyshev_rho;
  IsoSurfaceTracker tracker(mesh.V, mesh.F, iso, o);
  const std::vector<Mat3f> rotations(static_cast<std::size_t>(mesh.V.rows()), r);
  const FieldFunction field = make(cap);
  Positions P;
  for (auto _ : state) {
    state.PauseTiming();
    P = mesh.V;
    state.ResumeTiming();
    const TrackStats s = tracker.track(field, rotations, P);
    benchmark::DoNotOptimize(s.max_residual);
  }
  state.counters["vertices"] = static_cast<double>(mesh.V.rows());
  // Vertex-iterations per second, including the per-call overhead (copies, final statistics).
  state.SetItemsProcessed(state.iterations() * mesh.V.rows() * kIterations);
}

void BM_TrackIterations(benchmark::State& state) {
  track_iterations(state, TrackerOptions{}.chebyshev_rho);
}

void BM_TrackIterationsJacobi(benchmark::State& state) {
  track_iterations(state, 0.f);
}

}  // namespace

BENCHMARK(BM_TrackIterations)
    ->Args({0, 0})
    ->Args({0, 1024})
    ->Args({1, 0})
    ->Args({1, 1024})
    ->Args({2, 0})
    ->Args({2, 1024})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_TrackIterationsJacobi)
    ->Args({0, 0})
    ->Args({0, 1024})
    ->Args({1, 0})
    ->Args({1, 1024})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK_MAIN();
