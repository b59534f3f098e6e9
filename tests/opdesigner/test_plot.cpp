// SPDX-License-Identifier: MIT
// Marching squares against known curves, and figure writing (formats, atomic writes, errors).
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "isokit/core/error.h"
#include "isokit/core/math.h"
#include "isokit/plot/figure.h"

using namespace isokit;
using namespace isokit::plot;

namespace {
ScalarGrid radial_grid(int n) {
  ScalarGrid g;
  g.nx = g.ny = n;
  g.x0 = g.y0 = -1;
  g.x1 = g.y1 = 1;
  g.values.resize(static_cast<std::size_t>(n) * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      g.values[static_cast<std::size_t>(j) * n + i] = float(std::hypot(g.x(i), g.y(j)));
  return g;
}
}  // namespace

TEST_CASE("iso-segments of a radial function lie on the circle", "[plot]") {
  for (int n : {17, 64, 201}) {
    const ScalarGrid g = radial_grid(n);
    for (float radius : {0.2f, 0.5f, 0.77f}) {
      const auto segs = iso_segments(g, radius);
      REQUIRE(!segs.empty());
      const double h = 2.0 / (n - 1);
      for (const auto& s : segs)
        for (const auto& p : s) CHECK(std::abs(std::hypot(p[0], p[1]) - radius) <= h * h / radius);
      // Length converges to the circumference (polygon inscribed in the circle).
      const double circumference = 2 * kPi * radius;
      CHECK(std::abs(total_length(segs) - circumference) <=
            circumference * std::min(0.5, h * h / (radius * radius)));
    }
  }
  // Levels outside the range give nothing.
  CHECK(iso_segments(radial_grid(9), 5.f).empty());
}

TEST_CASE("figures are written by extension, atomically", "[plot]") {
  const auto dir = std::filesystem::temp_directory_path() / "isokit_test_plot";
  std::filesystem::create_directories(dir);
  Figure fig(radial_grid(33), FigureOptions{200, 0.0, 1.5, "radial"});
  fig.add_iso_lines(0.5f, {1, 0, 0}, 2.0);
  fig.add_polyline({{-1, -1}, {1, 1}}, {1, 1, 1}, 1.0, true);
  fig.add_label({0, 0}, "centre", {1, 1, 1});
  fig.add_caption("caption line");
  for (const char* ext : {"png", "svg", "pdf"}) {
    const auto path = dir / (std::string("fig.") + ext);
    std::filesystem::remove(path);
    fig.save(path.string());
    REQUIRE(std::filesystem::exists(path));
    CHECK(std::filesystem::file_size(path) > 100);
  }
  for (const auto& e : std::filesystem::directory_iterator(dir))  // no temporary file left
    CHECK(e.path().filename().string().find(".tmp") == std::string::npos);
  std::ifstream png(dir / "fig.png", std::ios::binary);
  char magic[4] = {};
  png.read(magic, 4);
  CHECK(std::string(magic + 1, 3) == "PNG");
  CHECK_THROWS_WITH(fig.save((dir / "fig.bmp").string()), Catch::Contains("unknown extension"));
  CHECK_THROWS_AS(fig.save((dir / "no-such-folder" / "fig.png").string()), InputError);
  CHECK_FALSE(std::filesystem::exists(dir / "no-such-folder"));
  ScalarGrid bad = radial_grid(5);
  bad.values.pop_back();
  CHECK_THROWS_AS(Figure(bad), InputError);
}
