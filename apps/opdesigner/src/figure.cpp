// SPDX-License-Identifier: MIT
#include "isokit/plot/figure.h"

#include <cairo-pdf.h>
#include <cairo-svg.h>
#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <utility>

#include "isokit/core/atomic_file.h"
#include "isokit/core/error.h"

namespace isokit::plot {
namespace {

Point2 lerp_edge(const Point2& a, const Point2& b, float va, float vb, float level) {
  const double t = (va == vb) ? 0.5 : double(level - va) / double(vb - va);
  return {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])};
}

std::string extension_of(const std::string& path) {
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos) return "";
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

}  // namespace

std::vector<Segment2> iso_segments(const ScalarGrid& g, float level) {
  std::vector<Segment2> out;
  for (int j = 0; j + 1 < g.ny; ++j) {
    for (int i = 0; i + 1 < g.nx; ++i) {
      // Corners counter-clockwise: (i,j) (i+1,j) (i+1,j+1) (i,j+1).
      const Point2 p[4] = {
          {g.x(i), g.y(j)}, {g.x(i + 1), g.y(j)}, {g.x(i + 1), g.y(j + 1)}, {g.x(i), g.y(j + 1)}};
      const float v[4] = {g.at(i, j), g.at(i + 1, j), g.at(i + 1, j + 1), g.at(i, j + 1)};
      int mask = 0;
      for (int c = 0; c < 4; ++c) mask |= (v[c] >= level ? 1 : 0) << c;
      if (mask == 0 || mask == 15) continue;
      // Crossing point on each edge e = (c, c+1) whose ends straddle the level.
      Point2 cross[4];
      bool has[4];
      for (int e = 0; e < 4; ++e) {
        const int a = e, b = (e + 1) % 4;
        has[e] = ((mask >> a) & 1) != ((mask >> b) & 1);
        if (has[e]) cross[e] = lerp_edge(p[a], p[b], v[a], v[b], level);
      }
      if (mask == 5 || mask == 10) {  // saddle: decide by the centre value
        const bool centre_in = (v[0] + v[1] + v[2] + v[3]) / 4.f >= level;
        const bool corner0_in = (mask & 1) != 0;
        if (centre_in == corner0_in) {  // corners 0 and 2 connected through the centre
          out.push_back({cross[0], cross[1]});
          out.push_back({cross[2], cross[3]});
        } else {
          out.push_back({cross[3], cross[0]});
          out.push_back({cross[1], cross[2]});
        }
        continue;
      }
      Point2 ends[2];
      int k = 0;
      for (int e = 0; e < 4 && k < 2; ++e)
        if (has[e]) ends[k++] = cross[e];
      out.push_back({ends[0], ends[1]});
    }
  }
  return out;
}

double total_length(const std::vector<Segment2>& segments) {
  double len = 0;
  for (const auto& s : segments) len += std::hypot(s[1][0] - s[0][0], s[1][1] - s[0][1]);
  return len;
}

Rgb colormap(double t) {
  // isokit's own sequential map: control colours chosen for monotone lightness.
  static const Rgb stops[] = {{0.08, 0.06, 0.28}, {0.16, 0.26, 0.55}, {0.10, 0.50, 0.58},
                              {0.28, 0.70, 0.45}, {0.75, 0.85, 0.25}, {0.99, 0.93, 0.55}};
  constexpr int n = sizeof(stops) / sizeof(stops[0]);
  t = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0) * (n - 1);
  const int i = std::min(int(t), n - 2);
  const double f = t - i;
  return {stops[i][0] + f * (stops[i + 1][0] - stops[i][0]),
          stops[i][1] + f * (stops[i + 1][1] - stops[i][1]),
          stops[i][2] + f * (stops[i + 1][2] - stops[i][2])};
}

Figure::Figure(ScalarGrid grid, FigureOptions options)
    : grid_(std::move(grid)), options_(std::move(options)) {
  require(grid_.nx >= 2 && grid_.ny >= 2, "Figure grid", "needs at least 2x2 samples",
          "sample the function on a larger grid");
  require(grid_.values.size() == static_cast<std::size_t>(grid_.nx) * grid_.ny, "Figure grid",
          "has " + std::to_string(grid_.values.size()) + " values for " + std::to_string(grid_.nx) + "x" +
              std::to_string(grid_.ny) + " samples",
          "fill nx * ny values");
  require(grid_.x1 > grid_.x0 && grid_.y1 > grid_.y0, "Figure grid", "has an empty extent",
          "pass x1 > x0 and y1 > y0");
  require(options_.pixel_size >= 16 && options_.pixel_size <= 8192, "Figure pixel_size",
          "must be in [16, 8192] (got " + std::to_string(options_.pixel_size) + ")",
          "pass a sensible image width");
  require(options_.value_max > options_.value_min, "Figure value range", "is empty",
          "pass value_max > value_min");
}

void Figure::add_iso_lines(float level, const Rgb& color, double width_px, bool dashed) {
  strokes_.push_back({iso_segments(grid_, level), color, width_px, dashed});
}

