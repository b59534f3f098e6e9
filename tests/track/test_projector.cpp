// SPDX-License-Identifier: MIT
// The 2013 projector: Newton steps (σ = 0.35), 55° contact stop, MVC relaxation, smoothing.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "isokit/core/error.h"
#include "isokit/track/projector2013.h"
#include "isokit/track/tracker.h"
#include "test_util.h"
#include "track/track_fixtures.h"

using namespace isokit;
using namespace isokit::track;
using isokit::test::capsule_mesh;

namespace {

/// Synthetic field for the contact rule: f = 0.5 - 0.1 z (iso 0.5 at z = 0), whose reported
/// gradient direction is turned by `turn` radians about y below z = 0.5.
FieldFunction turning_field(float turn) {
  return [turn](const Vec3f* p, std::size_t n, float* v, Vec3f* g, std::uint8_t*) {
    for (std::size_t k = 0; k < n; ++k) {
      v[k] = 0.5f - 0.1f * p[k].z;
      const float a = p[k].z < 0.5f ? turn : 0.f;
      g[k] = Vec3f{std::sin(a), 0.f, -std::cos(a)} * 0.1f;
    }
  };
}

test::Mesh single_triangle(float z, float size = 1.f) {
  test::Mesh m;
  m.V.resize(3, 3);
  m.V << 0, 0, z, size, 0, z, 0, size, z;
  m.F.resize(1, 3);
  m.F << 0, 1, 2;
  return m;
}

}  // namespace

TEST_CASE("projector 2013: contact stop triggers at the stated angle", "[track][projector]") {
  const test::Mesh rest = single_triangle(0.f);
  for (const bool secant : {false, true})
    for (const float deg : {50.f, 54.f, 56.f, 70.f}) {
      ProjectorOptions o;
      o.secant = secant;
      Projector2013 proj(rest.V, rest.F, turning_field(0.f), o);
      Positions P = single_triangle(1.f).V;
      const TrackStats s = proj.project(turning_field(deg * kPiF / 180.f), P);
      INFO("turn " << deg << (secant ? ", secant steps" : ", σ steps"));
      const bool stopped = deg > 55.f;
      CHECK(s.contact_vertices == (stopped ? 3 : 0));
      if (stopped) {
        // Stopped right after crossing z = 0.5, before any further step: σ steps go 1, 0.65,
        // 0.4225; the secant's second step is 0.7 x the full Newton step, 0.65 -> 0.195.
        const float lowest = secant ? 0.19f : 0.42f;
        for (int i = 0; i < 3; ++i) CHECK((P(i, 2) < 0.5f && P(i, 2) > lowest));
      } else {
        CHECK(s.max_residual <= o.tolerance);
      }
    }
  // The 2014 tracker applies the same rule when angle_contacts is on.
  TrackerOptions o;
  o.smoothing.smoothing_steps = 0;
  IsoSurfaceTracker t(rest.V, rest.F, std::vector<float>(3, 0.5f), o);
  Positions P = single_triangle(1.f).V;
  CHECK(t.track(turning_field(60.f * kPiF / 180.f), {}, P).contact_vertices == 3);
  P = single_triangle(1.f).V;
  CHECK(t.track(turning_field(50.f * kPiF / 180.f), {}, P).contact_vertices == 0);
}

TEST_CASE("projector 2013: MVC relaxation leaves the rest pose unchanged", "[track][projector]") {
  const test::Mesh m = capsule_mesh(0.3f, 0.6f, 20, 16, 5);
  auto cap = std::make_shared<implicit::CapsuleField>(Vec3f{0, -0.6f, 0}, Vec3f{0, 0.6f, 0}, 0.3f);
  const FieldFunction f = test::as_function(cap);
  Projector2013 proj(m.V, m.F, f);
  std::vector<Vec3f> normals(static_cast<std::size_t>(m.V.rows()));
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) {
    const Vec3f g = cap->eval(Vec3f{m.V(i, 0), m.V(i, 1), m.V(i, 2)}).gradient;
    normals[static_cast<std::size_t>(i)] = g / norm(g);
  }
  const float diag = test::diagonal(m.V);
  Positions P = m.V;
  proj.relax(normals, 1.f, P);  // full relaxation (μ = 1)
  CHECK(test::max_distance(P, m.V) <= 1e-5f * diag);
  // ...whereas a distorted pose is moved.
  Positions Q = m.V;
  for (Eigen::Index i = 0; i < Q.rows(); i += 3) Q(i, 1) += 0.02f;
  Positions Q0 = Q;
  proj.relax(normals, 1.f, Q);
  CHECK(test::max_distance(Q, Q0) > 1e-3f);
  // A full projection from the rest pose with μ forced to 1 also stays put.
  ProjectorOptions o;
  o.mu = 1.f;
  Projector2013 proj1(m.V, m.F, f, o);
  Positions R = m.V;
  const TrackStats s = proj1.project(f, R);
  CHECK(test::max_distance(R, m.V) <= 1e-5f * diag);
  CHECK(s.contact_vertices == 0);
  CHECK(s.inverted_triangles == 0);
}

