// SPDX-License-Identifier: MIT
// What the rest field tells the 2014 tracker (IsoSurfaceTracker::set_rest_field): the free
// vertices, where the field disagrees with the rest mesh, and the contact smoothing that keeps the
// rest detail (docs/tracking.md, "Free vertices" and step 4). The fixture reproduces what the
// Fox showed on a real rig: a union of two primitives whose crease crosses the skin, so that the
// field's inward direction on the skin's middle ring is more than 60° off the mesh normal.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include "isokit/implicit/primitives.h"
#include "isokit/track/tracker.h"
#include "test_util.h"
#include "track/track_fixtures.h"

using namespace isokit;
using namespace isokit::track;
using isokit::test::capsule_mesh;

namespace {

/// Two balls of radius 0.75 at y = ±0.6, composed by max (a union with a crease at y = 0), the
/// upper one turned by `angle` about z around the origin; the skin is a capsule of radius 0.3
/// from y = -0.6 to 0.6, inside both balls on its middle ring, where the balls' inward directions
/// are 63° off the capsule's. Driven like a two-bone limb: the previous result's upper half moves
/// rigidly with the upper ball, target rotations blend across the middle.
struct TwoBalls {
  test::Mesh mesh = capsule_mesh(0.3f, 0.6f, 16, 8, 4);
  float angle = 0.f;
  Positions P;
  std::vector<float> iso;

  TwoBalls() {
    P = mesh.V;
    iso = sample_iso_values(field(), mesh.V);
  }
  FieldFunction field() const {
    const implicit::SphereField low({0.f, -0.6f, 0.f}, 0.75f);
    const implicit::SphereField high(test::rot_z(angle) * Vec3f{0.f, 0.6f, 0.f}, 0.75f);
    return [low, high](const Vec3f* p, std::size_t n, float* v, Vec3f* g, std::uint8_t*) {
      for (std::size_t k = 0; k < n; ++k) {
        const implicit::FieldSample a = low.eval(p[k]), b = high.eval(p[k]);
        const implicit::FieldSample& m = a.value >= b.value ? a : b;
        v[k] = m.value;
        g[k] = m.gradient;
      }
    };
  }
  TrackStats step(IsoSurfaceTracker& tracker, float to) {
    test::ZLimb::turn_upper(mesh.V, to - angle, P);
    angle = to;
    return tracker.track(field(), test::ZLimb::rotations(mesh.V, angle), P);
  }
};

/// Bends the upper ball 0 -> max_deg -> 0 in 10° steps, then holds the rest pose for 10 calls;
/// returns the rest recovery (max distance to the rest mesh / its bounding-box diagonal).
float bend_and_hold(TwoBalls& t, IsoSurfaceTracker& tracker, int max_deg) {
  for (int deg = 10; deg <= max_deg; deg += 10) t.step(tracker, float(deg) * kPiF / 180.f);
  for (int deg = max_deg - 10; deg >= 0; deg -= 10) t.step(tracker, float(deg) * kPiF / 180.f);
  for (int k = 0; k < 10; ++k) t.step(tracker, 0.f);
  return test::max_distance(t.P, t.mesh.V) / test::diagonal(t.mesh.V);
}

int count(const std::vector<std::uint8_t>& flags) {
  return static_cast<int>(std::count(flags.begin(), flags.end(), std::uint8_t{1}));
}

/// The free-vertex rule at the angle docs/tracking.md measures (the default, 180, is off).
TrackerOptions free_at(float angle_deg) {
  TrackerOptions o;
  o.free_vertex_angle_deg = angle_deg;
  return o;
}

}  // namespace

