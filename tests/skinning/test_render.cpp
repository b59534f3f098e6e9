// SPDX-License-Identifier: MIT
// Offscreen renders: coverage against the analytic silhouette of a sphere, framing, colours,
// determinism, PNG round trip through Cairo, contact sheets, errors.
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <tbb/global_control.h>

#include "isokit/core/error.h"
#include "isokit/skinning/render.h"
#include "mesh_fixture.h"

using namespace isokit;
using namespace isokit::skinning;
using track::Positions;
using track::Triangles;

namespace {

using testing::kPi;
using testing::Mesh;

/// UV sphere, counter-clockwise seen from outside.
Mesh sphere(int rings, int segments, double radius, const Eigen::Vector3d& centre) {
  Mesh m;
  m.v.resize(2 + (rings - 1) * segments, 3);
  m.v.row(0) = (centre + Eigen::Vector3d(0, 0, radius)).cast<float>().transpose();
  m.v.row(1) = (centre - Eigen::Vector3d(0, 0, radius)).cast<float>().transpose();
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double th = kPi * r / rings, ph = 2 * kPi * s / segments;
      const Eigen::Vector3d p(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
      m.v.row(2 + (r - 1) * segments + s) = (centre + radius * p).cast<float>().transpose();
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
  m.f.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (std::size_t i = 0; i < f.size(); ++i)
    m.f.row(static_cast<Eigen::Index>(i)) << f[i][0], f[i][1], f[i][2];
  return m;
}

const std::uint8_t* pixel(const Image& im, int x, int y) {
  return &im.rgba[(static_cast<std::size_t>(y) * im.width + x) * 4];
}

bool is_background(const Image& im, int x, int y, const Eigen::Vector3f& bg = {1, 1, 1}) {
  const std::uint8_t* p = pixel(im, x, y);
  for (int c = 0; c < 3; ++c)
    if (p[c] != static_cast<std::uint8_t>(std::lround(bg[c] * 255))) return false;
  return true;
}

int object_pixels(const Image& im) {
  int n = 0;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) n += is_background(im, x, y) ? 0 : 1;
  return n;
}

/// Distance from `c` to the camera ray through the centre of pixel (x, y).
double ray_distance(const Camera& cam, double x, double y, const Eigen::Vector3d& c) {
  const Eigen::Vector3d d =
      (cam.focal_px * cam.forward + (x - 0.5 * cam.width) * cam.right - (y - 0.5 * cam.height) * cam.up)
          .normalized();
  const Eigen::Vector3d w = c - cam.eye;
  return (w - w.dot(d) * d).norm();
}

std::filesystem::path temp_dir() {
  const auto dir = std::filesystem::temp_directory_path() / "isokit-test-render";
  std::filesystem::create_directories(dir);
  return dir;
}

Image solid(int w, int h, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  Image im;
  im.width = w;
  im.height = h;
  im.rgba.resize(static_cast<std::size_t>(w) * h * 4);
  for (std::size_t i = 0; i < im.rgba.size(); i += 4) {
    im.rgba[i] = r;
    im.rgba[i + 1] = g;
    im.rgba[i + 2] = b;
    im.rgba[i + 3] = 255;
  }
  return im;
}

int count_color(const Image& im, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  int n = 0;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      const std::uint8_t* p = pixel(im, x, y);
      n += (p[0] == r && p[1] == g && p[2] == b) ? 1 : 0;
    }
  return n;
}

}  // namespace

TEST_CASE("render: a sphere covers its analytic silhouette and nothing else", "[skinning][render]") {
  const Eigen::Vector3d centre(0.3, -0.2, 1.0);
  const double radius = 0.7;
  const Mesh m = sphere(48, 96, radius, centre);
  for (const Eigen::Vector3d& view :
       {Eigen::Vector3d(0, 0, -1), Eigen::Vector3d(-1, -0.5, -0.8), Eigen::Vector3d(0.2, 1, 0.1)}) {
    RenderOptions o;
    o.width = 160;
    o.height = 120;
    o.view_direction = view;
    o.up = Eigen::Vector3d(0, 0, 1).cross(view).norm() > 0.5 ? Eigen::Vector3d(0, 0, 1)
                                                             : Eigen::Vector3d(1, 0, 0);
    o.frame = Eigen::AlignedBox3d(centre.array() - 1.0, centre.array() + 1.0);
    const Image im = render_mesh(m.v, m.f, o);
    REQUIRE(im.width == 160);
    REQUIRE(im.height == 120);
    REQUIRE(im.rgba.size() == 160u * 120u * 4u);
    const Camera cam = frame_camera(o, o.frame);
    int inside = 0, outside = 0;
    for (int y = 0; y < im.height; ++y)
      for (int x = 0; x < im.width; ++x) {
        const double d = ray_distance(cam, x + 0.5, y + 0.5, centre);
        if (d < 0.95 * radius) {
          ++inside;
          CHECK_FALSE(is_background(im, x, y));
        } else if (d > 1.03 * radius) {
          ++outside;
          CHECK(is_background(im, x, y));
        }
        CHECK(pixel(im, x, y)[3] == 255);
      }
    CHECK(inside > 1000);
    CHECK(outside > 1000);
  }
}

