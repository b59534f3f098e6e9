// SPDX-License-Identifier: MIT
// The distance field of a mesh part (fit.h, `fit_part_distance`; docs/decisions/
// part-fields-from-the-mesh.md): its 0.5 iso-surface is the part's own skin, −∇f follows the vertex
// normals, it vanishes on its support's faces and does not take in a neighbour's vertices. The
// agreement figures are asserted on the shapes the HRBF of ~50 samples cannot follow: a low-poly
// tube, a hand with five thin fingers on one bone, two limbs side by side, an open border.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>

#include "isokit/core/error.h"
#include "isokit/core/math.h"
#include "isokit/implicit/fit.h"
#include "isokit/implicit/fit_quality.h"

using namespace isokit;
using namespace isokit::implicit;

namespace {

/// A tube around the axis from `a` along +z of `length`, `segments` sides, `rings` rings, radius
/// R, outward triangles; `cap_top` / `cap_bottom` close an end with a fan to a point `tip`
/// beyond it (0: a flat fan).
void add_tube(MeshPart& m, const Vec3d& a, double R, double length, int segments, int rings, bool cap_bottom,
              bool cap_top, double tip = 0) {
  const int base = int(m.vertices.size());
  for (int k = 0; k < rings; ++k)
    for (int s = 0; s < segments; ++s) {
      const double t = 2 * kPi * (s + 0.5 * (k % 2)) / segments;
      m.vertices.push_back(a + Vec3d{R * std::cos(t), R * std::sin(t), length * k / (rings - 1)});
    }
  for (int k = 0; k + 1 < rings; ++k)
    for (int s = 0; s < segments; ++s) {
      const int p = base + k * segments + s, q = base + k * segments + (s + 1) % segments;
      const int u = p + segments, w = q + segments;
      if (k % 2 == 0) {
        m.triangles.push_back({p, q, u});
        m.triangles.push_back({q, w, u});
      } else {
        m.triangles.push_back({p, q, w});
        m.triangles.push_back({p, w, u});
      }
    }
  if (cap_bottom) {
    const int c = int(m.vertices.size());
    m.vertices.push_back(a + Vec3d{0, 0, -tip});
    for (int s = 0; s < segments; ++s) m.triangles.push_back({base + (s + 1) % segments, base + s, c});
  }
  if (cap_top) {
    const int c = int(m.vertices.size()), top = base + (rings - 1) * segments;
    m.vertices.push_back(a + Vec3d{0, 0, length + tip});
    for (int s = 0; s < segments; ++s) m.triangles.push_back({top + s, top + (s + 1) % segments, c});
  }
}

MeshPart low_poly_tube(int segments) {
  MeshPart m;
  m.name = "tube";
  add_tube(m, {0, 0, 0}, 0.3, 1.0, segments, 7, false, false);
  m.bone_start = {0, 0, 0};
  m.bone_end = {0, 0, 1};
  return m;
}

/// A closed ellipsoid with semi-axes `axes` around `centre` (`rings` × `segments` UV sphere),
/// outward triangles.
void add_ellipsoid(MeshPart& m, const Vec3d& centre, const Vec3d& axes, int rings, int segments) {
  const int base = int(m.vertices.size());
  m.vertices.push_back(centre + Vec3d{0, 0, -axes.z});
  for (int k = 1; k < rings; ++k) {
    const double phi = kPi * k / rings;
    for (int s = 0; s < segments; ++s) {
      const double t = 2 * kPi * s / segments;
      m.vertices.push_back(centre + Vec3d{axes.x * std::sin(phi) * std::cos(t),
                                          axes.y * std::sin(phi) * std::sin(t), -axes.z * std::cos(phi)});
    }
  }
  m.vertices.push_back(centre + Vec3d{0, 0, axes.z});
  const int top = int(m.vertices.size()) - 1;
  auto at = [&](int k, int s) { return base + 1 + (k - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; ++s) m.triangles.push_back({base, at(1, s + 1), at(1, s)});
  for (int k = 1; k + 1 < rings; ++k)
    for (int s = 0; s < segments; ++s) {
      m.triangles.push_back({at(k, s), at(k, s + 1), at(k + 1, s + 1)});
      m.triangles.push_back({at(k, s), at(k + 1, s + 1), at(k + 1, s)});
    }
  for (int s = 0; s < segments; ++s) m.triangles.push_back({at(rings - 1, s), at(rings - 1, s + 1), top});
}

constexpr double kFingerRadius = 0.06;
double finger_x(int f) {
  return -0.36 + 0.18 * f;
}

/// A palm (a flat ellipsoid) with five thin fingers (closed 8-sided tubes) rooted in it, all on
/// one bone along +z — separate overlapping pieces, as game characters are often modelled.
MeshPart hand() {
  MeshPart m;
  m.name = "hand";
  add_ellipsoid(m, {0, 0, 0.4}, {0.5, 0.15, 0.4}, 16, 24);
  for (int f = 0; f < 5; ++f)
    add_tube(m, {finger_x(f), 0, 0.45}, kFingerRadius, 0.75 + 0.05 * (f % 3), 8, 10, true, true, 0.05);
  m.bone_start = {0, 0.01, 0.1};
  m.bone_end = {0, 0.01, 1.4};
  return m;
}

/// The hand's vertices on the surface of the union: not a finger's inside the palm, nor the
/// palm's inside a finger.
bool on_hand_surface(const Vec3d& p) {
  const Vec3d q{p.x / 0.5, p.y / 0.15, (p.z - 0.4) / 0.4};
  if (dot(q, q) < 1 - 1e-6) return false;
  for (int f = 0; f < 5; ++f)
    if (p.z > 0.45 && std::hypot(p.x - finger_x(f), p.y) < kFingerRadius * std::cos(kPi / 8) - 1e-9)
      return false;
  return true;
}

std::vector<Vec3d> normals_of(const MeshPart& m) {
  return area_weighted_normals(m.vertices, m.triangles);
}

FieldAgreement agreement(const FittedPart& f, const MeshPart& m) {
  return field_agreement(*f.field(), f.local_to_world, m.vertices, normals_of(m));
}

float value_at(const FittedPart& f, const Vec3d& world) {
  const Vec3d l = f.local_to_world.apply_inverse(world);
  return f.field()->eval({float(l.x), float(l.y), float(l.z)}).value;
}

PartFitOptions distance_options() {
  PartFitOptions o;
  o.field = PartFitOptions::FieldKind::distance;
  return o;
}

}  // namespace

TEST_CASE("distance field: a low-poly tube's skin is its iso-surface, normals agree", "[fit][distance]") {
  for (int segments : {8, 12, 24}) {
    CAPTURE(segments);
    const MeshPart m = low_poly_tube(segments);
    const FittedPart f = fit_part(m, distance_options());
    REQUIRE(f.grid);
    CHECK(f.local == nullptr);
    CHECK(f.closure_points == 2);  // a dome over each open end
    const FieldAgreement a = agreement(f, m);
    CHECK(a.points == int(m.vertices.size()));
    CHECK(a.over_limit == 0);
    CHECK(a.angle_p95 <= 20.0);
    // Trilinear interpolation rounds the corners of the facets: within half a cell.
    const double cell = double(f.grid->support().size().x) / (f.grid->resolution() - 1);
    CHECK(a.distance_p95 <= 0.5 * cell);
    // Inside the tube at mid length; outside beyond its radius.
    CHECK(value_at(f, {0, 0, 0.5}) > 0.9f);
    CHECK(value_at(f, {0.45, 0, 0.5}) < 0.5f);
  }
}

TEST_CASE("distance field: the HRBF of 50 samples does not follow an 8-sided tube as closely",
          "[fit][distance]") {
  const MeshPart m = low_poly_tube(8);
  const FieldAgreement d = agreement(fit_part(m, distance_options()), m);
  const FieldAgreement h = agreement(fit_part(m, PartFitOptions{}), m);
  CHECK(d.distance_p95 < h.distance_p95);
  CHECK(d.angle_p95 <= h.angle_p95 + 1.0);
}

TEST_CASE("distance field: a hand with five thin fingers on one bone", "[fit][distance]") {
  const MeshPart m = hand();
  const FittedPart f = fit_part(m, distance_options());
  // The spacing follows the fingers: at least three cells across one.
  const double cell = double(f.grid->support().size().x) / (f.grid->resolution() - 1);
  CHECK(cell <= 2 * kFingerRadius / 3 * 1.01);
  CHECK(f.grid->resolution() <= 96);
  const std::vector<Vec3d> normals = normals_of(m);
  std::vector<Vec3d> surface, surface_normals;
  for (std::size_t i = 0; i < m.vertices.size(); ++i)
    if (on_hand_surface(m.vertices[i]))
      surface.push_back(m.vertices[i]), surface_normals.push_back(normals[i]);
  REQUIRE(surface.size() > 300);
  const FieldAgreement a = field_agreement(*f.field(), f.local_to_world, surface, surface_normals);
  CHECK(a.over_limit == 0);
  CHECK(a.angle_p95 <= 20.0);
  CHECK(a.distance_p95 <= 0.5 * cell);
  // The HRBF of 50 samples cannot follow the fingers.
  const FittedPart h = fit_part(m, PartFitOptions{});
  const FieldAgreement ha = field_agreement(*h.field(), h.local_to_world, surface, surface_normals);
  CHECK(ha.distance_p95 > 3 * a.distance_p95);
  // Between two fingers is outside; inside a finger is inside.
  CHECK(value_at(f, {0.5 * (finger_x(1) + finger_x(2)), 0, 1.0}) < 0.5f);
  CHECK(value_at(f, {finger_x(2), 0, 1.0}) > 0.5f);
}

TEST_CASE("distance field: two limbs side by side do not take in each other's vertices", "[fit][distance]") {
  // Two closed tubes 2 % of their radius apart.
  const double R = 0.3, gap = 0.02 * R;
  MeshPart a, b;
  a.name = "left";
  b.name = "right";
  add_tube(a, {-R - gap / 2, 0, 0}, R, 1.0, 16, 9, true, true, 0.15);
  add_tube(b, {R + gap / 2, 0, 0}, R, 1.0, 16, 9, true, true, 0.15);
  a.bone_start = {-R - gap / 2, 0, 0};
  a.bone_end = {-R - gap / 2, 0, 1};
  b.bone_start = {R + gap / 2, 0, 0};
  b.bone_end = {R + gap / 2, 0, 1};
  const FittedPart fa = fit_part(a, distance_options()), fb = fit_part(b, distance_options());
  CHECK(fa.closure_points == 0);  // closed: nothing to cap
  int captured = 0;
  for (const Vec3d& v : b.vertices) captured += value_at(fa, v) > 0.5f ? 1 : 0;
  for (const Vec3d& v : a.vertices) captured += value_at(fb, v) > 0.5f ? 1 : 0;
  CHECK(captured == 0);
  for (const auto* pair : {&a, &b}) {
    const FieldAgreement g = agreement(pair == &a ? fa : fb, *pair);
    CHECK(g.over_limit == 0);
    CHECK(g.angle_p95 <= 20.0);
  }
}

TEST_CASE("distance field: an open border is closed by a dome that meets the skin smoothly",
          "[fit][distance]") {
  MeshPart m;
  m.name = "finger";
  add_tube(m, {0, 0, 0}, 0.2, 1.0, 16, 9, false, true, 0.1);  // open at the joint end (z = 0)
  m.bone_start = {0, 0, 0};
  m.bone_end = {0, 0, 1};
  const FittedPart f = fit_part(m, distance_options());
  CHECK(f.closure_points == 1);
  // The rim's vertices: the field's surface leaves them along the tube's wall.
  MeshPart rim = m;
  std::vector<Vec3d> normals = normals_of(m), rim_normals;
  rim.vertices.clear();
  for (std::size_t i = 0; i < m.vertices.size(); ++i)
    if (std::abs(m.vertices[i].z) < 1e-12)
      rim.vertices.push_back(m.vertices[i]), rim_normals.push_back(normals[i]);
  REQUIRE(rim.vertices.size() == 16);
  const FieldAgreement a = field_agreement(*f.field(), f.local_to_world, rim.vertices, rim_normals);
  CHECK(a.over_limit == 0);
  CHECK(a.angle_max <= 25.0);
  CHECK(a.distance_max <= 0.5 * double(f.grid->support().size().x) / (f.grid->resolution() - 1));
  // The dome closes the part: inside just below the rim on the axis, outside beyond the dome.
  CHECK(value_at(f, {0, 0, -0.05}) > 0.5f);
  CHECK(value_at(f, {0, 0, -0.3}) < 0.5f);
}

TEST_CASE("distance field: compact support, finite data, gradients match the values", "[fit][distance]") {
  const MeshPart m = hand();
  const FittedPart f = fit_part(m, distance_options());
  const GridField& g = *f.grid;
  const Box3f box = g.support();
  const int n = g.resolution();
  const std::vector<float>& nodes = g.nodes();
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const bool face = i == 0 || j == 0 || k == 0 || i == n - 1 || j == n - 1 || k == n - 1;
        const float* node = &nodes[4 * ((std::size_t(k) * n + j) * n + i)];
        if (face) REQUIRE(node[0] == 0.f);
        REQUIRE(std::isfinite(node[1]));
      }
  // Gradient against central differences of the value, near the surface, at cell centres.
  const Vec3f cell = box.size() / float(n - 1);
  int checked = 0;
  for (std::size_t v = 0; v < m.vertices.size(); v += 7) {
    const Vec3d l = f.local_to_world.apply_inverse(m.vertices[v]);
    const Vec3f p{float(l.x), float(l.y), float(l.z)};
    const FieldSample s = g.eval(p);
    const float gl = norm(s.gradient);
    REQUIRE(gl > 0.f);
    Vec3f fd;
    for (int a = 0; a < 3; ++a) {
      Vec3f e{};
      e[a] = cell[a];
      fd[a] = (g.eval(p + e).value - g.eval(p - e).value) / (2 * cell[a]);
    }
    // Within 30° of each other (the stored gradient is interpolated, not differentiated).
    CHECK(dot(fd, s.gradient) >= std::cos(30 * kPi / 180) * norm(fd) * gl);
    ++checked;
  }
  CHECK(checked > 20);
}