TEST_CASE("rest field: a field that agrees with the mesh leaves no vertex free", "[track][rest_field]") {
  const test::Mesh m = capsule_mesh(0.5f, 0.f, 16, 0, 8);
  auto sphere = std::make_shared<implicit::SphereField>(Vec3f{0, 0, 0}, 0.5f);
  IsoSurfaceTracker tracker(m.V, m.F, sample_iso_values(test::as_function(sphere), m.V), free_at(60.f));
  tracker.set_rest_field(test::as_function(sphere));
  Positions P = m.V;
  const TrackStats s = tracker.track(test::as_function(sphere), {}, P);
  CHECK(s.free_vertices == 0);
  CHECK(count(tracker.flags().free) == 0);
  CHECK(P == m.V);
}

TEST_CASE("rest field: where the field's crease crosses the skin, those vertices are free",
          "[track][rest_field]") {
  TwoBalls t;
  IsoSurfaceTracker tracker(t.mesh.V, t.mesh.F, t.iso, free_at(60.f));
  tracker.set_rest_field(t.field());
  Positions P = t.mesh.V;
  const TrackStats s = tracker.track(t.field(), {}, P);
  // The middle ring (y = 0): the balls' inward directions are atan(0.6 / 0.3) = 63° off the
  // capsule's inward normal; the next rings (y = ±0.15) are 56° off, within the default 60°.
  const std::vector<std::uint8_t>& free = tracker.flags().free;
  REQUIRE(free.size() == std::size_t(t.mesh.V.rows()));
  for (Eigen::Index i = 0; i < t.mesh.V.rows(); ++i) {
    INFO("vertex " << i << " y " << t.mesh.V(i, 1));
    CHECK(free[std::size_t(i)] == (std::abs(t.mesh.V(i, 1)) < 1e-6f ? 1 : 0));
  }
  CHECK(s.free_vertices == 16);
  CHECK(P == t.mesh.V);  // the rest pose is still a fixed point, bit for bit
  CHECK(s.converged);

  SECTION("the default angle, 180, keeps every vertex held to its iso-value (2014)") {
    IsoSurfaceTracker paper(t.mesh.V, t.mesh.F, t.iso);
    paper.set_rest_field(t.field());
    Positions Q = t.mesh.V;
    CHECK(paper.track(t.field(), {}, Q).free_vertices == 0);
    CHECK(count(paper.flags().free) == 0);
  }
  SECTION("a larger angle frees fewer vertices, a smaller one more") {
    TrackerOptions o;
    o.free_vertex_angle_deg = 70.f;
    IsoSurfaceTracker wide(t.mesh.V, t.mesh.F, t.iso, o);
    wide.set_rest_field(t.field());
    o.free_vertex_angle_deg = 50.f;
    IsoSurfaceTracker narrow(t.mesh.V, t.mesh.F, t.iso, o);
    narrow.set_rest_field(t.field());
    Positions Q = t.mesh.V, R = t.mesh.V;
    CHECK(wide.track(t.field(), {}, Q).free_vertices == 0);
    CHECK(narrow.track(t.field(), {}, R).free_vertices == 48);  // y = 0 and ±0.15
  }
}

TEST_CASE("rest field: free vertices follow their neighbours, the limb returns to rest",
          "[track][rest_field]") {
  const int max_deg = GENERATE(30, 60);
  INFO("bend " << max_deg << " degrees");
  auto recovery = [&](float free_angle, bool keep_detail) {
    TwoBalls t;
    TrackerOptions o;
    o.free_vertex_angle_deg = free_angle;
    o.smoothing.keep_detail = keep_detail;
    IsoSurfaceTracker tracker(t.mesh.V, t.mesh.F, t.iso, o);
    tracker.set_rest_field(t.field());
    const float r = bend_and_hold(t, tracker, max_deg);
    const TrackStats s = t.step(tracker, 0.f);
    CHECK(s.free_vertices == (free_angle < 180.f ? 16 : 0));
    CHECK(s.max_residual <= 1e-3f);  // free vertices are left out of it
    CHECK(t.P.allFinite());
    return r;
  };
  // Free vertices (60°) with the 2013 smoothing: measured 2e-5 of the diagonal.
  CHECK(recovery(60.f, false) <= 1e-3f);
  // Keeping the rest detail in the contact smoothing brings it back too, alone (measured 4e-5)
  // or with the free vertices (2e-5) ...
  CHECK(recovery(180.f, true) <= 1e-3f);
  CHECK(recovery(60.f, true) <= 1e-3f);
  // ... and with neither (the defaults, 2014) the middle ring stays on the other ball's sheet
  // after the bend: measured 1.8e-2, the defect the Fox showed (docs/tracking.md, "Free
  // vertices").
  CHECK(recovery(180.f, false) > 1e-3f);
}

