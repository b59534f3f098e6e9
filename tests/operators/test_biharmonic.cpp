// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include <cmath>

#include "isokit/core/error.h"
#include "isokit/operators/biharmonic.h"
#include "isokit/operators/checks.h"
#include "test_util.h"

using namespace isokit;
using namespace isokit::operators;

namespace {

void check_slices(const OperatorSpec& spec, const GridOperator& g) {
  const double h = 1.0 / (g.nf() - 1);
  for (int k = 0; k < g.nd(); ++k) {
    const SliceReport r = inspect_slice(spec, g, k);
    INFO(spec.name << " res " << g.nf() << " slice " << k << " d = " << r.d);
    CHECK(r.boundary_error <= 1e-5);
    CHECK(r.axis_slope <= 1e-5);
    CHECK(r.iso_to_profile <= h);
    CHECK(r.profile_to_iso <= h);
    CHECK(r.contact_error <= h);
    // Zero normal derivative through the interpolation too (what Newton steps see), except
    // within 3 cells of the origin where g(f1, 0) = f1 and ∂g/∂f1(0, f2) = 0 conflict.
    for (double f = 3 * h; f <= 1.0; f += 0.0625) {
      CHECK(std::abs(g.eval(0.f, float(f), float(r.d)).dg1) <= 1e-3);
      CHECK(std::abs(g.eval(float(f), 0.f, float(r.d)).dg2) <= 1e-3);
    }
  }
}

}  // namespace

TEST_CASE("biharmonic presets: boundary conditions, axes, 0.5 iso-line on the profile (res 32)",
          "[operators][biharmonic]") {
  for (const auto& name : preset_spec_names()) {
    const OperatorSpec spec = preset_spec(name, 32);
    check_slices(spec, generate_operator(spec));
  }
}

TEST_CASE("check_operator: presets pass, a broken edge or a foreign profile fails, naming check and slice",
          "[operators][checks]") {
  for (const auto& name : preset_spec_names()) {
    const OperatorSpec spec = preset_spec(name, 32);
    const GridOperator g = generate_operator(spec);
    INFO(name);
    CHECK_FALSE(check_operator(spec, g).has_value());
  }
  const OperatorSpec contact = preset_spec("contact", 32);
  const GridOperator g = generate_operator(contact);
  // One boundary node off eq. 1 in the last slice: the boundary check fails there.
  GridOperator broken = g;
  const int last = g.nd() - 1, n = g.nf();
  broken.data()[(static_cast<std::size_t>(last) * n + 5) * n + (n - 1)] += 0.01f;
  const auto edge = check_operator(contact, broken);
  REQUIRE(edge.has_value());
  CHECK(edge->slice == last);
  CHECK(edge->check.find("boundary") != std::string::npos);
  CHECK(edge->message().find("slice " + std::to_string(last)) == 0);
  // The bulge grid against the contact spec: its 0.5 iso-line is not the contact profile's.
  const auto foreign = check_operator(contact, generate_operator(preset_spec("bulge", 32)));
  REQUIRE(foreign.has_value());
  CHECK(foreign->check.find("iso-line") != std::string::npos);
  CHECK(foreign->d > 0.0);
  CHECK_FALSE(foreign->fix.empty());
}

TEST_CASE("biharmonic presets at 64 and with 65 (odd) nodes", "[operators][biharmonic][slow]") {
  for (int res : {64, 65})
    for (const auto& name : preset_spec_names()) {
      const OperatorSpec spec = preset_spec(name, res);
      check_slices(spec, generate_operator(spec));
    }
}

TEST_CASE("contact operator g_dc: contact length 0 at d = 0 and increasing with d",
          "[operators][biharmonic]") {
  for (int res : {32, 48}) {
    const GridOperator g = generate_operator(preset_spec("contact", res));
    const double h = 1.0 / (res - 1);
    double prev = -1;
    for (int k = 0; k < g.nd(); ++k) {
      const double len = contact_length(g, k);
      INFO("res " << res << " slice " << k << " length " << len);
      if (k == 0) CHECK(len < 0.1 * h);
      CHECK(len > prev);
      // Within a cell of the specified end point (.5 + 0.4 d) on the diagonal.
      CHECK(std::abs(len - 0.4 * g.slice_d(k) * std::sqrt(2.0)) <= h * std::sqrt(2.0));
      prev = len;
    }
  }
  // The clean union never has a contact line.
  const GridOperator u = generate_operator(preset_spec("clean-union", 32));
  for (int k = 0; k < u.nd(); ++k) CHECK(contact_length(u, k) < 0.1 / 31);
}

