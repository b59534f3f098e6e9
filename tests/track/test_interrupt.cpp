// SPDX-License-Identifier: MIT
// The tracker's interrupt (IsoSurfaceTracker::set_interrupt), for each relaxation solver: a call
// stops after exactly the iterations its interrupt allowed and says so, its result is finite and
// closed by the same stages, a second call at the same field finishes the solve; an abandoned call
// returns the relaxation's positions and keeps the last call's flags; an interrupt that never
// fires changes nothing.
#include <catch2/catch.hpp>

#include <algorithm>
#include <vector>

#include "isokit/track/tracker.h"
#include "sphere_scene.h"
#include "test_util.h"
#include "track_fixtures.h"

using namespace isokit;
using namespace isokit::track;

namespace {

const Relaxation kSolvers[] = {Relaxation::kJacobi, Relaxation::kConjugateGradient, Relaxation::kGlobal,
                               Relaxation::kEnergy};

using Scene = test::SphereScene;

TrackerOptions options_for(Relaxation r) {
  TrackerOptions o;
  o.relaxation = r;
  o.max_iterations = 300;
  return o;
}

}  // namespace

TEST_CASE("interrupt: a call stops after the iterations its interrupt allowed, and the next one finishes",
          "[track][tracker][unit]") {
  for (const Relaxation r : kSolvers)
    for (const int part : {0, 1, 2, 3}) {
      const Scene sc({0.05f, -0.03f, 0.02f}, 0.02f, 3u + std::uint32_t(part));
      const FieldFunction f = test::as_function(sc.field);
      IsoSurfaceTracker whole(sc.mesh.V, sc.mesh.F, sc.iso, options_for(r));
      Positions W = sc.start;
      const TrackStats sw = whole.track(f, {}, W);
      REQUIRE(sw.converged);
      const int allowed = part * (sw.iterations - 1) / 3;  // 0 .. all but the last
      INFO("solver " << int(r) << ", interrupted before iteration " << allowed << " of " << sw.iterations);

      IsoSurfaceTracker cut(sc.mesh.V, sc.mesh.F, sc.iso, options_for(r));
      int tests = 0;
      cut.set_interrupt(
          [&] { return tests++ >= allowed ? TrackInterrupt::kStop : TrackInterrupt::kContinue; });
      Positions P = sc.start;
      const TrackStats s1 = cut.track(f, {}, P);
      CHECK(s1.iterations == allowed);
      CHECK(s1.interrupted);
      CHECK_FALSE(s1.abandoned);
      CHECK_FALSE(s1.converged);
      CHECK(P.allFinite());
      CHECK(s1.lost_vertices == 0);

      cut.set_interrupt({});  // the rest of the solve, from where the first call stopped
      const TrackStats s2 = cut.track(f, {}, P);
      CHECK_FALSE(s2.interrupted);
      CHECK(s2.converged);
      CHECK(s2.max_residual <= std::max(2 * sw.max_residual, 1e-4f));
      CHECK((P - W).rowwise().norm().maxCoeff() <= 0.05f);  // the same surface, up to tangential drift
    }
}

TEST_CASE("interrupt: one that never fires leaves the result bit for bit", "[track][tracker][unit]") {
  const Scene sc({0.03f, 0.02f, -0.01f}, 0.01f, 17);
  for (const Relaxation r : kSolvers) {
    INFO("solver " << int(r));
    IsoSurfaceTracker plain(sc.mesh.V, sc.mesh.F, sc.iso, options_for(r));
    IsoSurfaceTracker watched = plain;
    int tests = 0;
    watched.set_interrupt([&] {
      ++tests;
      return TrackInterrupt::kContinue;
    });
    Positions a = sc.start, b = sc.start;
    const TrackStats sa = plain.track(test::as_function(sc.field), {}, a);
    const TrackStats sb = watched.track(test::as_function(sc.field), {}, b);
    CHECK(a == b);
    CHECK(sa.iterations == sb.iterations);
    CHECK(tests == sb.iterations);  // tested once before each iteration
    CHECK_FALSE(sb.interrupted);
  }
}

TEST_CASE("interrupt: an abandoned call keeps the last call's flags and its positions start the next call",
          "[track][tracker][unit]") {
  for (const Relaxation r : kSolvers) {
    INFO("solver " << int(r));
    const Scene sc({0.05f, 0.03f, -0.02f}, 0.02f, 29);
    const Scene moved({0.15f, 0.03f, -0.02f}, 0.f, 29);  // the next pose: the field moved on
    const FieldFunction f = test::as_function(sc.field);
    IsoSurfaceTracker tracker(sc.mesh.V, sc.mesh.F, sc.iso, options_for(r));
    Positions P = sc.start;
    REQUIRE(tracker.track(f, {}, P).converged);
    const VertexFlags before = tracker.flags();
    int tests = 0;
    tracker.set_interrupt(
        [&] { return tests++ >= 2 ? TrackInterrupt::kAbandon : TrackInterrupt::kContinue; });
    Positions Q = P;
    // Not moved with it: the projection pulls the vertices across, the relaxation has work.
    const TrackStats s = tracker.track(test::as_function(moved.field), {}, Q);
    CHECK(s.abandoned);
    CHECK(s.interrupted);
    CHECK(s.iterations == 2);
    CHECK(Q.allFinite());
    CHECK(tracker.flags().contact == before.contact);  // not this call's: it did not close
    CHECK(tracker.flags().beta == before.beta);
    tracker.set_interrupt({});
    const TrackStats next = tracker.track(test::as_function(moved.field), {}, Q);
    CHECK(next.converged);
    CHECK_FALSE(next.abandoned);
    CHECK(next.max_residual <= 1e-3f);
  }
}
