// SPDX-License-Identifier: MIT
// Closing a part where its mesh ends (docs/skinning.md, "Decision: closing a part at its
// borders"): the border loops of a triangle set, the dome over a loop, and the fit that caps its
// borders, against the paper's closure points at the joints (2013 §4.1).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include "../../libimplicit/src/fit_caps.h"
#include "isokit/core/error.h"
#include "isokit/core/math.h"
#include "isokit/implicit/fit.h"
#include "isokit/implicit/fit_quality.h"

using namespace isokit;
using namespace isokit::implicit;
using detail::boundary_loops;
using detail::loop_cap;

namespace {

Vec3f to_f(const Vec3d& p) {
  return {float(p.x), float(p.y), float(p.z)};
}

/// An open tube of `rings` × `segments` vertices around the world y axis, y in [y0, y1], radius
/// R, outward triangles.
MeshPart tube(double R, double y0, double y1, int rings = 12, int segments = 16) {
  MeshPart m;
  for (int k = 0; k < rings; ++k)
    for (int s = 0; s < segments; ++s) {
      const double t = 2 * kPi * s / segments;
      m.vertices.push_back({R * std::cos(t), y0 + (y1 - y0) * k / (rings - 1), -R * std::sin(t)});
    }
  for (int k = 0; k + 1 < rings; ++k)
    for (int s = 0; s < segments; ++s) {
      const int a = k * segments + s, b = k * segments + (s + 1) % segments;
      m.triangles.push_back({a, b, b + segments});
      m.triangles.push_back({a, b + segments, a + segments});
    }
  return m;
}

std::vector<int> sorted(std::vector<int> v) {
  std::sort(v.begin(), v.end());
  return v;
}

}  // namespace

TEST_CASE("boundary loops: tubes, closed meshes, touching holes", "[fit][caps]") {
  const MeshPart t = tube(0.3, 0, 1, 5, 16);
  const auto loops = boundary_loops(t.triangles, int(t.vertices.size()));
  REQUIRE(loops.size() == 2);
  for (const auto& l : loops) {
    CHECK(l.size() == 16);
    // One ring each: every vertex of a loop at the same height.
    for (int v : l) CHECK(t.vertices[std::size_t(v)].y == t.vertices[std::size_t(l[0])].y);
  }
  // One triangle: its border runs as the triangle does.
  const auto one = boundary_loops({{0, 1, 2}}, 3);
  REQUIRE(one.size() == 1);
  CHECK(one[0] == std::vector<int>{0, 1, 2});
  // A closed tetrahedron has no border.
  CHECK(boundary_loops({{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}}, 4).empty());
  // Two holes touching at a vertex (a bow tie) are two loops, not one figure of eight.
  const auto bow = boundary_loops({{0, 1, 2}, {0, 3, 4}}, 5);
  REQUIRE(bow.size() == 2);
  CHECK(sorted(bow[0]) != sorted(bow[1]));
  for (const auto& l : bow) CHECK(l.size() == 3);
  // A band one triangle wide (every vertex on both borders): its two rings.
  std::vector<std::array<int, 3>> band;
  const int n = 12;
  for (int s = 0; s < n; ++s) {
    const int a = s, b = (s + 1) % n, c = n + s, d = n + (s + 1) % n;
    band.push_back({a, b, d});
    band.push_back({a, d, c});
  }
  const auto rings = boundary_loops(band, 2 * n);
  REQUIRE(rings.size() == 2);
  CHECK(rings[0].size() == std::size_t(n));
  CHECK(rings[1].size() == std::size_t(n));
  // Edges of three triangles are no border; an empty set has none.
  CHECK(boundary_loops({}, 0).empty());
}