TEST_CASE("projector 2013: elbow poses are projected onto their iso-values", "[track][projector]") {
  const test::Mesh m = capsule_mesh(0.3f, 1.0f, 24, 32, 6);
  test::ElbowField field(0.3f, 1.0f, 48);
  Projector2013 proj(m.V, m.F, field.function());
  for (const float deg : {45.f, 90.f}) {
    const float a = deg * kPiF / 180.f;
    field.set_angle(a);
    // Initial pose: smooth skinning about the joint (rotation by a weight blended across it).
    Positions P = m.V;
    for (Eigen::Index i = 0; i < P.rows(); ++i) {
      const float w = std::clamp((m.V(i, 1) + 0.3f) / 0.6f, 0.f, 1.f);
      const Vec3f q = test::rot_z(a * w * w * (3.f - 2.f * w)) * Vec3f{P(i, 0), P(i, 1), P(i, 2)};
      P.row(i) << q.x, q.y, q.z;
    }
    const TrackStats s = proj.project(field.function(), P);
    INFO("angle " << deg << " residual " << s.max_residual << " contacts " << s.contact_vertices);
    CHECK(s.max_residual <= 1e-3f);
    CHECK(P.allFinite());
    CHECK(s.lost_vertices == 0);
  }
}

namespace {

/// f = 0.5 - 0.1 z (iso 0.5 at z = 0), whose reported gradient is `scale` times the true one:
/// scale < 1/σ makes σ Newton steps overshoot and grow the residual (a Newton 2-cycle's worst case).
FieldFunction scaled_gradient_field(float scale) {
  return [scale](const Vec3f* p, std::size_t n, float* v, Vec3f* g, std::uint8_t*) {
    for (std::size_t k = 0; k < n; ++k) {
      v[k] = 0.5f - 0.1f * p[k].z;
      g[k] = Vec3f{0.f, 0.f, -0.1f * scale};
    }
  };
}

/// max |f - iso| at `P` over the vertices not in contact or lost (what TrackStats::max_residual reports).
float recomputed_max_residual(const FieldFunction& f, const Projector2013& proj, const Positions& P) {
  const std::vector<float> v = sample_iso_values(f, P);
  float mx = 0.f;
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!proj.flags().contact[i] && !proj.flags().lost[i] && !(proj.flags().beta[i] > 0.f))
      mx = std::max(mx, std::abs(v[i] - proj.iso_values()[i]));
  return mx;
}

}  // namespace

TEST_CASE("projector 2013: vertices at their iso-value take one evaluation each", "[track][projector]") {
  const test::Mesh m = capsule_mesh(0.3f, 0.6f, 20, 16, 5);
  const FieldFunction f = test::as_function(
      std::make_shared<implicit::CapsuleField>(Vec3f{0, -0.6f, 0}, Vec3f{0, 0.6f, 0}, 0.3f));
  for (const bool paper : {false, true}) {
    ProjectorOptions o;
    if (paper) o.secant = false, o.stall_steps = 0, o.tolerance = 1e-4f;
    Projector2013 proj(m.V, m.F, f, o);
    Positions P = m.V;
    const TrackStats s = proj.project(f, P);
    const long n = static_cast<long>(m.V.rows());
    CHECK(s.converged);
    CHECK(s.iterations == 1);
    CHECK(s.field_evaluations == n);
    CHECK(test::max_distance(P, m.V) == 0.f);
  }
}

