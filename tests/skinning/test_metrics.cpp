// SPDX-License-Identifier: MIT
// Property tests of the geometric skin metrics on meshes built here (spheres, tori, constructed
// intersections, duplicated and degenerate triangles).
#include <catch2/catch.hpp>

#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <utility>

#include "isokit/core/error.h"
#include "isokit/skinning/metrics.h"
#include "mesh_fixture.h"
#include "test_util.h"

using namespace isokit;
using namespace isokit::skinning;
using track::Positions;
using track::Triangles;

namespace {

using testing::from_lists;
using testing::icosphere;
using testing::join;
using testing::kPi;
using testing::Mesh;
using testing::orient_outward;
using testing::vtx;

/// UV sphere with `rings` latitude bands and `segments` longitudes (welded poles).
Mesh uv_sphere(int rings, int segments, double radius = 1) {
  std::vector<Eigen::Vector3d> v = {{0, 0, radius}, {0, 0, -radius}};
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double th = kPi * r / rings, ph = 2 * kPi * s / segments;
      v.emplace_back(radius * std::sin(th) * std::cos(ph), radius * std::sin(th) * std::sin(ph),
                     radius * std::cos(th));
    }
  auto id = [&](int r, int s) { return 2 + (r - 1) * segments + (s % segments); };
  std::vector<std::array<int, 3>> f;
  for (int s = 0; s < segments; ++s) {
    f.push_back({0, id(1, s), id(1, s + 1)});
    f.push_back({1, id(rings - 1, s + 1), id(rings - 1, s)});
    for (int r = 1; r + 1 < rings; ++r) {
      f.push_back({id(r, s), id(r + 1, s), id(r + 1, s + 1)});
      f.push_back({id(r, s), id(r + 1, s + 1), id(r, s + 1)});
    }
  }
  Mesh m = from_lists(v, f);
  orient_outward(m, [](const Eigen::Vector3d&) -> Eigen::Vector3d { return Eigen::Vector3d::Zero(); });
  return m;
}

Mesh torus(double big_r, double small_r, int nu, int nv) {
  std::vector<Eigen::Vector3d> v;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * kPi * i / nu, w = 2 * kPi * j / nv;
      v.emplace_back((big_r + small_r * std::cos(w)) * std::cos(u),
                     (big_r + small_r * std::cos(w)) * std::sin(u), small_r * std::sin(w));
    }
  auto id = [&](int i, int j) { return (i % nu) * nv + (j % nv); };
  std::vector<std::array<int, 3>> f;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      f.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      f.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  Mesh m = from_lists(v, f);
  orient_outward(m, [&](const Eigen::Vector3d& c) -> Eigen::Vector3d {
    return Eigen::Vector3d(c.x(), c.y(), 0).normalized() * big_r;
  });
  return m;
}

Mesh transformed(const Mesh& m, const Eigen::Matrix3d& r, const Eigen::Vector3d& t, double scale = 1) {
  Mesh out = m;
  for (Eigen::Index i = 0; i < m.v.rows(); ++i)
    out.v.row(i) = (scale * (r * vtx(m, i)) + t).cast<float>().transpose();
  return out;
}

Eigen::Vector3d random_shift(test::Rng& rng, double range) {
  const Vec3d t = rng.vec(-range, range);
  return {t.x, t.y, t.z};
}

Eigen::Matrix3d random_rotation(test::Rng& rng) {
  const Mat3T<double> q = rng.rotation();
  Eigen::Matrix3d r;
  for (int i = 0; i < 9; ++i) r(i / 3, i % 3) = q.m[i];
  return r;
}

/// Möller–Trumbore segment / triangle test in double (an independent, inexact reference).
bool segment_hits(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& a,
                  const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d d = q - p, e1 = b - a, e2 = c - a;
  const Eigen::Vector3d h = d.cross(e2);
  const double det = e1.dot(h);
  if (std::abs(det) < 1e-300) return false;
  const Eigen::Vector3d s = p - a;
  const double u = s.dot(h) / det;
  if (u < 0 || u > 1) return false;
  const Eigen::Vector3d qv = s.cross(e1);
  const double w = d.dot(qv) / det;
  if (w < 0 || u + w > 1) return false;
  const double t = e2.dot(qv) / det;
  return t >= 0 && t <= 1;
}

