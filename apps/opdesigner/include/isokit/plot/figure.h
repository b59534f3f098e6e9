// SPDX-License-Identifier: MIT
/// \file
/// 2D figures for operator slices and field slices (Cairo): a heat map of a sampled scalar
/// function, iso-lines extracted by marching squares, overlaid polylines and labels. The output
/// format follows the file extension (.png, .svg, .pdf); files are written atomically
/// (isokit::write_file_atomically), so a failed write never leaves a half-written figure.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace isokit::plot {

/// A scalar function sampled on a regular grid over `[x0, x1] x [y0, y1]`:
/// `values[j * nx + i]` at `(x0 + i (x1 - x0) / (nx - 1), y0 + j (y1 - y0) / (ny - 1))`.
struct ScalarGrid {
  int nx{0}, ny{0};
  double x0{0}, y0{0}, x1{1}, y1{1};
  std::vector<float> values;

  double x(int i) const { return x0 + (x1 - x0) * i / (nx - 1); }
  double y(int j) const { return y0 + (y1 - y0) * j / (ny - 1); }
  float at(int i, int j) const { return values[static_cast<std::size_t>(j) * nx + i]; }
};

using Point2 = std::array<double, 2>;
using Segment2 = std::array<Point2, 2>;
using Rgb = std::array<double, 3>;

/// Iso-line segments of `grid` at `level` (marching squares, linear interpolation along cell
/// edges; saddle cells resolved by the cell-centre average). Segments are in grid coordinates
/// (x, y), not pixels.
std::vector<Segment2> iso_segments(const ScalarGrid& grid, float level);

/// Total length of a set of segments.
double total_length(const std::vector<Segment2>& segments);

/// Colour of `t` in [0, 1] on isokit's sequential map (dark blue -> teal -> yellow).
Rgb colormap(double t);

/// An 8-bit RGBA image, rows top to bottom, `pixels[4 * (y * width + x) + c]`.
struct RgbaImage {
  int width{0}, height{0};
  std::vector<std::uint8_t> pixels;

  const std::uint8_t* at(int x, int y) const {
    return &pixels[4 * (static_cast<std::size_t>(y) * width + x)];
  }
};

/// Writes `image` as a PNG (atomically). \throw isokit::InputError naming `path` if the image is
/// empty or the file cannot be written.
void write_png(const std::string& path, const RgbaImage& image);
/// Reads a PNG into RGBA. \throw isokit::InputError naming `path` if it cannot be read as a PNG.
RgbaImage read_png(const std::string& path);

struct FigureOptions {
  int pixel_size = 640;  ///< Width of the plot area in pixels (height follows the aspect ratio).
  double value_min = 0.0, value_max = 1.0;  ///< Colour-map range.
  std::string title;
};

/// A heat map with overlays, saved by extension. Throws `isokit::InputError` on a bad grid, an
/// unknown extension or a file that cannot be written (the message names it).
class Figure {
 public:
  Figure(ScalarGrid grid, FigureOptions options = {});

  void add_iso_lines(float level, const Rgb& color, double width_px, bool dashed = false);
  void add_polyline(const std::vector<Point2>& points, const Rgb& color, double width_px,
                    bool dashed = false);
  void add_segments(const std::vector<Segment2>& segments, const Rgb& color, double width_px);
  void add_label(const Point2& at, const std::string& text, const Rgb& color);
  /// Text lines printed under the plot.
  void add_caption(const std::string& line);

  /// Writes `path` (.png, .svg or .pdf).
  void save(const std::string& path) const;

 private:
  struct Stroke {
    std::vector<Segment2> segments;
    Rgb color;
    double width;
    bool dashed;
  };
  struct Label {
    Point2 at;
    std::string text;
    Rgb color;
  };
  ScalarGrid grid_;
  FigureOptions options_;
  std::vector<Stroke> strokes_;
  std::vector<Label> labels_;
  std::vector<std::string> caption_;

  class Painter;  // draws the layers with Cairo (figure.cpp)
};

}  // namespace isokit::plot
