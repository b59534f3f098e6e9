// SPDX-License-Identifier: MIT
// The design studio's model (isokit-opdesigner gui) at the real resolution: the synchronous
// re-solve of the displayed slice per drag frame, and the background re-solve of every slice
// an edit changed. Arg: resolution (slices = resolution).
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>

#include "isokit/studio/model.h"

using namespace isokit;
using namespace isokit::studio;

namespace {

operators::OperatorSpec spec_at(int resolution) {
  operators::OperatorSpec spec = operators::preset_spec("contact", resolution);
  spec.slices = resolution;
  return spec;
}

StudioOptions bench_options() {
  StudioOptions o;
  o.recent_files_path = "";
  o.edit_band_cells = 3;
  return o;
}

// One drag frame: the contact line's end moves by up to a cell; drag_to returns with the
// displayed slice (d = 0.7) re-solved. The background keeps re-solving the other slices.
void BM_StudioDragFrame(benchmark::State& state) {
  const auto setup_start = std::chrono::steady_clock::now();
  StudioModel model(spec_at(int(state.range(0))), bench_options());
  model.wait_until_solved();
  const double setup = std::chrono::duration<double>(std::chrono::steady_clock::now() - setup_start).count();
  model.set_d(0.7);
  const CurvePoint end{1, 1};
  const Point2 start = model.control_points(1)[1];
  model.begin_drag(end);
  int frame = 0, schur = 0;
  for (auto _ : state) {
    const double t = 0.01 * std::sin(0.1 * frame), u = 0.01 * std::cos(0.13 * frame);
    if (!model.drag_to({start[0] + t, start[1] + u})) state.SkipWithError("drag refused");
    schur += model.last_solve_was_schur();
    model.poll();
    ++frame;
  }
  model.end_drag();
  state.SetLabel("schur " + std::to_string(schur) + "/" + std::to_string(frame) + ", open + full solve " +
                 std::to_string(setup) + " s");
}

// One edit (the contact end dragged at d = 0.5, inserting a keyframe: most slices change), then
// the wait until the background has re-solved every changed slice.
void BM_StudioEditFullResolve(benchmark::State& state) {
  StudioModel model(spec_at(int(state.range(0))), bench_options());
  model.wait_until_solved();
  model.set_d(0.5);
  const Point2 start = model.control_points(1)[1];
  int edit = 0, queued = 0;
  for (auto _ : state) {
    model.begin_drag({1, 1});
    model.drag_to({start[0] + 0.004 * (edit % 2 ? 1 : -1), start[1]});
    model.end_drag();
    queued = model.progress().total;
    model.wait_until_solved();
    ++edit;
  }
  state.SetLabel(std::to_string(queued) + " slices queued per edit");
}

}  // namespace

BENCHMARK(BM_StudioDragFrame)->Arg(32)->Arg(128)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StudioEditFullResolve)->Arg(32)->Arg(128)->Unit(benchmark::kMillisecond)->Iterations(5);

BENCHMARK_MAIN();