namespace {

// The ball of radius 0.5 at the origin.
FieldFunction ball_field() {
  return test::as_function(std::make_shared<implicit::SphereField>(Vec3f{0, 0, 0}, 0.5f));
}

// `plain` with its cap beyond 0.2 along `up` reported in contact: every call smooths it.
FieldFunction capped(FieldFunction plain, Vec3f up) {
  return [plain, up](const Vec3f* p, std::size_t n, float* v, Vec3f* g, std::uint8_t* c) {
    plain(p, n, v, g, c);
    if (c)
      for (std::size_t k = 0; k < n; ++k) c[k] = dot(p[k], up) > 0.2f ? 1 : 0;
  };
}

}  // namespace

TEST_CASE("rest field: contact smoothing keeps a rigidly moved coarse rest shape in place",
          "[track][rest_field]") {
  // A coarse ball (8 vertices around) whose upper cap the field reports in contact: every call
  // smooths it. Moved rigidly (turned by 40° about z), the mesh is on its iso-values with no
  // tangential stress, so only the smoothing can move it.
  const test::Mesh m = capsule_mesh(0.5f, 0.f, 8, 0, 4);
  const Mat3f r = test::rot_z(0.7f);
  const Vec3f up = r * Vec3f{0.f, 1.f, 0.f};
  const FieldFunction plain = ball_field();
  const FieldFunction field = capped(plain, up);
  Positions moved = m.V;
  for (Eigen::Index i = 0; i < moved.rows(); ++i) {
    const Vec3f q = r * Vec3f{m.V(i, 0), m.V(i, 1), m.V(i, 2)};
    moved.row(i) << q.x, q.y, q.z;
  }
  const std::vector<Mat3f> rots(std::size_t(m.V.rows()), r);
  const float diag = test::diagonal(m.V);
  auto run = [&](bool keep_detail) {
    TrackerOptions o;
    o.smoothing.keep_detail = keep_detail;
    IsoSurfaceTracker tracker(m.V, m.F, sample_iso_values(plain, m.V), o);
    Positions P = moved;
    const TrackStats s = tracker.track(field, rots, P);
    CHECK(s.contact_vertices > 0);
    CHECK(s.smoothed_vertices > s.contact_vertices);
    return test::max_distance(P, moved) / diag;
  };
  CHECK(run(true) <= 1e-5f);
  // 2013 eq. 7 (toward the centroid) flattens the cap: about a fifth of an edge here.
  CHECK(run(false) > 1e-2f);
}