TEST_CASE("contact line end point: the paper's (.5 + d/sqrt2) leaves the square and is rejected",
          "[operators][biharmonic]") {
  OperatorSpec spec = preset_spec("contact", 32);
  spec.curves[1].keyframes[1].points[1] = {0.5 + 1 / std::sqrt(2.0), 0.5 + 1 / std::sqrt(2.0)};
  CHECK_THROWS_WITH(validate(spec, "s.json"), Catch::Contains("curves[1].keyframes[1].points[1]") &&
                                                  Catch::Contains("outside the unit square"));
  // The preset's end point keeps g = 0.5 on the line and reaches g(1, 1) = 1 at the corner.
  const GridOperator g = generate_operator(preset_spec("contact", 32));
  const int last = g.nd() - 1;
  CHECK(g.eval(0.9f, 0.9f, 1.f).g == Approx(0.5).margin(1.0 / 31));
  CHECK(g.eval(1.f, 1.f, 1.f).g == Approx(1.0).margin(1e-6));
  CHECK(inspect_slice(preset_spec("contact", 32), g, last).boundary_error <= 1e-5);
}

TEST_CASE("bulge operator g_db inflates with d", "[operators][biharmonic]") {
  const OperatorSpec spec = preset_spec("bulge", 32);
  const GridOperator g = generate_operator(spec);
  // Points just outside the clean union's L become inside as the profile inflates toward the
  // origin; at d = 0 the operator is the clean union (the same as the clean-union preset).
  for (const auto& p : {Point2{0.30, 0.46}, Point2{0.46, 0.30}, Point2{0.40, 0.40}}) {
    CHECK(g.eval(float(p[0]), float(p[1]), 0.f).g < 0.49f);
    CHECK(g.eval(float(p[0]), float(p[1]), 1.f).g > 0.5f);
  }
  const GridOperator u = generate_operator(preset_spec("clean-union", 32));
  for (std::size_t i = 0; i < std::size_t(u.nf()) * u.nf(); ++i)
    CHECK(g.data()[i] == Approx(u.data()[i]).margin(1e-5));
}

TEST_CASE("biharmonic: schemes, backends and parallel runs agree", "[operators][biharmonic]") {
  for (const auto& name : {"contact", "bulge"}) {
    const OperatorSpec spec = preset_spec(name, 32);
    BiharmonicOptions schur, refactor, lu, serial;
    schur.scheme = SliceScheme::kSchur;
    refactor.scheme = SliceScheme::kRefactor;
    lu.backend = SparseBackend::kSparseLU;
    lu.scheme = SliceScheme::kRefactor;
    serial.tasks = 1;
    BiharmonicOptions par;
    par.tasks = 2;
    BiharmonicOperatorGenerator a(spec, schur), b(spec, refactor), c(spec, lu);
    CHECK(a.stats().scheme == "schur");
    CHECK(b.stats().scheme == "refactor");
    CHECK(c.stats().backend == "sparselu");
    if (BiharmonicOperatorGenerator::has_cholmod()) CHECK(a.stats().backend == "cholmod");
    for (double d : {0.0, 0.2, 0.55, 1.0, 0.37}) {  // 0.37 is between slices
      const auto x = a.solve_slice(d), y = b.solve_slice(d), z = c.solve_slice(d);
      for (std::size_t i = 0; i < x.size(); ++i) {
        CHECK(x[i] == Approx(y[i]).margin(1e-5));
        CHECK(x[i] == Approx(z[i]).margin(1e-5));
      }
    }
    const GridOperator gs = generate_operator(spec, serial), gp = generate_operator(spec, par);
    CHECK(gs.data() == gp.data());
  }
}

TEST_CASE("biharmonic: bad input", "[operators][biharmonic]") {
  OperatorSpec spec = preset_spec("contact", 32);
  spec.resolution = 7;
  CHECK_THROWS_WITH(BiharmonicOperatorGenerator(spec), Catch::Contains("resolution"));
  spec.resolution = 1025;
  CHECK_THROWS_WITH(BiharmonicOperatorGenerator(spec), Catch::Contains("resolution"));
  spec = preset_spec("contact", 32);
  BiharmonicOperatorGenerator g(spec);
  CHECK_THROWS_AS(g.solve_slice(1.5), InputError);
  CHECK_THROWS_AS(g.solve_slice(std::nan("")), InputError);
}

TEST_CASE("biharmonic: random user profiles (polyline and B-spline, with contact lines)",
          "[operators][biharmonic]") {
  test::Rng rng(77);
  for (int trial = 0; trial < 12; ++trial) {
    OperatorSpec spec;
    spec.name = "random" + std::to_string(trial);
    spec.resolution = 32;
    spec.slices = 8;
    spec.controller = "bulge";
    const Point2 m{rng.uniform(0.3, 0.6), rng.uniform(0.3, 0.6)};
    const double a = rng.uniform(0.1, 0.25), b = rng.uniform(0.1, 0.25);
    ProfileCurve boundary{CurveKind::kBoundary, trial % 2 ? CurveType::kBSpline : CurveType::kPolyline, {}};
    const Point2 m1{m[0] + rng.uniform(-0.05, 0.05), m[1] + rng.uniform(-0.05, 0.05)};
    boundary.keyframes = {{0.0, {{0, 0.5}, {a, 0.5}, m, {0.5, b}, {0.5, 0}}},
                          {1.0, {{0, 0.5}, {a, 0.5}, m1, {0.5, b}, {0.5, 0}}}};
    spec.curves.push_back(boundary);
    if (trial % 3 != 0) {
      // Contact line from the polyline's corner (the B-spline does not pass through m: start
      // just inside instead) toward the upper corner.
      const Point2 s0 = trial % 2 ? Point2{0.62, 0.62} : m, s1 = trial % 2 ? Point2{0.62, 0.62} : m1;
      const double len = rng.uniform(0.05, 0.2);
      spec.curves.push_back(
          {CurveKind::kContact,
           CurveType::kPolyline,
           {{0.0, {s0, {s0[0] + 0.01, s0[1] + 0.01}}}, {1.0, {s1, {s1[0] + len, s1[1] + len}}}}});
    }
    INFO("trial " << trial << " m = (" << m[0] << ", " << m[1] << ")");
    validate(spec, "random");
    check_slices(spec, generate_operator(spec));
  }
}

