// SPDX-License-Identifier: MIT
// The design studio's CPU side: plot mapping, slice images and iso-lines, scripts, PNG I/O, and
// the composed-capsules field shared by `compose` and the studio's preview.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <string>

#include "isokit/core/error.h"
#include "isokit/opdesigner/designer.h"
#include "isokit/operators/biharmonic.h"
#include "isokit/studio/script.h"
#include "isokit/studio/view.h"

using namespace isokit;
using namespace isokit::studio;

TEST_CASE("plot mapping: operator (f1, f2) <-> pixels, y up on the plot", "[studio]") {
  const PlotMapping m{100, 50, 400, 400, 0, 0, 1, 1};
  const auto corner = m.to_screen({0, 0});
  CHECK(corner[0] == Approx(100));
  CHECK(corner[1] == Approx(450));  // f2 = 0 at the bottom
  const auto top = m.to_screen({1, 1});
  CHECK(top[0] == Approx(500));
  CHECK(top[1] == Approx(50));
  for (const plot::Point2 p : {plot::Point2{0.3, 0.7}, plot::Point2{0.9, 0.1}, plot::Point2{0.5, 0.5}}) {
    const auto back = m.to_domain(m.to_screen(p));
    CHECK(back[0] == Approx(p[0]));
    CHECK(back[1] == Approx(p[1]));
  }
  CHECK(m.contains({300, 300}));
  CHECK_FALSE(m.contains({99, 300}));
  const PlotMapping preview{0, 0, 320, 320, -1.6, -1.6, 1.6, 1.6};
  CHECK(preview.to_screen({0, 0})[0] == Approx(160));
}

TEST_CASE("slice grid: x = f1, y = f2 from the generator's [i1 * nf + i2] order", "[studio]") {
  const int nf = 5;
  std::vector<float> v(nf * nf);
  for (int i1 = 0; i1 < nf; ++i1)
    for (int i2 = 0; i2 < nf; ++i2) v[i1 * nf + i2] = float(i1) + 10.f * float(i2);
  const plot::ScalarGrid g = slice_grid(v.data(), nf);
  CHECK(g.nx == nf);
  CHECK(g.at(3, 1) == 13.f);  // f1 index 3, f2 index 1
  CHECK(g.at(1, 3) == 31.f);
  CHECK_THROWS_AS(slice_grid(nullptr, nf), InputError);
  const operators::GridOperator op(2, nf, [&] {
    std::vector<float> two = v;
    two.insert(two.end(), v.begin(), v.end());
    return two;
  }());
  CHECK(slice_grid(op, 1).at(3, 1) == 13.f);
  CHECK_THROWS_AS(slice_grid(op, 2), InputError);
}

TEST_CASE("colour image: one pixel per sample, top row = top of the plot, colour map ends", "[studio]") {
  plot::ScalarGrid g;
  g.nx = 3;
  g.ny = 2;
  g.values = {0, 0, 0, 1, 1, 1};  // bottom row 0, top row 1
  const plot::RgbaImage img = colour_image(g);
  REQUIRE(img.width == 3);
  REQUIRE(img.height == 2);
  const plot::Rgb hi = plot::colormap(1), lo = plot::colormap(0);
  for (int c = 0; c < 3; ++c) {
    CHECK(int(img.at(1, 0)[c]) == int(std::lround(255 * hi[c])));
    CHECK(int(img.at(1, 1)[c]) == int(std::lround(255 * lo[c])));
  }
  CHECK(int(img.at(2, 1)[3]) == 255);
  g.values[0] = 7;  // out of range: clamped
  CHECK(colour_image(g).at(0, 1)[0] == img.at(2, 0)[0]);
}

TEST_CASE("decile iso-lines: g = f1 gives vertical lines at 0.1 ... 0.9", "[studio]") {
  const int nf = 21;
  std::vector<float> v(nf * nf);
  for (int i1 = 0; i1 < nf; ++i1)
    for (int i2 = 0; i2 < nf; ++i2) v[i1 * nf + i2] = float(i1) / float(nf - 1);
  const auto sets = decile_iso_lines(slice_grid(v.data(), nf));
  REQUIRE(sets.size() == 9);
  for (const auto& s : sets) {
    REQUIRE_FALSE(s.segments.empty());
    double length = 0;
    for (const auto& seg : s.segments) {
      CHECK(seg[0][0] == Approx(s.level).margin(1e-5));
      CHECK(seg[1][0] == Approx(s.level).margin(1e-5));
      length += std::hypot(seg[1][0] - seg[0][0], seg[1][1] - seg[0][1]);
    }
    CHECK(length == Approx(1.0).margin(1e-6));
  }
}