TEST_CASE("projector 2013: every vertex ends within the tolerance, reported as measured",
          "[track][projector]") {
  // Random radial offsets of a capsule's vertices (± 40 % of the radius) projected back with
  // isokit's rules and with the paper's σ steps: every call ends before the cap with every
  // vertex at its iso-value, the residual statistics equal the field at the returned positions,
  // and the secant steps need fewer evaluations.
  const test::Mesh m = capsule_mesh(0.3f, 0.6f, 20, 16, 5);
  const FieldFunction f = test::as_function(
      std::make_shared<implicit::CapsuleField>(Vec3f{0, -0.6f, 0}, Vec3f{0, 0.6f, 0}, 0.3f));
  test::Rng rng(7);
  for (int trial = 0; trial < 8; ++trial) {
    Positions start = m.V;
    for (Eigen::Index i = 0; i < start.rows(); ++i) {
      Vec3f p{start(i, 0), start(i, 1), start(i, 2)};
      const Vec3f axis{0.f, std::clamp(p.y, -0.6f, 0.6f), 0.f};
      p = axis + (p - axis) * static_cast<float>(1.0 + rng.uniform(-0.4, 0.4));
      start.row(i) << p.x, p.y, p.z;
    }
    long evaluations[2] = {0, 0};
    for (const bool secant : {false, true}) {
      ProjectorOptions o;
      o.secant = secant;
      Projector2013 proj(m.V, m.F, f, o);
      Positions P = start;
      const TrackStats s = proj.project(f, P);
      INFO("trial " << trial << (secant ? ", secant steps" : ", σ steps"));
      CHECK(s.converged);
      CHECK(s.stalled_vertices == 0);
      CHECK(s.contact_vertices == 0);
      CHECK(s.max_residual <= o.tolerance);
      CHECK(s.max_residual == recomputed_max_residual(f, proj, P));
      evaluations[secant] = s.field_evaluations;
    }
    CHECK(evaluations[1] < evaluations[0]);
  }
}

TEST_CASE("projector 2013: a vertex making no progress stops by rule, not at the cap", "[track][projector]") {
  // A triangle of edges 20 (a Newton step may reach 10): the steps are not clamped.
  const test::Mesh rest = single_triangle(0.f, 20.f);
  const FieldFunction wrong = scaled_gradient_field(0.1f);  // σ steps of 3.5x the distance
  SECTION("σ steps: the residual grows, the stall rule stops it; without the rule the cap does") {
    for (const int stall : {3, 0}) {
      ProjectorOptions o;
      o.secant = false;
      o.stall_steps = stall;
      Projector2013 proj(rest.V, rest.F, turning_field(0.f), o);
      Positions P = single_triangle(1.f, 20.f).V;
      const TrackStats s = proj.project(wrong, P);
      INFO("stall_steps " << stall);
      CHECK(s.converged == (stall > 0));
      CHECK(s.iterations == (stall > 0 ? stall + 1 : o.max_iterations));
      CHECK(s.stalled_vertices == (stall > 0 ? 3 : 0));
      CHECK(P.allFinite());
    }
  }
  SECTION("secant steps: the overshoot brackets the iso-value and the secant lands on it") {
    Projector2013 proj(rest.V, rest.F, turning_field(0.f));
    Positions P = single_triangle(1.f, 20.f).V;
    const TrackStats s = proj.project(wrong, P);
    CHECK(s.converged);
    CHECK(s.stalled_vertices == 0);
    CHECK(s.iterations == 3);  // the σ step, the secant step, the evaluation at the iso-value
    CHECK(s.max_residual <= ProjectorOptions{}.tolerance);
    for (int i = 0; i < 3; ++i) CHECK(std::abs(P(i, 2)) <= 1e-2f);
  }
}

TEST_CASE("projector 2013: bad input", "[track][projector][errors]") {
  const test::Mesh m = capsule_mesh(0.5f, 0.f, 8, 0, 4);
  auto f = test::as_function(std::make_shared<implicit::SphereField>(Vec3f{0, 0, 0}, 0.5f));
  ProjectorOptions o;
  o.sigma = 2.f;
  CHECK_THROWS_WITH(Projector2013(m.V, m.F, f, o), Catch::Contains("sigma"));
  for (const auto& [set, key] : std::vector<std::pair<void (*)(ProjectorOptions&), const char*>>{
           {[](ProjectorOptions& p) { p.stall_steps = 300; }, "stall_steps"},
           {[](ProjectorOptions& p) { p.progress = 0.f; }, "progress"},
           {[](ProjectorOptions& p) { p.secant_max_factor = 1.5f; }, "secant_max_factor"},
           {[](ProjectorOptions& p) { p.tolerance = -1.f; }, "tolerance"}}) {
    ProjectorOptions bad;
    set(bad);
    CHECK_THROWS_WITH(Projector2013(m.V, m.F, f, bad), Catch::Contains(key));
  }
  Triangles F = m.F;
  F(1, 0) = -3;
  CHECK_THROWS_WITH(Projector2013(m.V, F, f), Catch::Contains("triangle 1"));
  Projector2013 p(m.V, m.F, f);
  Positions short_p = m.V.topRows(2);
  CHECK_THROWS_WITH(p.project(f, short_p), Catch::Contains("initial positions"));
}