void Figure::add_polyline(const std::vector<Point2>& points, const Rgb& color, double width_px, bool dashed) {
  Stroke s{{}, color, width_px, dashed};
  for (std::size_t i = 1; i < points.size(); ++i) s.segments.push_back({points[i - 1], points[i]});
  strokes_.push_back(std::move(s));
}

void Figure::add_segments(const std::vector<Segment2>& segments, const Rgb& color, double width_px) {
  strokes_.push_back({segments, color, width_px, false});
}

void Figure::add_label(const Point2& at, const std::string& text, const Rgb& color) {
  labels_.push_back({at, text, color});
}

void Figure::add_caption(const std::string& line) {
  caption_.push_back(line);
}

/// Draws a figure in pixels: the layout (plot area, margins, title and caption bands) and one
/// member per layer, painted in order: background, heat map, strokes, labels, title and caption.
class Figure::Painter {
 public:
  explicit Painter(const Figure& figure)
      : f_(figure),
        plot_w_(f_.options_.pixel_size),
        plot_h_(plot_w_ * (f_.grid_.y1 - f_.grid_.y0) / (f_.grid_.x1 - f_.grid_.x0)),
        title_h_(f_.options_.title.empty() ? 0 : 24),
        width_(plot_w_ + 2 * kMargin),
        height_(plot_h_ + 2 * kMargin + title_h_ + kLineH * double(f_.caption_.size())),
        ox_(kMargin),
        oy_(kMargin + title_h_) {}

  /// Paints the figure and writes it to `file` as `ext` (png, svg or pdf); the Cairo status.
  cairo_status_t write(const std::string& ext, const std::string& file) const {
    using SurfacePtr = std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)>;
    SurfacePtr surface(ext == "png"
                           ? cairo_image_surface_create(CAIRO_FORMAT_RGB24, int(width_), int(height_))
                       : ext == "svg" ? cairo_svg_surface_create(file.c_str(), width_, height_)
                                      : cairo_pdf_surface_create(file.c_str(), width_, height_),
                       &cairo_surface_destroy);
    std::unique_ptr<cairo_t, decltype(&cairo_destroy)> cr(cairo_create(surface.get()), &cairo_destroy);
    cairo_t* c = cr.get();
    cairo_set_source_rgb(c, 1, 1, 1);
    cairo_paint(c);
    heat_map(c);
    strokes(c);
    labels(c);
    title_and_caption(c);
    cr.reset();
    if (ext == "png") return cairo_surface_write_to_png(surface.get(), file.c_str());
    cairo_surface_finish(surface.get());
    return cairo_surface_status(surface.get());
  }

 private:
  static constexpr double kMargin = 16, kLineH = 16;

  Point2 to_px(const Point2& p) const {
    const ScalarGrid& g = f_.grid_;
    return {ox_ + (p[0] - g.x0) / (g.x1 - g.x0) * plot_w_,
            oy_ + plot_h_ - (p[1] - g.y0) / (g.y1 - g.y0) * plot_h_};
  }

  /// One rectangle per sample cell, coloured by the cell-centre average.
  void heat_map(cairo_t* c) const {
    const ScalarGrid& g = f_.grid_;
    const FigureOptions& o = f_.options_;
    const double cw = plot_w_ / (g.nx - 1), ch = plot_h_ / (g.ny - 1);
    for (int j = 0; j + 1 < g.ny; ++j)
      for (int i = 0; i + 1 < g.nx; ++i) {
        const double v = 0.25 * (double(g.at(i, j)) + g.at(i + 1, j) + g.at(i, j + 1) + g.at(i + 1, j + 1));
        const Rgb col = colormap((v - o.value_min) / (o.value_max - o.value_min));
        cairo_set_source_rgb(c, col[0], col[1], col[2]);
        const Point2 p = to_px({g.x(i), g.y(j + 1)});
        cairo_rectangle(c, p[0], p[1], cw + 0.5, ch + 0.5);
        cairo_fill(c);
      }
  }

  void strokes(cairo_t* c) const {
    for (const Stroke& s : f_.strokes_) {
      cairo_set_source_rgb(c, s.color[0], s.color[1], s.color[2]);
      cairo_set_line_width(c, s.width);
      cairo_set_line_cap(c, CAIRO_LINE_CAP_ROUND);
      const double dash[] = {6.0, 4.0};
      cairo_set_dash(c, dash, s.dashed ? 2 : 0, 0);
      for (const auto& seg : s.segments) {
        const Point2 a = to_px(seg[0]), b = to_px(seg[1]);
        cairo_move_to(c, a[0], a[1]);
        cairo_line_to(c, b[0], b[1]);
      }
      cairo_stroke(c);
    }
    cairo_set_dash(c, nullptr, 0, 0);
  }

  void labels(cairo_t* c) const {
    cairo_select_font_face(c, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(c, 13);
    for (const Label& l : f_.labels_) {
      const Point2 p = to_px(l.at);
      cairo_set_source_rgb(c, l.color[0], l.color[1], l.color[2]);
      cairo_move_to(c, p[0], p[1]);
      cairo_show_text(c, l.text.c_str());
    }
  }

  void title_and_caption(cairo_t* c) const {
    cairo_set_source_rgb(c, 0, 0, 0);
    if (!f_.options_.title.empty()) {
      cairo_set_font_size(c, 15);
      cairo_move_to(c, kMargin, kMargin + 14);
      cairo_show_text(c, f_.options_.title.c_str());
    }
    cairo_set_font_size(c, 12);
    for (std::size_t k = 0; k < f_.caption_.size(); ++k) {
      cairo_move_to(c, kMargin, oy_ + plot_h_ + kMargin + kLineH * double(k) + 4);
      cairo_show_text(c, f_.caption_[k].c_str());
    }
  }

  const Figure& f_;
  const double plot_w_, plot_h_, title_h_, width_, height_, ox_, oy_;
};