TEST_CASE("a border cap is a dome out of the part, flat where the hole is in the part's side",
          "[fit][caps]") {
  // The top ring of a tube along y: the cap's normal points up (+y), out of the tube.
  const double R = 0.4;
  const MeshPart t = tube(R, 0, 1, 4, 24);
  std::vector<int> top;
  for (const auto& l : boundary_loops(t.triangles, int(t.vertices.size())))
    if (t.vertices[std::size_t(l[0])].y > 0.5) top = l;
  REQUIRE(top.size() == 24);
  for (double h : {0.0, 0.5, 1.0}) {
    INFO("height " << h);
    const auto cap = loop_cap(t.vertices, top, h, 0.1, {0, 1, 0});
    REQUIRE(cap.size() > 10);
    // The centre, lifted h R (the rim's mean radius is R cos(π/24)-ish: within 1 %).
    CHECK(cap[0].position.y == Approx(1 + h * R).margin(0.01 * R));
    CHECK(cap[0].normal.y == Approx(1.0));
    for (const auto& s : cap) {
      CHECK(norm(s.normal) == Approx(1.0));
      CHECK(s.normal.y > 0);                     // outward, up
      CHECK(s.position.y >= 1 - 1e-12);          // never below the rim
      CHECK(s.position.y <= 1 + h * R + 1e-12);  // never above the centre
      CHECK(std::hypot(s.position.x, s.position.z) < R);
      // The normal leans out as the dome falls towards the rim.
      const double rho = std::hypot(s.position.x, s.position.z);
      if (h > 0 && rho > 0.2 * R) CHECK(s.normal.x * s.position.x + s.normal.z * s.position.z > 0);
    }
  }
  // The same hole seen by a bone across it (a hole in the part's side): a flat cap.
  for (const auto& s : loop_cap(t.vertices, top, 1.0, 0.1, {1, 0, 0})) CHECK(s.position.y == Approx(1.0));
  // A slit (a border that goes and comes back) encloses nothing: no cap.
  const std::vector<Vec3d> slit{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {1, 1e-3, 0}};
  CHECK(loop_cap(slit, {0, 1, 2, 3}, 1.0, 0.1, {0, 1, 0}).empty());
}

TEST_CASE("border caps close a part where its mesh ends, wherever its joints are", "[fit][caps]") {
  // A limb whose joints are away from its mesh's ends (a real rig's root joint above its hips,
  // a partition border far from the joint): the tube spans y in [0, 1], the bone runs from
  // y = -0.5 to 1.6. The paper's closure points sit on the axis `s` beyond each joint; the
  // caps follow the borders.
  const double R = 0.25;
  MeshPart part = tube(R, 0, 1, 16, 24);
  part.name = "misplaced";
  part.bone_start = {0, -0.5, 0};
  part.bone_end = {0, 1.6, 0};
  PartFitOptions joints, caps, best;
  joints.closure = PartFitOptions::Closure::joints;
  caps.closure = PartFitOptions::Closure::border_caps;
  best.closure = PartFitOptions::Closure::best;
  const FittedPart fj = fit_part(part, joints), fc = fit_part(part, caps), fb = fit_part(part, best);
  INFO("error (vertex -> surface + surface -> part p95): joints "
       << fj.error / R << " R, caps " << fc.error / R << " R, best " << fb.error / R << " R");
  CHECK(fj.closure_points == 2);
  CHECK(fc.closure_points >= 8);  // two domes: a centre and a ring each (measured 10)
  CHECK(fc.error < 0.5 * fj.error);
  CHECK(fc.error <
        R);  // measured 0.88 R (the domes stand R above the flat fans the error measures to); joints 4.5 R
  CHECK(fb.error == fc.error);  // `best` keeps the smaller
  CHECK(fb.closure_points == fc.closure_points);
  // The caps' 0.5 level closes each end about a radius beyond it (cap height 1 R) and the
  // field vanishes well beyond; the joint closure's reaches the joints' spheres instead.
  auto value = [](const FittedPart& f, const Vec3d& w) {
    return f.field()->eval(to_f(f.local_to_world.apply_inverse(w))).value;
  };
  CHECK(value(fc, {0, 0.5, 0}) > 0.5);
  CHECK(value(fc, {0, 1 + 0.5 * R, 0}) > 0.5);
  CHECK(value(fc, {0, 1 + 1.6 * R, 0}) < 0.5);
  CHECK(value(fc, {0, -1.6 * R, 0}) < 0.5);
  PartFitOptions bad = caps;
  bad.cap_height = 2.5;
  CHECK_THROWS_WITH(fit_part(part, bad),
                    Catch::Contains("misplaced: cap_height") && Catch::Contains("[0, 2]"));
}