/// Brute-force count over pairs of triangles sharing no vertex (generic positions: two
/// non-coplanar triangles intersect iff an edge of one crosses the other).
int brute_force_disjoint_pairs(const Mesh& m) {
  int count = 0;
  for (Eigen::Index f = 0; f < m.f.rows(); ++f)
    for (Eigen::Index g = f + 1; g < m.f.rows(); ++g) {
      bool shares = false;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) shares = shares || m.f(f, i) == m.f(g, j);
      if (shares) continue;
      const Eigen::Vector3d a[3] = {vtx(m, m.f(f, 0)), vtx(m, m.f(f, 1)), vtx(m, m.f(f, 2))};
      const Eigen::Vector3d b[3] = {vtx(m, m.f(g, 0)), vtx(m, m.f(g, 1)), vtx(m, m.f(g, 2))};
      bool hit = false;
      for (int k = 0; k < 3 && !hit; ++k)
        hit = segment_hits(a[k], a[(k + 1) % 3], b[0], b[1], b[2]) ||
              segment_hits(b[k], b[(k + 1) % 3], a[0], a[1], a[2]);
      count += hit ? 1 : 0;
    }
  return count;
}

/// Icosphere of level 2 with vertex 0 pushed through the opposite side.
Mesh pushed_through_sphere(int* pushed) {
  Mesh m = icosphere(2);
  const Eigen::Vector3d p = vtx(m, 0);
  m.v.row(0) = (-1.5 * p).cast<float>().transpose();
  *pushed = 0;
  return m;
}

int si(const Mesh& m, SelfIntersectionDetails* d = nullptr, SelfIntersectionOptions o = {}) {
  return count_self_intersections(m.v, m.f, d, o);
}

}  // namespace

TEST_CASE("self-intersections: clean closed meshes have none at any resolution", "[skinning][metrics]") {
  for (int level = 0; level <= 4; ++level) {
    SelfIntersectionDetails d;
    CHECK(si(icosphere(level, 0.3 + level), &d) == 0);
    CHECK(d.degenerate_count == 0);
    CHECK(d.pairs.empty());
  }
  for (int n : {3, 4, 8, 33, 100}) CHECK(si(uv_sphere(n, n + 1, 2.0)) == 0);
  CHECK(si(torus(1.0, 0.3, 48, 24)) == 0);
  CHECK(si(torus(1.0, 0.3, 5, 3)) == 0);
  // Far-apart copies of a sphere in one mesh: still none.
  CHECK(si(join(icosphere(3), icosphere(3, 1, {2.5, 0.1, 0}))) == 0);
}

TEST_CASE("self-intersections: clean fine sphere (163842 vertices)", "[skinning][metrics][slow]") {
  const Mesh m = icosphere(7);
  REQUIRE(m.v.rows() == 163842);
  SelfIntersectionDetails d;
  CHECK(si(m, &d) == 0);
  CHECK(d.degenerate_count == 0);
}