TEST_CASE(
    "render: the framed box projects inside the image, pixels outside the mesh's projection are background",
    "[skinning][render]") {
  const Mesh m = sphere(16, 32, 0.5, {1, 2, 3});
  RenderOptions o;
  o.width = 200;
  o.height = 100;
  o.view_direction = {1, -0.3, -0.6};
  o.up = {0, 1, 0};
  o.margin = 0.1;
  const Eigen::AlignedBox3d box(Eigen::Vector3d(0, 1, 2), Eigen::Vector3d(3, 3.5, 4));
  const Camera cam = frame_camera(o, box);
  double xmin = 1e9, xmax = -1e9, ymin = 1e9, ymax = -1e9;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d p = cam.project(box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(k)));
    CHECK(p.z() > 0);
    CHECK(p.x() >= 0.05 * 200 - 1e-6);
    CHECK(p.x() <= 0.95 * 200 + 1e-6);
    CHECK(p.y() >= 0.05 * 100 - 1e-6);
    CHECK(p.y() <= 0.95 * 100 + 1e-6);
  }
  // The tightest side touches the shrunk image border.
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d p = cam.project(box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(k)));
    xmin = std::min(xmin, p.x()), xmax = std::max(xmax, p.x());
    ymin = std::min(ymin, p.y()), ymax = std::max(ymax, p.y());
  }
  CHECK(std::max({10 - xmin + 0, xmax - 190, 5 - ymin, ymax - 95}) == Approx(0).margin(1e-6));
  o.frame = box;
  const Image im = render_mesh(m.v, m.f, o);
  double mx0 = 1e9, mx1 = -1e9, my0 = 1e9, my1 = -1e9;
  for (Eigen::Index i = 0; i < m.v.rows(); ++i) {
    const Eigen::Vector3d p = cam.project(m.v.row(i).cast<double>().transpose());
    mx0 = std::min(mx0, p.x()), mx1 = std::max(mx1, p.x());
    my0 = std::min(my0, p.y()), my1 = std::max(my1, p.y());
  }
  int covered = 0;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      const bool in_rect = x + 1 > mx0 && x < mx1 && y + 1 > my0 && y < my1;
      if (!in_rect) CHECK(is_background(im, x, y));
      covered += is_background(im, x, y) ? 0 : 1;
    }
  CHECK(covered > 100);
  // Default frame = the mesh's box: the object fills much more of the image.
  o.frame = Eigen::AlignedBox3d();
  CHECK(object_pixels(render_mesh(m.v, m.f, o)) > 2 * covered);
}

TEST_CASE("render: deterministic, options change the picture as they should", "[skinning][render]") {
  const Mesh m = sphere(24, 48, 1.0, {0, 0, 0});
  RenderOptions o;
  o.width = 120;
  o.height = 120;
  const Image a = render_mesh(m.v, m.f, o);
  CHECK(render_mesh(m.v, m.f, o).rgba == a.rgba);
  {
    const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    CHECK(render_mesh(m.v, m.f, o).rgba == a.rgba);
  }
  CHECK(object_pixels(a) > 120 * 120 / 3);

  SECTION("flat, no supersampling, wireframe") {
    RenderOptions flat = o;
    flat.shading = Shading::Flat;
    CHECK(render_mesh(m.v, m.f, flat).rgba != a.rgba);
    RenderOptions one = o;
    one.supersample = 1;
    CHECK(std::abs(object_pixels(render_mesh(m.v, m.f, one)) - object_pixels(a)) < 120 * 4);
    RenderOptions wire = o;
    wire.wireframe = true;
    wire.wire_color = {0, 0, 0};
    auto dark = [](const Image& im) {
      int n = 0;
      for (std::size_t i = 0; i < im.rgba.size(); i += 4)
        n += (im.rgba[i] < 40 && im.rgba[i + 1] < 40) ? 1 : 0;
      return n;
    };
    CHECK(dark(render_mesh(m.v, m.f, wire)) > dark(a) + 500);
  }
  SECTION("face colours, vertex colours, back faces") {
    RenderOptions red = o;
    red.face_colors = Colors::Zero(m.f.rows(), 3);
    red.face_colors.col(0).setOnes();
    const Image r = render_mesh(m.v, m.f, red);
    RenderOptions green = o;
    green.vertex_colors = Colors::Zero(m.v.rows(), 3);
    green.vertex_colors.col(1).setOnes();
    const Image g = render_mesh(m.v, m.f, green);
    const std::uint8_t* pr = pixel(r, 60, 60);
    const std::uint8_t* pg = pixel(g, 60, 60);
    CHECK(pr[0] > 100);
    CHECK(pr[1] == pr[2]);  // only the rim adds green and blue, equally
    CHECK(pr[0] > pr[1] + 60);
    CHECK(pg[1] > pg[0] + 60);
    // Inside out: the visible sides face away from the camera and take the back colour (blue).
    Triangles flipped = m.f;
    flipped.col(1).swap(flipped.col(2));
    const Image b = render_mesh(m.v, flipped, o);
    const std::uint8_t* pb = pixel(b, 60, 60);
    const std::uint8_t* pa = pixel(a, 60, 60);
    CHECK(pb[2] > pb[0]);
    CHECK(pa[0] > pa[2]);
  }
  SECTION("bad options and inputs") {
    RenderOptions bad = o;
    bad.up = {0, 0, 1};  // parallel to the default view
    CHECK_THROWS_AS(render_mesh(m.v, m.f, bad), InputError);
    bad = o;
    bad.width = 0;
    CHECK_THROWS_AS(render_mesh(m.v, m.f, bad), InputError);
    bad = o;
    bad.face_colors = Colors::Zero(3, 3);
    CHECK_THROWS_WITH(render_mesh(m.v, m.f, bad), Catch::Contains("face_colors"));
    Triangles t = m.f;
    t(0, 0) = 100000;
    CHECK_THROWS_WITH(render_mesh(m.v, t, o), Catch::Contains("triangle 0"));
    // An empty mesh gives the background.
    const Image empty = render_mesh(Positions(0, 3), Triangles(0, 3), o);
    CHECK(object_pixels(empty) == 0);
  }
}