TEST_CASE("distance field: bad input is a one-line error naming the part", "[fit][distance]") {
  MeshPart m = low_poly_tube(8);
  PartFitOptions o = distance_options();
  o.distance.cells_per_feature = 0;
  CHECK_THROWS_WITH(fit_part(m, o), Catch::Contains("tube: distance.cells_per_feature"));
  o = distance_options();
  m.triangles[3][1] = 999;
  CHECK_THROWS_WITH(fit_part(m, o), Catch::Contains("tube: triangle 3"));
  m = low_poly_tube(8);
  m.vertices[2].x = std::nan("");
  CHECK_THROWS_AS(fit_part(m, o), InputError);
  // A flat sheet with its border capped flat encloses nothing.
  MeshPart sheet;
  sheet.name = "sheet";
  sheet.vertices = {{0, 0, 0.2}, {1, 0, 0.2}, {1, 1, 0.2}, {0, 1, 0.2}};
  sheet.triangles = {{0, 1, 2}, {0, 2, 3}};
  sheet.bone_start = {0.5, 0.5, 0};
  sheet.bone_end = {0.5, 0.5, 1};
  o.distance.cap_height = 0;
  CHECK_THROWS_WITH(fit_part(sheet, o), Catch::Contains("no inside"));
}

TEST_CASE("distance field: smoothing passes turn the gradient gradually round a low-poly corner",
          "[fit][distance]") {
  const MeshPart m = low_poly_tube(8);
  // The largest turn of the gradient between consecutive points of a ring just outside the
  // tube's corners, at mid length.
  auto largest_turn = [&](const FittedPart& f) {
    double worst = 0;
    Vec3f prev{};
    for (int k = 0; k <= 720; ++k) {
      const double t = 2 * kPi * k / 720;
      const Vec3d w{0.31 * std::cos(t), 0.31 * std::sin(t), 0.5};
      const Vec3d l = f.local_to_world.apply_inverse(w);
      const Vec3f g = f.field()->eval({float(l.x), float(l.y), float(l.z)}).gradient;
      if (k > 0) {
        const double c = dot(g, prev) / (norm(g) * norm(prev));
        worst = std::max(worst, std::acos(std::clamp(c, -1.0, 1.0)) * 180 / kPi);
      }
      prev = g;
    }
    return worst;
  };
  PartFitOptions o = distance_options();
  const FittedPart sharp = fit_part(m, o);
  o.distance.smoothing_passes = 2;
  const FittedPart smooth = fit_part(m, o);
  CHECK(largest_turn(smooth) < largest_turn(sharp));
  const FieldAgreement a = agreement(smooth, m);
  CHECK(a.over_limit == 0);
  CHECK(a.angle_p95 <= 20.0);
  // Rounding the corners moves the level off them, by about a cell at most.
  const double cell = double(smooth.grid->support().size().x) / (smooth.grid->resolution() - 1);
  CHECK(a.distance_max <= 1.5 * cell);
  // Still compact: 0 on the faces.
  CHECK(smooth.grid->nodes()[0] == 0.f);
  o.distance.smoothing_passes = 9;
  CHECK_THROWS_WITH(fit_part(m, o), Catch::Contains("tube: distance.smoothing_passes"));
}