TEST_CASE("self-intersections: constructed pairs of triangles", "[skinning][metrics]") {
  using V = Eigen::Vector3d;
  auto count = [](const std::vector<V>& v, const std::vector<std::array<int, 3>>& f) {
    const Mesh m = from_lists(v, f);
    return si(m);
  };
  SECTION("no shared vertex: crossing, touching at a point, apart") {
    CHECK(count({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, -1}, {0.5, 0.5, 1}, {3, 3, 0}},
                {{0, 1, 2}, {3, 4, 5}}) == 1);
    // A corner of the second triangle exactly on the first one's interior: touching counts.
    CHECK(count({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, 0}, {0.5, 0.5, 1}, {1, 2, 1}},
                {{0, 1, 2}, {3, 4, 5}}) == 1);
    CHECK(count({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, 0.25}, {0.5, 0.5, 1}, {1, 2, 1}},
                {{0, 1, 2}, {3, 4, 5}}) == 0);
  }
  SECTION("shared edge: only a fold onto each other counts") {
    const std::vector<V> v = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0.3, 0.6, 0}, {0.5, 0.5, 1}};
    CHECK(count(v, {{0, 1, 2}, {1, 3, 2}}) == 0);  // flat quad
    CHECK(count(v, {{0, 1, 2}, {1, 5, 2}}) == 0);  // hinge
    CHECK(count(v, {{0, 1, 2}, {1, 4, 2}}) == 1);  // folded flat on the same side
    CHECK(count(v, {{0, 1, 2}, {2, 4, 1}}) == 1);  // ... either orientation
  }
  SECTION("shared vertex: counted only beyond it") {
    const std::vector<V> v = {{0, 0, 0},    {1, 0, 0},     {0, 1, 0},    {-1, 0, 0},  {0, -1, 0},
                              {1, 1, 0},    {1, 0.2, -1},  {1, 0.2, 1},  {-1, -1, 1}, {2, 0, 0},
                              {0.5, -1, 0}, {0.2, 0.2, 0}, {0.2, 0.1, 0}};
    CHECK(count(v, {{0, 1, 2}, {0, 3, 4}}) == 0);    // coplanar, opposite quadrants
    CHECK(count(v, {{0, 1, 2}, {0, 5, 3}}) == 1);    // coplanar, overlapping wedges
    CHECK(count(v, {{0, 1, 2}, {0, 6, 7}}) == 1);    // crossing out of plane
    CHECK(count(v, {{0, 1, 2}, {0, 8, 7}}) == 0);    // out of plane, meets the plane only at 0
    CHECK(count(v, {{0, 1, 2}, {0, 9, 10}}) == 1);   // coplanar, edge along edge (a segment)
    CHECK(count(v, {{0, 1, 2}, {0, 11, 4}}) == 1);   // coplanar, wedges overlap partly
    CHECK(count(v, {{0, 1, 2}, {0, 12, 11}}) == 1);  // coplanar, small triangle inside
  }
  SECTION("duplicated triangles, either orientation") {
    const std::vector<V> v = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    CHECK(count(v, {{0, 1, 2}, {0, 1, 2}}) == 1);
    CHECK(count(v, {{0, 1, 2}, {0, 2, 1}}) == 1);
    CHECK(count(v, {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}}) == 3);
  }
  SECTION("symmetric cross of two squares: four pairs, two of them touching at one point") {
    const std::vector<V> v = {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1},
                              {0, -1, -1}, {0, 1, -1}, {0, 1, 1}, {0, -1, 1}};
    const std::vector<std::array<int, 3>> f = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
    Mesh m = from_lists(v, f);
    SelfIntersectionDetails d;
    CHECK(si(m, &d) == 4);
    CHECK(d.pairs == std::vector<std::array<int, 2>>{{0, 2}, {0, 3}, {1, 2}, {1, 3}});
    // Exact quarter turns and integer shifts keep the point contacts exact.
    Eigen::Matrix3d quarter;
    quarter << 0, -1, 0, 1, 0, 0, 0, 0, 1;
    Eigen::Matrix3d quarter_x;
    quarter_x << 1, 0, 0, 0, 0, -1, 0, 1, 0;
    CHECK(si(transformed(m, quarter, {3, -2, 7})) == 4);
    CHECK(si(transformed(m, quarter_x * quarter, {-5, 1, 2})) == 4);
  }
}

