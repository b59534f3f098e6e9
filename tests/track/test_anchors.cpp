// SPDX-License-Identifier: MIT
// Anchors of the 2014 tracker (IsoSurfaceTracker::set_anchor_stiffness: the relaxation mask of
// 2014 Fig. 11 as a term of the solve), for each relaxation solver: stiffness 0 changes nothing,
// 1 pins a vertex to its anchor while its neighbours are tracked, values between pull toward the
// anchor more as they grow, and bad input is refused naming the item.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "isokit/core/error.h"
#include "isokit/track/tracker.h"
#include "sphere_scene.h"
#include "test_util.h"
#include "track_fixtures.h"

using namespace isokit;
using namespace isokit::track;

namespace {

const Relaxation kSolvers[] = {Relaxation::kJacobi, Relaxation::kConjugateGradient, Relaxation::kGlobal,
                               Relaxation::kEnergy};

const char* name_of(Relaxation r) {
  return r == Relaxation::kJacobi   ? "jacobi"
         : r == Relaxation::kGlobal ? "global"
         : r == Relaxation::kEnergy ? "energy"
                                    : "cg";
}

TrackerOptions options_for(Relaxation r) {
  TrackerOptions o;
  o.relaxation = r;
  o.max_iterations = 300;
  return o;
}

using Scene = test::SphereScene;

/// Largest distance between rows `rows` of two position sets.
float max_distance_on(const Positions& a, const Positions& b, const std::vector<int>& rows) {
  float d = 0.f;
  for (int i : rows) d = std::max(d, (a.row(i) - b.row(i)).norm());
  return d;
}

}  // namespace

TEST_CASE("anchors: stiffness 0 everywhere gives the result of a tracker without anchors",
          "[track][tracker][anchors][unit]") {
  const Scene sc({0.04f, -0.02f, 0.01f}, 0.01f, 11);
  for (const Relaxation r : kSolvers) {
    INFO(name_of(r));
    IsoSurfaceTracker plain(sc.mesh.V, sc.mesh.F, sc.iso, options_for(r));
    IsoSurfaceTracker anchored = plain;
    anchored.set_anchor_stiffness(std::vector<float>(static_cast<std::size_t>(sc.mesh.V.rows()), 0.f));
    Positions a = sc.start, b = sc.start;
    Positions far = sc.start;
    far.array() += 3.f;  // anchors of stiffness 0 are ignored, wherever they are
    plain.track(test::as_function(sc.field), {}, a);
    anchored.track(test::as_function(sc.field), {}, b, far);
    CHECK(a == b);
  }
}

TEST_CASE("anchors: pinned vertices stay exactly at their anchors while their neighbours are tracked",
          "[track][tracker][anchors][unit]") {
  const Scene sc({0.04f, -0.02f, 0.01f}, 0.01f, 5);
  const auto nv = static_cast<std::size_t>(sc.mesh.V.rows());
  // The upper cap is pinned to the rest mesh moved by the field's shift and turned a little: a
  // rigid placement by its bone, slightly off the moved iso-surface.
  std::vector<float> k(nv, 0.f);
  std::vector<int> pinned, free;
  for (std::size_t v = 0; v < nv; ++v)
    (sc.mesh.V(Eigen::Index(v), 1) > 0.3f ? pinned : free).push_back(int(v));
  for (int v : pinned) k[std::size_t(v)] = 1.f;
  const Mat3f R = test::rot_z(0.05f);
  Positions anchors = sc.mesh.V;
  for (Eigen::Index i = 0; i < anchors.rows(); ++i) {
    const Vec3f q = R * Vec3f{anchors(i, 0), anchors(i, 1), anchors(i, 2)} + Vec3f{0.04f, -0.02f, 0.01f};
    anchors.row(i) << q.x, q.y, q.z;
  }
  for (const Relaxation r : kSolvers) {
    INFO(name_of(r));
    IsoSurfaceTracker tracker(sc.mesh.V, sc.mesh.F, sc.iso, options_for(r));
    tracker.set_anchor_stiffness(k);
    Positions P = sc.start;
    const TrackStats s = tracker.track(test::as_function(sc.field), {}, P, anchors);
    CHECK(P.allFinite());
    CHECK(max_distance_on(P, anchors, pinned) == 0.f);  // exactly: not projected, relaxed or smoothed
    for (int v : pinned) CHECK_FALSE(tracker.flags().contact[std::size_t(v)]);
    // The rest are on their iso-values (the statistics leave the pinned vertices out)...
    CHECK(s.max_residual <= 1e-3f);
    CHECK(s.lost_vertices == 0);
    // ...and they moved: projected and relaxed from the perturbed start.
    CHECK(max_distance_on(P, sc.start, free) > 1e-3f);
    // Without the pin the cap would have been moved onto the iso-surface.
    IsoSurfaceTracker unpinned(sc.mesh.V, sc.mesh.F, sc.iso, options_for(r));
    Positions Q = sc.start;
    unpinned.track(test::as_function(sc.field), {}, Q);
    CHECK(max_distance_on(Q, anchors, pinned) > 1e-3f);
  }
}