TEST_CASE("render: PNG round trip through Cairo, unwritable paths are named", "[skinning][render]") {
  const Mesh m = sphere(12, 24, 1.0, {0, 0, 0});
  RenderOptions o;
  o.width = 64;
  o.height = 48;
  const Image im = render_mesh(m.v, m.f, o);
  const std::string path = (temp_dir() / "sphere.png").string();
  write_png(im, path);
  for (const auto& e : std::filesystem::directory_iterator(temp_dir()))  // no temporary file left
    CHECK(e.path().filename().string().find("sphere.tmp") == std::string::npos);
  const Image back = read_png(path);
  CHECK(back.width == 64);
  CHECK(back.height == 48);
  CHECK(back.rgba == im.rgba);
  std::ifstream in(path, std::ios::binary);
  char magic[4] = {};
  in.read(magic, 4);
  CHECK(std::string(magic + 1, 3) == "PNG");

  const std::string bad = "/nonexistent-isokit-dir/out.png";
  CHECK_THROWS_WITH(write_png(im, bad), Catch::Contains(bad));
  CHECK_THROWS_WITH(read_png(bad), Catch::Contains(bad));
  Image broken = im;
  broken.rgba.pop_back();
  CHECK_THROWS_AS(write_png(broken, path), InputError);
}

TEST_CASE("render: contact sheet holds every image at full size", "[skinning][render]") {
  const std::uint8_t palette[6][3] = {{250, 10, 10},  {10, 250, 10},  {10, 10, 250},
                                      {250, 250, 10}, {10, 250, 250}, {250, 10, 250}};
  std::vector<std::vector<Image>> grid(2);
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 3; ++c) {
      const auto* p = palette[r * 3 + c];
      grid[static_cast<std::size_t>(r)].push_back(solid(c == 1 ? 50 : 60, 40, p[0], p[1], p[2]));
    }
  const Image sheet = compose_contact_sheet(grid, {"lbs", "tracking2014"}, {"45°", "90°", "120°"}, "bend");
  CHECK(sheet.width >= 3 * 60 + 4 * 10);
  CHECK(sheet.height >= 2 * 40 + 3 * 10);
  for (int k = 0; k < 6; ++k)
    CHECK(count_color(sheet, palette[k][0], palette[k][1], palette[k][2]) == (k % 3 == 1 ? 50 : 60) * 40);
  // Text is drawn: dark pixels exist.
  int dark = 0;
  for (std::size_t i = 0; i < sheet.rgba.size(); i += 4)
    dark += sheet.rgba[i] < 100 && sheet.rgba[i + 1] < 100 ? 1 : 0;
  CHECK(dark > 20);
  CHECK(compose_contact_sheet(grid, {"lbs", "tracking2014"}, {"45°", "90°", "120°"}, "bend").rgba ==
        sheet.rgba);

  const std::string path = (temp_dir() / "sheet.png").string();
  write_contact_sheet(grid, {"lbs", "tracking2014"}, {"45°", "90°", "120°"}, "bend", path);
  const Image back = read_png(path);
  CHECK(back.width == sheet.width);
  CHECK(back.height == sheet.height);
  // Ragged rows and no labels.
  grid[1].pop_back();
  const Image ragged = compose_contact_sheet(grid, {}, {}, "");
  CHECK(count_color(ragged, palette[5][0], palette[5][1], palette[5][2]) == 0);
  CHECK(ragged.width < sheet.width);

  CHECK_THROWS_AS(compose_contact_sheet(grid, {"only one"}, {}, ""), InputError);
  CHECK_THROWS_AS(compose_contact_sheet({}, {}, {}, ""), InputError);
  CHECK_THROWS_WITH(write_contact_sheet(grid, {}, {}, "", "/nonexistent-isokit-dir/sheet.png"),
                    Catch::Contains("/nonexistent-isokit-dir/sheet.png"));
}