TEST_CASE("self-intersections: overlapping spheres match a brute-force reference", "[skinning][metrics]") {
  test::Rng rng(7);
  const Mesh a = icosphere(2);
  for (const Eigen::Vector3d& offset :
       {Eigen::Vector3d(1.03, 0.07, 0.11), Eigen::Vector3d(0.4, 0.3, -0.2), Eigen::Vector3d(1.6, 0.2, 0.1)}) {
    const Mesh m = join(a, icosphere(2, 0.8, offset));
    SelfIntersectionDetails d;
    const int n = si(m, &d);
    CHECK(n > 0);
    CHECK(n == brute_force_disjoint_pairs(m));
    // Every pair has one triangle from each sphere.
    for (const auto& p : d.pairs) CHECK((p[0] < a.f.rows() && p[1] >= a.f.rows()));
    // Invariant under rigid motions.
    for (int k = 0; k < 3; ++k) CHECK(si(transformed(m, random_rotation(rng), random_shift(rng, 5))) == n);
  }
  CHECK(si(join(a, icosphere(2, 0.8, {2.5, 0.2, 0.1}))) == 0);
}

TEST_CASE("self-intersections: a vertex pushed through the opposite side", "[skinning][metrics]") {
  int pushed = -1;
  const Mesh m = pushed_through_sphere(&pushed);
  SelfIntersectionDetails d;
  const int n = si(m, &d);
  CHECK(n > 0);
  CHECK(n == brute_force_disjoint_pairs(m));  // pairs sharing a vertex do not intersect here
  for (const auto& p : d.pairs) {
    const bool touches_pushed =
        (m.f.row(p[0]).array() == pushed).any() || (m.f.row(p[1]).array() == pushed).any();
    CHECK(touches_pushed);
  }
  test::Rng rng(11);
  for (int k = 0; k < 3; ++k) CHECK(si(transformed(m, random_rotation(rng), {0.3, -2, 1})) == n);
}

TEST_CASE("self-intersections: a duplicated triangle in a sphere gives exactly one pair",
          "[skinning][metrics]") {
  Mesh m = icosphere(2);
  const Eigen::Index nf = m.f.rows();
  m.f.conservativeResize(nf + 1, 3);
  m.f.row(nf) = m.f.row(17);
  SelfIntersectionDetails d;
  CHECK(si(m, &d) == 1);
  CHECK(d.pairs == std::vector<std::array<int, 2>>{{17, static_cast<int>(nf)}});
}

TEST_CASE("self-intersections: degenerate triangles are reported, not tested", "[skinning][metrics]") {
  Mesh m = icosphere(1);
  const Eigen::Index nv = m.v.rows(), nf = m.f.rows();
  m.v.conservativeResize(nv + 2, 3);
  m.v.row(nv) << 0.f, 0.f, 0.f;   // collinear with two opposite sphere vertices...
  m.v.row(nv + 1) = -m.v.row(0);  // ... through the centre, crossing the sphere surface?
  m.f.conservativeResize(nf + 3, 3);
  m.f.row(nf) << 0, static_cast<int>(nv), static_cast<int>(nv + 1);  // collinear: 0, centre, -0
  m.f.row(nf + 1) << 1, 1, 2;                                        // repeated index
  m.f.row(nf + 2) << static_cast<int>(nv), static_cast<int>(nv), static_cast<int>(nv);  // a point
  REQUIRE(m.v.row(nv + 1).cast<double>().norm() > 0);
  SelfIntersectionDetails d;
  CHECK(si(m, &d) == 0);
  CHECK(d.degenerate_count == 3);
  CHECK(d.degenerate_faces ==
        std::vector<int>{static_cast<int>(nf), static_cast<int>(nf + 1), static_cast<int>(nf + 2)});
}

TEST_CASE("self-intersections: serial and parallel agree, pair list is capped", "[skinning][metrics]") {
  const Mesh m = join(icosphere(3), icosphere(3, 0.9, {0.7, 0.3, 0.1}));
  SelfIntersectionDetails serial, parallel;
  SelfIntersectionOptions o;
  o.grain = 0;
  o.max_pairs = 1 << 20;
  const int n = si(m, &serial, o);
  for (std::size_t grain : {1, 7, 64, 1000}) {  // many thin slabs down to one triangle each
    o.grain = grain;
    CHECK(si(m, &parallel, o) == n);
    CHECK(serial.pairs == parallel.pairs);
    CHECK(serial.candidate_pairs == parallel.candidate_pairs);
  }
  REQUIRE(static_cast<int>(serial.pairs.size()) == n);
  SelfIntersectionDetails capped;
  o.max_pairs = 3;
  CHECK(si(m, &capped, o) == n);
  REQUIRE(capped.pairs.size() == 3);
  for (int i = 0; i < 3; ++i)
    CHECK(capped.pairs[static_cast<std::size_t>(i)] == serial.pairs[static_cast<std::size_t>(i)]);
  CHECK(capped.candidate_pairs >= n);
}

