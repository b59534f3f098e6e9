// SPDX-License-Identifier: MIT
// Checks the report and screenshots of the scripted studio run (tests/opdesigner/gui_drag.json):
// the window is not blank, the handles are drawn where the model has its control points, the
// slice changed under the drag, the dragged point moved, undo restored it and redo replayed it.
// Usage: gui_check REPORT.json. Exit 0 when every check passes; prints each failure.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "isokit/plot/figure.h"

using isokit::plot::RgbaImage;
using nlohmann::json;

namespace {

int failures = 0;

void expect(bool ok, const std::string& what) {
  std::printf("%s: %s\n", ok ? "ok  " : "FAIL", what.c_str());
  if (!ok) ++failures;
}

const json& named(const json& list, const std::string& name) {
  for (const auto& m : list)
    if (m["name"] == name) return m;
  throw std::runtime_error("the report has no '" + name + "'");
}

bool near_colour(const std::uint8_t* p, const json& rgb, int tol) {
  for (int c = 0; c < 3; ++c)
    if (std::abs(int(p[c]) - rgb[c].get<int>()) > tol) return false;
  return true;
}

std::size_t distinct_colours(const RgbaImage& img) {
  std::set<std::uint32_t> seen;
  for (std::size_t i = 0; i < img.pixels.size(); i += 4)
    seen.insert(std::uint32_t(img.pixels[i]) << 16 | std::uint32_t(img.pixels[i + 1]) << 8 |
                img.pixels[i + 2]);
  return seen.size();
}

/// Pixels of the plot rectangle `plot` = [left, top, width, height] that differ between a and b.
std::size_t differing(const RgbaImage& a, const RgbaImage& b, const json& plot) {
  std::size_t n = 0;
  const int x0 = int(plot[0].get<double>()), y0 = int(plot[1].get<double>());
  const int w = int(plot[2].get<double>()), h = int(plot[3].get<double>());
  for (int y = y0; y < y0 + h && y < a.height; ++y)
    for (int x = x0; x < x0 + w && x < a.width; ++x)
      for (int c = 0; c < 3; ++c)
        if (std::abs(int(a.at(x, y)[c]) - int(b.at(x, y)[c])) > 8) {
          ++n;
          break;
        }
  return n;
}

void check_handles(const json& shot, const RgbaImage& img, const json& handle, const json& selected) {
  int drawn = 0, total = 0;
  for (const auto& p : shot["points"]) {
    const int x = int(std::floor(p["px"][0].get<double>())), y = int(std::floor(p["px"][1].get<double>()));
    ++total;
    if (x >= 0 && y >= 0 && x < img.width && y < img.height &&
        (near_colour(img.at(x, y), handle, 12) || near_colour(img.at(x, y), selected, 12)))
      ++drawn;
  }
  expect(total > 0 && drawn == total, shot["name"].get<std::string>() + ": handle colour at the model's " +
                                          std::to_string(drawn) + "/" + std::to_string(total) +
                                          " control points");
}

json point(const json& mark, int curve, int index) {
  for (const auto& p : mark["points"])
    if (p["curve"] == curve && p["index"] == index) return p["op"];
  throw std::runtime_error("no point [" + std::to_string(curve) + ", " + std::to_string(index) + "]");
}

double dist(const json& a, const json& b) {
  return std::hypot(a[0].get<double>() - b[0].get<double>(), a[1].get<double>() - b[1].get<double>());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: gui_check REPORT.json\n");
    return 2;
  }
  try {
    std::ifstream in(argv[1]);
    const json r = json::parse(in);
    const json& shots = r["screenshots"];
    const json& marks = r["marks"];
    const RgbaImage before = isokit::plot::read_png(named(shots, "studio-before")["file"]);
    const RgbaImage dragged = isokit::plot::read_png(named(shots, "studio-dragged")["file"]);
    const RgbaImage undone = isokit::plot::read_png(named(shots, "studio-undone")["file"]);
    expect(distinct_colours(before) > 500,
           "window not blank: " + std::to_string(distinct_colours(before)) + " distinct colours");
    const json selected = {255, 150, 0};
    for (const char* name : {"studio-before", "studio-dragged", "studio-undone"})
      check_handles(named(shots, name), isokit::plot::read_png(named(shots, name)["file"]), r["handle_rgb"],
                    selected);
    const json& plot = named(shots, "studio-before")["plot"];
    const std::size_t area = std::size_t(plot[2].get<double>() * plot[3].get<double>());
    const std::size_t changed = differing(before, dragged, plot), restored = differing(before, undone, plot);
    expect(changed > area / 50, "the slice changed under the drag: " + std::to_string(changed) + " pixels");
    expect(restored < area / 200, "undo restored the slice: " + std::to_string(restored) + " pixels differ");
    const json p0 = point(named(marks, "before"), 1, 1), p1 = point(named(marks, "dragged"), 1, 1);
    expect(dist(p0, p1) > 0.1, "the dragged point moved by " + std::to_string(dist(p0, p1)));
    expect(dist(p1, json{0.8, 0.62}) < 0.02, "the dragged point is under the mouse (0.8, 0.62)");
    expect(named(marks, "dragged")["can_undo"].get<bool>(), "the drag is an undo step");
    expect(dist(point(named(marks, "undone"), 1, 1), p0) < 1e-9, "Ctrl+Z put the point back");
    expect(named(marks, "undone")["can_redo"].get<bool>(), "Ctrl+Z left a redo step");
    expect(dist(point(named(marks, "redone"), 1, 1), p1) < 1e-9, "Ctrl+Y replayed the drag");
    expect(named(marks, "redone")["fully_solved"].get<bool>(), "every slice solved at the end");
    const json& failed = named(shots, "studio-check");
    expect(!failed["check"].is_null(),
           "a contact line run into the f1 = 1 edge fails a check: " + failed["check"].dump());
    const RgbaImage check_img = isokit::plot::read_png(failed["file"]);
    int marked = 0;
    for (const auto& px : failed["check_marks_px"])
      for (int dy = -6; dy <= 6; ++dy)
        for (int dx = -6; dx <= 6; ++dx) {
          const int x = int(px[0].get<double>()) + dx, y = int(px[1].get<double>()) + dy;
          if (x >= 0 && y >= 0 && x < check_img.width && y < check_img.height &&
              near_colour(check_img.at(x, y), r["check_rgb"], 40))
            ++marked;
        }
    expect(failed["check_marks_px"].size() > 0 && marked > 10,
           "the offending region is marked in red (" + std::to_string(marked) + " red pixels at the marks)");
    const json &k0 = named(marks, "check")["knots"], &k1 = named(marks, "knot")["knots"];
    expect(k0.size() == k1.size() && k1.size() >= 3 && dist(k1[1], json{1.2, 0.3}) < 0.02 &&
               dist(k0[1], k1[1]) > 0.1,
           "the controller knot 1 was dragged to (1.2, 0.3): " + k0[1].dump() + " -> " + k1[1].dump());
    const json& lat = r["timing"]["latency_frames"];
    expect(lat["count"].get<int>() > 0 && lat["max"].get<int>() <= 2,
           "input to redrawn slice within 2 frames (max " + lat["max"].dump() + ")");
  } catch (const std::exception& e) {
    std::printf("FAIL: %s\n", e.what());
    return 1;
  }
  return failures == 0 ? 0 : 1;
}