TEST_CASE("contact smoothing in the tangent plane or re-projected moves no vertex into the body",
          "[track][rest_field]") {
  // The coarse ball of the test above, its cap reported in contact, pushed 2 % off its iso-values
  // (outward) so that the call has work: 2013 eq. 7 pulls the cap and the ring around it inward
  // by a fraction of an edge. In the tangent plane (SmoothingOptions::tangential) nothing moves
  // inward; followed by Newton sweeps (reproject_steps) the ring around the contact goes back on
  // its sphere (the contact vertices themselves stay where the smoothing flattened them).
  const test::Mesh m = capsule_mesh(0.5f, 0.f, 8, 0, 4);
  const FieldFunction plain = ball_field();
  const FieldFunction field = capped(plain, Vec3f{0.f, 1.f, 0.f});
  const std::vector<float> iso = sample_iso_values(plain, m.V);
  const float edge = 2.f * 3.14159265f * 0.5f / 8.f;
  // The largest move into the ball (radius lost) in edge lengths and the largest iso residual,
  // over the vertices smoothed but not in contact (the ring), or over every vertex (`all`).
  auto run = [&](bool tangential, int reproject, bool all) {
    TrackerOptions o;
    o.smoothing.tangential = tangential;
    o.smoothing.reproject_steps = reproject;
    IsoSurfaceTracker tracker(m.V, m.F, iso, o);
    Positions P = m.V * 1.02f;
    const TrackStats s = tracker.track(field, {}, P);
    CHECK(s.smoothed_vertices > s.contact_vertices);
    CHECK(P.allFinite());
    float inward = 0.f, residual = 0.f;
    std::vector<float> v(std::size_t(P.rows()));
    std::vector<Vec3f> g(v.size()), q(v.size());
    std::vector<std::uint8_t> c(v.size());
    for (Eigen::Index i = 0; i < P.rows(); ++i) q[std::size_t(i)] = Vec3f{P(i, 0), P(i, 1), P(i, 2)};
    plain(q.data(), q.size(), v.data(), g.data(), c.data());
    for (Eigen::Index i = 0; i < P.rows(); ++i) {
      const std::size_t k = std::size_t(i);
      const bool ring = tracker.flags().beta[k] > 0.f && !tracker.flags().contact[k];
      if (!all && !ring) continue;
      inward = std::max(inward, (m.V.row(i).norm() - P.row(i).norm()) / edge);
      residual = std::max(residual, std::abs(v[k] - iso[k]));
    }
    return std::pair<float, float>(inward, residual);
  };
  const auto paper = run(false, 0, true), tangential = run(true, 0, true);
  const auto ring = run(false, 0, false), reprojected = run(false, 3, false);
  INFO("inward (edges) / residual: 2013 " << paper.first << " / " << paper.second << " (ring " << ring.first
                                          << " / " << ring.second << "), tangential " << tangential.first
                                          << " / " << tangential.second << ", ring re-projected "
                                          << reprojected.first << " / " << reprojected.second);
  CHECK(paper.first > 0.05f);
  CHECK(tangential.first < 0.2f * paper.first);
  CHECK(ring.first > 0.01f);
  CHECK(reprojected.first < 0.2f * ring.first);
  CHECK(reprojected.second < 0.2f * ring.second);
}

TEST_CASE("rest field: vertices without a usable rest gradient are free, the output stays finite",
          "[track][rest_field][errors]") {
  // The rest field is 0 (outside its support) on the lower half and NaN on one vertex: those
  // vertices cannot be located, so they are free; the others are tracked as usual.
  const test::Mesh m = capsule_mesh(0.5f, 0.f, 12, 0, 6);
  auto sphere = std::make_shared<implicit::SphereField>(Vec3f{0, 0, 0}, 0.5f);
  const FieldFunction plain = test::as_function(sphere);
  const FieldFunction rest = [plain](const Vec3f* p, std::size_t n, float* v, Vec3f* g, std::uint8_t* c) {
    plain(p, n, v, g, c);
    for (std::size_t k = 0; k < n; ++k) {
      if (p[k].y < -1e-3f) v[k] = 0.f, g[k] = Vec3f{};
      if (k == 3) g[k] = Vec3f{std::nanf(""), 0.f, 0.f};
    }
  };
  IsoSurfaceTracker tracker(m.V, m.F, sample_iso_values(plain, m.V), free_at(60.f));
  tracker.set_rest_field(rest);
  Positions P = m.V * 1.05f;
  const TrackStats s = tracker.track(plain, {}, P);
  int lower = 0;
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) lower += m.V(i, 1) < -1e-3f ? 1 : 0;
  const std::vector<std::uint8_t>& free = tracker.flags().free;
  CHECK(free[3] == 1);
  CHECK(s.free_vertices == lower + (m.V(3, 1) < -1e-3f ? 0 : 1));
  CHECK(P.allFinite());
  CHECK(s.max_residual <= 1e-3f);
}