TEST_CASE("self-intersections: bad indices throw and name the triangle", "[skinning][metrics]") {
  Mesh m = icosphere(0);
  m.f(5, 1) = 99;
  CHECK_THROWS_AS(si(m), InputError);
  CHECK_THROWS_WITH(si(m), Catch::Contains("triangle 5") && Catch::Contains("99"));
  m.f(5, 1) = -1;
  CHECK_THROWS_AS(si(m), InputError);
  m.f(5, 1) = 2;
  m.v(3, 1) = std::numeric_limits<float>::quiet_NaN();
  CHECK_THROWS_WITH(si(m), Catch::Contains("vertex 3"));
  CHECK(count_self_intersections(Positions(0, 3), Triangles(0, 3)) == 0);
}

TEST_CASE("volume: converges to the sphere's, flips with orientation, ignores translation",
          "[skinning][metrics]") {
  const double r = 2.0, exact = 4.0 / 3.0 * kPi * r * r * r;
  double previous = 1e9;
  for (int level = 1; level <= 5; ++level) {
    const double err =
        std::abs(enclosed_volume(icosphere(level, r).v, icosphere(level, r).f) - exact) / exact;
    CHECK(err < previous);
    previous = err;
  }
  CHECK(previous < 2e-3);
  const Mesh s = icosphere(3, r, {10, -20, 5});
  const double vol = enclosed_volume(s.v, s.f);
  CHECK(vol > 0);
  Triangles flipped = s.f;
  flipped.col(1).swap(flipped.col(2));
  CHECK(enclosed_volume(s.v, flipped) == Approx(-vol).epsilon(1e-12));
  CHECK(vol == Approx(enclosed_volume(icosphere(3, r).v, icosphere(3, r).f)).epsilon(1e-5));
  // A unit cube, exactly.
  const Mesh cube = from_lists(
      {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}, {{0, 2, 1},
                                                                                                 {0, 3, 2},
                                                                                                 {4, 5, 6},
                                                                                                 {4, 6, 7},
                                                                                                 {0, 1, 5},
                                                                                                 {0, 5, 4},
                                                                                                 {1, 2, 6},
                                                                                                 {1, 6, 5},
                                                                                                 {2, 3, 7},
                                                                                                 {2, 7, 6},
                                                                                                 {3, 0, 4},
                                                                                                 {3, 4, 7}});
  CHECK(enclosed_volume(cube.v, cube.f) == Approx(1.0).epsilon(1e-12));
  CHECK(enclosed_volume(torus(1, 0.25, 64, 32).v, torus(1, 0.25, 64, 32).f) ==
        Approx(2 * kPi * kPi * 1 * 0.25 * 0.25).epsilon(1e-2));
}