TEST_CASE("biharmonic: interactive edits inside the band use the Schur scheme and agree",
          "[operators][biharmonic]") {
  const OperatorSpec spec = preset_spec("contact", 32);
  BiharmonicOptions o;
  o.edit_band_cells = 3;
  BiharmonicOperatorGenerator gen(spec, o);
  CHECK(gen.stats().scheme == "schur");
  test::Rng rng(91);
  for (int trial = 0; trial < 6; ++trial) {
    // Drag the corner of the boundary curve and the contact line's end by up to ~1.5 cells.
    OperatorSpec edited = spec;
    const double dx = rng.uniform(-0.05, 0.05), dy = rng.uniform(-0.05, 0.05);
    edited.curves[0].keyframes[0].points[1] = {0.5 + dx, 0.5 + dy};
    edited.curves[1].keyframes[0].points = {{0.5 + dx, 0.5 + dy}, {0.5 + dx, 0.5 + dy}};
    edited.curves[1].keyframes[1].points = {{0.5 + dx, 0.5 + dy}, {0.85 + dy, 0.85 + dx}};
    const double d = rng.uniform(0, 1);
    const std::vector<float> a = gen.solve_edited(d, edited);
    INFO("trial " << trial << " d " << d);
    CHECK(gen.last_edit_was_schur());
    BiharmonicOptions r;
    r.scheme = SliceScheme::kRefactor;
    BiharmonicOperatorGenerator fresh(edited, r);
    const std::vector<float> b = fresh.solve_slice(d);
    for (std::size_t i = 0; i < a.size(); ++i) CHECK(a[i] == Approx(b[i]).margin(1e-5));
  }
  // An edit that leaves the band falls back to a factorisation and still agrees.
  OperatorSpec far = spec;
  far.curves[0].keyframes[0].points[1] = {0.3, 0.3};
  far.curves[1].keyframes[1].points = {{0.3, 0.3}, {0.7, 0.7}};
  far.curves[1].keyframes[0].points = {{0.3, 0.3}, {0.3, 0.3}};
  const std::vector<float> a = gen.solve_edited(0.5, far);
  CHECK_FALSE(gen.last_edit_was_schur());
  BiharmonicOperatorGenerator fresh(far);
  const std::vector<float> b = fresh.solve_slice(0.5);
  for (std::size_t i = 0; i < a.size(); ++i) CHECK(a[i] == Approx(b[i]).margin(1e-5));
  OperatorSpec other = preset_spec("contact", 16);
  CHECK_THROWS_WITH(gen.solve_edited(0.5, other), Catch::Contains("resolution"));
}

TEST_CASE("biharmonic: a small grid whose edit band covers every unknown (no free node) works",
          "[operators][biharmonic]") {
  // At resolution 8 a band of 3 cells covers the whole interior: the Schur scheme has no free
  // block F (it used to hand CHOLMOD an empty matrix and crash).
  for (int res = 8; res <= 16; ++res)
    for (int band : {1, 2, 3, 6}) {
      const OperatorSpec spec = preset_spec("contact", res);
      BiharmonicOptions o;
      o.edit_band_cells = band;
      INFO("resolution " << res << " band " << band);
      BiharmonicOperatorGenerator gen(spec, o);
      BiharmonicOptions r;
      r.scheme = SliceScheme::kRefactor;
      BiharmonicOperatorGenerator ref(spec, r);
      for (double d : {0.0, 0.5, 1.0}) {
        const std::vector<float> a = gen.solve_edited(d, spec), b = ref.solve_slice(d);
        REQUIRE(a.size() == b.size());
        for (std::size_t i = 0; i < a.size(); ++i) CHECK(a[i] == Approx(b[i]).margin(1e-5));
      }
    }
  for (int res : {8, 9}) {
    BiharmonicOptions s;
    s.scheme = SliceScheme::kSchur;
    const OperatorSpec spec = preset_spec("bulge", res);
    CHECK_NOTHROW(generate_operator(spec, s));
  }
}