TEST_CASE("scripts: every event parses, errors name the event and the field", "[studio]") {
  const auto ev = parse_script(R"([
    {"type": "frames", "n": 3}, {"type": "move", "to": {"op": [0.4, 0.3]}, "frames": 5},
    {"type": "move", "to": {"point": [1, 2]}}, {"type": "move", "to": {"knot": 2}},
    {"type": "press"}, {"type": "release", "button": 1}, {"type": "key", "key": "Z", "ctrl": true},
    {"type": "wait_solved"}, {"type": "screenshot", "name": "a"}, {"type": "set", "d": 0.5, "angle": 90},
    {"type": "mark", "name": "m"}, {"type": "move", "to": {"ctrl": [1.5, 0.25]}}])",
                               "t");
  REQUIRE(ev.size() == 12);
  CHECK(ev[11].target.kind == TargetKind::kController);
  CHECK(ev[11].target.at[1] == Approx(0.25));
  CHECK(ev[1].kind == EventKind::kMove);
  CHECK(ev[1].target.kind == TargetKind::kOperator);
  CHECK(ev[1].frames == 5);
  CHECK(ev[2].target.kind == TargetKind::kControlPoint);
  CHECK(ev[2].target.curve == 1);
  CHECK(ev[2].target.index == 2);
  CHECK(ev[3].target.kind == TargetKind::kKnot);
  CHECK(ev[5].button == 1);
  CHECK(ev[6].ctrl);
  CHECK(ev[7].frames == 600);
  CHECK(ev[9].d == Approx(0.5));
  CHECK(*ev[9].angle == Approx(90));
  auto message = [](const std::string& text) {
    try {
      parse_script(text, "s.json");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK_THAT(message("{"), Catch::Contains("s.json") && Catch::Contains("not valid JSON"));
  CHECK_THAT(message("{}"), Catch::Contains("list of events"));
  CHECK_THAT(message(R"([{"type": "frames"}, {"type": "jump"}])"),
             Catch::Contains("event 2") && Catch::Contains("jump"));
  CHECK_THAT(message(R"([{"type": "move"}])"), Catch::Contains("needs 'to'"));
  CHECK_THAT(message(R"([{"type": "move", "to": {"op": [1]}}])"), Catch::Contains("'op'"));
  CHECK_THAT(message(R"([{"type": "screenshot", "name": "a/b"}])"), Catch::Contains("'/'"));
  CHECK_THAT(message(R"([{"type": "frames", "n": -1}])"), Catch::Contains("'n'"));
  CHECK_THROWS_AS(load_script("/nonexistent/script.json"), InputError);
}

TEST_CASE("PNG write/read round trip keeps opaque pixels", "[studio]") {
  plot::RgbaImage img;
  img.width = 4;
  img.height = 3;
  for (int i = 0; i < 12; ++i)
    img.pixels.insert(img.pixels.end(), {std::uint8_t(20 * i), 7, std::uint8_t(255 - i), 255});
  const std::string path = "test_studio_roundtrip.png";
  plot::write_png(path, img);
  const plot::RgbaImage back = plot::read_png(path);
  CHECK(back.width == 4);
  CHECK(back.height == 3);
  CHECK(back.pixels == img.pixels);
  std::remove(path.c_str());
  CHECK_THROWS_AS(plot::read_png("/nonexistent.png"), InputError);
  CHECK_THROWS_AS(plot::write_png(path, plot::RgbaImage{}), InputError);
}

TEST_CASE("compose_field is what compose measures (one field function for the CLI and the studio)",
          "[studio]") {
  operators::StoredOperator op;
  op.spec = operators::preset_spec("contact", 24);
  op.grid = operators::generate_operator(op.spec);
  opdesigner::ComposeOptions o;
  o.samples = 101;
  o.angle_deg = 150;
  const auto field = opdesigner::compose_field(op.grid, op.spec.make_controller().table(), o);
  const auto stats = opdesigner::compose(op, o, "");
  CHECK(field.stats.contact_length == stats.contact_length);
  CHECK(field.stats.max_d == stats.max_d);
  CHECK(field.grid.nx == 101);
  CHECK(field.stats.contact_length > 0.05);
  CHECK_FALSE(field.contact.empty());
  // Far from both capsules the composed field is 0; on the joint it is inside (> 0.5).
  CHECK(field.grid.at(0, 0) == 0.f);
  CHECK(field.grid.at(50, 50) > 0.5f);
  o.angle_deg = 200;
  CHECK_THROWS_AS(opdesigner::compose_field(op.grid, op.spec.make_controller().table(), o), InputError);
}