TEST_CASE("edge distortion: zero for rigid motions, |s - 1| for a uniform scale", "[skinning][metrics]") {
  test::Rng rng(3);
  const Mesh m = icosphere(3);
  for (int k = 0; k < 5; ++k) {
    const EdgeDistortion d =
        edge_distortion(m.v, transformed(m, random_rotation(rng), random_shift(rng, 3)).v, m.f);
    CHECK(d.max < 1e-5);
    CHECK(d.mean < 1e-6);
    CHECK(d.edges == 30 * 64);
    CHECK(d.zero_rest_edges == 0);
  }
  for (double s : {0.5, 1.5, 3.0}) {
    const EdgeDistortion d =
        edge_distortion(m.v, transformed(m, Eigen::Matrix3d::Identity(), {1, 2, 3}, s).v, m.f);
    CHECK(d.mean == Approx(std::abs(s - 1)).margin(1e-5));
    CHECK(d.max == Approx(std::abs(s - 1)).margin(1e-5));
  }
  // One triangle stretched along x by 2: edges 1 -> 2, 1 -> 1, sqrt(2) -> sqrt(5).
  const Mesh t = from_lists({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
  const EdgeDistortion d =
      edge_distortion(t.v, transformed(t, Eigen::Vector3d(2, 1, 1).asDiagonal(), {0, 0, 0}).v, t.f);
  CHECK(d.edges == 3);
  CHECK(d.max == Approx(1.0));
  CHECK(d.worst_edge == std::array<int, 2>{0, 1});
  CHECK(d.mean == Approx((1 + 0 + (std::sqrt(5.0 / 2.0) - 1)) / 3));
  CHECK_THROWS_AS(edge_distortion(t.v, m.v, t.f), InputError);
}

TEST_CASE("displacement and bounding box", "[skinning][metrics]") {
  const Mesh m = icosphere(2, 2.0, {1, 1, 1});
  CHECK(bbox_diagonal(m.v) == Approx(4 * std::sqrt(3.0)).epsilon(1e-6));
  CHECK(bbox_diagonal(Positions(0, 3)) == 0);
  CHECK(bounding_box(Positions(0, 3)).isEmpty());
  CHECK(max_displacement(m.v, m.v) == 0);
  Positions moved = m.v;
  moved.row(7) += Eigen::RowVector3f(0, 3, 4);
  moved.row(9) += Eigen::RowVector3f(1, 0, 0);
  CHECK(max_displacement(m.v, moved) == Approx(5.0));
  CHECK_THROWS_AS(max_displacement(m.v, Positions(3, 3)), InputError);
}

TEST_CASE("frame metrics: evaluator over poses, worst of a clip", "[skinning][metrics]") {
  const Mesh m = icosphere(3);
  const FrameMetricsEvaluator eval(m.v, m.f);
  const FrameMetrics rest = eval.evaluate(m.v);
  CHECK(rest.self_intersections == 0);
  CHECK(rest.degenerate_faces == 0);
  CHECK(rest.volume_ratio == Approx(1.0));
  CHECK(rest.edge_distortion_max == 0);
  CHECK(rest.max_displacement == 0);
  CHECK(rest.rest_distance == 0);
  CHECK(std::isnan(rest.iso_residual_max));
  CHECK(rest.inverted_triangles == -1);
  const FrameMetrics big = eval.evaluate(transformed(m, Eigen::Matrix3d::Identity(), {0, 0, 0}, 1.1).v);
  CHECK(big.volume_ratio == Approx(1.331).epsilon(1e-5));
  CHECK(big.edge_distortion_mean == Approx(0.1).epsilon(1e-4));
  CHECK(big.rest_distance == Approx(0.1 / eval.rest_diagonal()).epsilon(1e-5));
  int pushed = 0;
  const Mesh broken = pushed_through_sphere(&pushed);
  const FrameMetricsEvaluator eval2(icosphere(2).v, icosphere(2).f);
  const FrameMetrics bad = eval2.evaluate(broken.v);
  CHECK(bad.self_intersections > 0);
  FrameMetrics small = rest;
  small.volume_ratio = 0.8;
  small.inverted_triangles = 2;
  const FrameMetrics w = worst_of(worst_of(rest, big), small);
  CHECK(w.volume_ratio == Approx(1.331).epsilon(1e-5));  // farther from 1 than 0.8
  CHECK(w.edge_distortion_mean == Approx(0.1).epsilon(1e-4));
  CHECK(w.inverted_triangles == 2);
  CHECK(w.self_intersections == 0);
  CHECK(std::isnan(w.iso_residual_mean));
  CHECK_THROWS_AS(eval.evaluate(Positions(4, 3)), InputError);
}

namespace {

/// `m` without its triangle `f` (an open border of three edges).
Mesh without_triangle(const Mesh& m, Eigen::Index f) {
  Mesh out = m;
  out.f.resize(m.f.rows() - 1, 3);
  for (Eigen::Index i = 0, k = 0; i < m.f.rows(); ++i)
    if (i != f) out.f.row(k++) = m.f.row(i);
  return out;
}

/// The positions of `whole` with the rows from `first` on replaced by `part`'s.
Positions with_rows(const Positions& whole, Eigen::Index first, const Positions& part) {
  Positions p = whole;
  p.bottomRows(whole.rows() - first) = part;
  return p;
}

}  // namespace

TEST_CASE("closed meshes: open borders, non-manifold and misoriented edges, components",
          "[skinning][metrics]") {
  const Mesh sphere = icosphere(2);
  const MeshClosure whole = mesh_closure(sphere.f, sphere.v.rows());
  REQUIRE(whole.components.size() == 1);
  CHECK(whole.closed());
  CHECK(whole.components[0].triangles == sphere.f.rows());

  const Mesh open = without_triangle(sphere, 5);
  const MeshClosure o = mesh_closure(open.f, open.v.rows());
  CHECK_FALSE(o.closed());
  CHECK(o.components[0].border_edges == 3);
  // A fin on an edge of the sphere: that edge has three triangles.
  Mesh fin = sphere;
  fin.v.conservativeResize(fin.v.rows() + 1, 3);
  fin.v.row(fin.v.rows() - 1) << 3.f, 0.f, 0.f;
  fin.f.conservativeResize(fin.f.rows() + 1, 3);
  fin.f.row(fin.f.rows() - 1) << sphere.f(0, 0), sphere.f(0, 1), static_cast<int>(fin.v.rows() - 1);
  const MeshClosure fc = mesh_closure(fin.f, fin.v.rows());
  CHECK_FALSE(fc.closed());
  CHECK(fc.components[0].non_manifold_edges == 1);
  CHECK(fc.components[0].border_edges == 2);
  // One triangle turned over: its three edges are traversed the same way twice.
  Mesh flipped = sphere;
  std::swap(flipped.f(7, 1), flipped.f(7, 2));
  const MeshClosure mc = mesh_closure(flipped.f, flipped.v.rows());
  CHECK_FALSE(mc.closed());
  CHECK(mc.components[0].misoriented_edges == 3);

  // Two closed spheres and an open one: three components, two closed.
  const Mesh two = join(sphere, icosphere(1, 0.5, {3, 0, 0}));
  const Mesh three = join(two, without_triangle(icosphere(1, 0.5, {-3, 0, 0}), 0));
  const MeshClosure c = mesh_closure(three.f, three.v.rows());
  REQUIRE(c.components.size() == 3);
  CHECK(c.closed_components() == 2);
  CHECK_FALSE(c.closed());
  CHECK(c.component[0] == 0);
  CHECK(c.component[static_cast<std::size_t>(three.f.rows() - 1)] == 2);
  CHECK_THROWS_WITH(mesh_closure(sphere.f, 3), Catch::Contains("triangle"));
}

TEST_CASE("frame metrics: volume over the closed components only", "[skinning][metrics]") {
  // An open mesh: no volume at all.
  const Mesh open = without_triangle(icosphere(2), 5);
  const FrameMetricsEvaluator eo(open.v, open.f);
  CHECK_FALSE(eo.closure().closed());
  CHECK(eo.rest_volume() == 0);
  const FrameMetrics mo = eo.evaluate(transformed(open, Eigen::Matrix3d::Identity(), {0, 0, 0}, 1.1).v);
  CHECK(std::isnan(mo.volume));
  CHECK(std::isnan(mo.volume_ratio));
  CHECK(mo.edge_distortion_mean == Approx(0.1).epsilon(1e-4));

  // Two closed spheres: the ratio of their summed volumes; an open third part is left out.
  const Mesh a = icosphere(2), b = icosphere(2, 0.5, {3, 0, 0});
  const Mesh two = join(a, b);
  const Mesh three = join(two, without_triangle(icosphere(1, 0.5, {-3, 0, 0}), 0));
  const FrameMetricsEvaluator e2(two.v, two.f), e3(three.v, three.f);
  CHECK(e2.closure().closed_components() == 2);
  CHECK(e2.rest_volume() == Approx(enclosed_volume(a.v, a.f) + enclosed_volume(b.v, b.f)).epsilon(1e-9));
  CHECK(e3.rest_volume() == Approx(e2.rest_volume()).epsilon(1e-9));
  // Scale the second sphere by 2 about its centre (volume × 8) and the open part by 3: only the
  // closed ones count.
  Positions posed = three.v;
  posed.middleRows(a.v.rows(), b.v.rows()) = transformed(b, Eigen::Matrix3d::Identity(), {-3, 0, 0}, 2).v;
  posed.bottomRows(three.v.rows() - two.v.rows()) *= 3.f;
  const double va = enclosed_volume(a.v, a.f), vb = enclosed_volume(b.v, b.f);
  CHECK(e3.evaluate(posed).volume_ratio == Approx((va + 8 * vb) / (va + vb)).epsilon(1e-5));
}

TEST_CASE("self-intersections: new pairs exclude the rest pairs by identity", "[skinning][metrics]") {
  // At rest spheres A and B overlap (rest pairs); C is far away.
  const Mesh a = icosphere(2), b = icosphere(2, 0.8, {1.03, 0.07, 0.11}), c = icosphere(1, 0.5, {6, 0, 0});
  const Mesh rest = join(join(a, b), c);
  const FrameMetricsEvaluator eval(rest.v, rest.f);
  const int rest_pairs = si(join(a, b));
  REQUIRE(rest_pairs > 0);
  CHECK(static_cast<int>(eval.rest_pairs().size()) == rest_pairs);
  const FrameMetrics at_rest = eval.evaluate(rest.v);
  CHECK(at_rest.self_intersections == rest_pairs);
  CHECK(at_rest.self_intersections_new == 0);

  // Pose 1: C moved into A. Its pairs with A are new; the rest pairs are not.
  const Mesh c_in = icosphere(1, 0.5, {-0.9, 0.1, 0.05});
  const Eigen::Index first_c = a.v.rows() + b.v.rows();
  const FrameMetrics m1 = eval.evaluate(with_rows(rest.v, first_c, c_in.v));
  const int ac = si(join(a, c_in));
  REQUIRE(ac > 0);
  CHECK(m1.self_intersections == rest_pairs + ac);
  CHECK(m1.self_intersections_new == ac);

  // Pose 2: B moved away too: fewer pairs than at rest, yet C's are new (a difference of counts
  // would say ac - rest_pairs).
  Positions p2 = with_rows(rest.v, first_c, c_in.v);
  p2.middleRows(a.v.rows(), b.v.rows()).rowwise() += Eigen::RowVector3f(0.f, 5.f, 0.f);
  const FrameMetrics m2 = eval.evaluate(p2);
  CHECK(m2.self_intersections == ac);
  CHECK(m2.self_intersections_new == ac);

  // Pose 3: B slid along A: some pairs stay, others are new; the new ones are those whose pair of
  // triangle indices is not in the rest list.
  Positions p3 = rest.v;
  p3.middleRows(a.v.rows(), b.v.rows()).rowwise() += Eigen::RowVector3f(0.f, 0.f, 0.3f);
  SelfIntersectionDetails d3;
  const Mesh m3mesh{p3, rest.f};
  si(m3mesh, &d3, [] {
    SelfIntersectionOptions o;
    o.max_pairs = 1 << 30;
    return o;
  }());
  int expected = 0;
  for (const auto& p : d3.pairs)
    expected += std::find(eval.rest_pairs().begin(), eval.rest_pairs().end(), p) == eval.rest_pairs().end();
  const FrameMetrics m3 = eval.evaluate(p3);
  CHECK(m3.self_intersections_new == expected);
  CHECK(expected > 0);
  CHECK(expected < m3.self_intersections);
  CHECK(worst_of(m1, m3).self_intersections_new == std::max(ac, expected));
  // Without the exact pass neither count is computed.
  CHECK(eval.evaluate(p3, false).self_intersections_new == -1);
}