TEST_CASE(
    "anchors: a stiffer anchor pulls its vertex closer, the vertex stays on its iso-value (projecting "
    "solvers)",
    "[track][tracker][anchors][unit]") {
  // The field does not move; the start is the rest mesh with a tangential-ish perturbation, and
  // the anchors are that start: the ARAP relaxation pulls toward the rest mesh, the anchors hold
  // the perturbation.
  const Scene sc({0.f, 0.f, 0.f}, 0.03f, 9);
  const auto nv = static_cast<std::size_t>(sc.mesh.V.rows());
  std::vector<int> all(nv);
  for (std::size_t v = 0; v < nv; ++v) all[v] = int(v);
  for (const Relaxation r : kSolvers) {
    INFO(name_of(r));
    float last = std::numeric_limits<float>::infinity();
    for (const float stiffness : {0.f, 0.3f, 0.7f, 0.95f}) {
      INFO("stiffness " << stiffness);
      IsoSurfaceTracker tracker(sc.mesh.V, sc.mesh.F, sc.iso, options_for(r));
      tracker.set_anchor_stiffness(std::vector<float>(nv, stiffness));
      Positions P = sc.start;
      const TrackStats s = tracker.track(test::as_function(sc.field), {}, P, sc.start);
      // The energy solve's anchor and iso terms are both soft: an anchored vertex settles between
      // its anchor and its iso-value (docs/tracking.md, "The energy solve"); the others project.
      if (r != Relaxation::kEnergy) CHECK(s.max_residual <= 1e-3f);
      // Mean tangential distance to the anchors (radial parts are the projection's).
      double sum = 0;
      for (int v : all) {
        const Eigen::Vector3f a = sc.start.row(v).transpose().normalized(),
                              b = P.row(v).transpose().normalized();
        sum += double(std::acos(std::clamp(a.dot(b), -1.f, 1.f)));
      }
      const float mean = float(sum / double(nv));
      CHECK(mean < last);
      last = mean;
    }
  }
}

TEST_CASE("anchors: bad stiffness or anchors are refused naming the item",
          "[track][tracker][anchors][errors][unit]") {
  const Scene sc({0.f, 0.f, 0.f}, 0.f, 1);
  const auto nv = static_cast<std::size_t>(sc.mesh.V.rows());
  IsoSurfaceTracker tracker(sc.mesh.V, sc.mesh.F, sc.iso);
  CHECK_THROWS_WITH(tracker.set_anchor_stiffness(std::vector<float>(nv - 1, 0.5f)),
                    Catch::Contains("anchor stiffness") && Catch::Contains("differs from the vertex count"));
  std::vector<float> k(nv, 0.5f);
  k[3] = 1.5f;
  CHECK_THROWS_WITH(tracker.set_anchor_stiffness(k), Catch::Contains("anchor stiffness vertex 3"));
  k[3] = std::nanf("");
  CHECK_THROWS_AS(tracker.set_anchor_stiffness(k), InputError);
  k[3] = 0.5f;
  tracker.set_anchor_stiffness(k);
  Positions P = sc.start;
  const Positions short_anchors = sc.start.topRows(sc.start.rows() - 1);
  CHECK_THROWS_WITH(tracker.track(test::as_function(sc.field), {}, P, short_anchors),
                    Catch::Contains("anchors") && Catch::Contains("rows"));
  Positions bad = sc.start;
  bad(2, 1) = std::numeric_limits<float>::infinity();
  CHECK_THROWS_WITH(tracker.track(test::as_function(sc.field), {}, P, bad),
                    Catch::Contains("anchors vertex 2") && Catch::Contains("not finite"));
  CHECK(P == sc.start);  // nothing written on a refused call
  // The energy solve has no tangential step for a relaxation mask to scale: a mask below 1 is
  // refused with the fix (its anchors), all ones is accepted.
  IsoSurfaceTracker energy(sc.mesh.V, sc.mesh.F, sc.iso, options_for(Relaxation::kEnergy));
  energy.set_relaxation_mask(std::vector<float>(nv, 1.f));
  CHECK_THROWS_WITH(energy.set_relaxation_mask(std::vector<float>(nv, 0.5f)),
                    Catch::Contains("energy solve") && Catch::Contains("set_anchor_stiffness"));
}
