// SPDX-License-Identifier: MIT
// 2014 tracker throughput: vertex-iterations per second (one Jacobi step of the tangential
// ARAP energy + one Newton projection per vertex-iteration) on capsule meshes of ~10k, 50k and
// 200k vertices, with a cheap analytic field (one capsule) and per-vertex rotations.
// Args: {vertices class (0: 10k, 1: 50k, 2: 200k), grain (0 = serial)}.
// BM_TrackIterations: default options (Chebyshev-accelerated Jacobi); BM_TrackIterationsJacobi:
// `chebyshev_rho = 0` (plain Jacobi, as in 2014), to read the per-iteration cost of the
// acceleration in the same run.
// BM_TrackRefinement: the two-capsule elbow of the tracker tests bent 0 -> 60 -> 0 degrees in 15
// degree steps on its mesh at 1x, 4x, 16x and 64x the vertices, with the Jacobi relaxation (the
// default) and the global solve (Relaxation::kGlobal), the default tolerances and cap; counters:
// mean iterations per call, the share of converged calls, vertices.
// Args: {refinement (1, 2, 4, 8: about 1x, 4x, 16x, 64x the vertices), solver (0 Jacobi, 1 global)}.
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

void BM_TrackRefinement(benchmark::State& state) {
  const int refinement = static_cast<int>(state.range(0));
  const test::Mesh mesh = test::capsule_mesh(0.3f, 1.0f, 12 * refinement, 16 * refinement, 3 * refinement);
  test::ElbowField field(0.3f, 1.0f, 48);
  const std::vector<float> iso = sample_iso_values(field.function(), mesh.V);
  TrackerOptions o;
  o.relaxation = state.range(1) == 1 ? Relaxation::kGlobal : Relaxation::kJacobi;
  const std::vector<int> angles = {15, 30, 45, 60, 45, 30, 15, 0};
  long iterations = 0, calls = 0, converged = 0;
  for (auto _ : state) {
    IsoSurfaceTracker tracker(mesh.V, mesh.F, iso, o);
    Positions P = mesh.V;
    float angle = 0.f;
    for (int deg : angles) {
      const float to = float(deg) * kPiF / 180.f;
      test::ZLimb::turn_upper(mesh.V, to - angle, P);
      angle = to;
      field.set_angle(to);
      const TrackStats s = tracker.track(field.function(), test::ZLimb::rotations(mesh.V, angle), P);
      iterations += s.iterations;
      converged += s.converged ? 1 : 0;
      ++calls;
    }
    benchmark::DoNotOptimize(P.data());
  }
  state.counters["vertices"] = static_cast<double>(mesh.V.rows());
  state.counters["iterations_per_call"] = double(iterations) / double(calls);
  state.counters["converged_share"] = double(converged) / double(calls);
  state.counters["calls"] = double(calls);
}

}  // namespace

BENCHMARK(BM_TrackRefinement)
    ->ArgsProduct({{1, 2, 4, 8}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

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