void Figure::save(const std::string& path) const {
  const std::string ext = extension_of(path);
  require(ext == "png" || ext == "svg" || ext == "pdf", "figure file '" + path + "'",
          "has an unknown extension '" + ext + "'", "use .png, .svg or .pdf");
  const Painter painter(*this);
  write_file_atomically(path, [&](const std::string& tmp) {
    const cairo_status_t status = painter.write(ext, tmp);
    require(status == CAIRO_STATUS_SUCCESS, "figure file '" + path + "'",
            std::string("Cairo cannot write it (") + cairo_status_to_string(status) + ")",
            "check that the folder is writable and the disk has space");
  });
}

void write_png(const std::string& path, const RgbaImage& image) {
  require(image.width > 0 && image.height > 0 &&
              image.pixels.size() == 4 * static_cast<std::size_t>(image.width) * image.height,
          "image for '" + path + "'", "is empty or its pixel count does not match its size",
          "pass width * height RGBA pixels");
  // Cairo's ARGB32 is premultiplied, native-endian 32-bit words; screenshots are opaque.
  std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surface(
      cairo_image_surface_create(CAIRO_FORMAT_ARGB32, image.width, image.height), cairo_surface_destroy);
  cairo_surface_flush(surface.get());
  unsigned char* data = cairo_image_surface_get_data(surface.get());
  const int stride = cairo_image_surface_get_stride(surface.get());
  for (int y = 0; y < image.height; ++y) {
    auto* row = reinterpret_cast<std::uint32_t*>(data + static_cast<std::size_t>(y) * stride);
    for (int x = 0; x < image.width; ++x) {
      const std::uint8_t* p = image.at(x, y);
      const std::uint32_t a = p[3];
      const auto pm = [a](std::uint32_t c) { return (c * a + 127) / 255; };
      row[x] = (a << 24) | (pm(p[0]) << 16) | (pm(p[1]) << 8) | pm(p[2]);
    }
  }
  cairo_surface_mark_dirty(surface.get());
  write_file_atomically(path, [&](const std::string& tmp) {
    const cairo_status_t status = cairo_surface_write_to_png(surface.get(), tmp.c_str());
    require(status == CAIRO_STATUS_SUCCESS, "PNG file '" + path + "'",
            std::string("Cairo cannot write it (") + cairo_status_to_string(status) + ")",
            "check that the folder is writable and the disk has space");
  });
}

RgbaImage read_png(const std::string& path) {
  std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surface(
      cairo_image_surface_create_from_png(path.c_str()), cairo_surface_destroy);
  const cairo_status_t status = cairo_surface_status(surface.get());
  require(status == CAIRO_STATUS_SUCCESS, "PNG file '" + path + "'",
          std::string("cannot be read (") + cairo_status_to_string(status) + ")", "check the path");
  cairo_surface_flush(surface.get());
  RgbaImage out;
  out.width = cairo_image_surface_get_width(surface.get());
  out.height = cairo_image_surface_get_height(surface.get());
  out.pixels.resize(4 * static_cast<std::size_t>(out.width) * out.height);
  const unsigned char* data = cairo_image_surface_get_data(surface.get());
  const int stride = cairo_image_surface_get_stride(surface.get());
  const bool has_alpha = cairo_image_surface_get_format(surface.get()) == CAIRO_FORMAT_ARGB32;
  for (int y = 0; y < out.height; ++y) {
    const auto* row = reinterpret_cast<const std::uint32_t*>(data + static_cast<std::size_t>(y) * stride);
    for (int x = 0; x < out.width; ++x) {
      const std::uint32_t w = row[x], a = has_alpha ? (w >> 24) : 255;
      const auto un = [a](std::uint32_t c) { return a == 0 ? 0u : std::min(255u, (c * 255 + a / 2) / a); };
      std::uint8_t* p = &out.pixels[4 * (static_cast<std::size_t>(y) * out.width + x)];
      p[0] = std::uint8_t(un((w >> 16) & 255));
      p[1] = std::uint8_t(un((w >> 8) & 255));
      p[2] = std::uint8_t(un(w & 255));
      p[3] = std::uint8_t(a);
    }
  }
  return out;
}

}  // namespace isokit::plot
