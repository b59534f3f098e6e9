// SPDX-License-Identifier: MIT
// PNG input/output and labelled contact sheets through Cairo image surfaces.
#include <cairo/cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>

#include "isokit/core/atomic_file.h"
#include "isokit/core/error.h"
#include "isokit/skinning/render.h"

namespace isokit::skinning {
namespace {

using SurfacePtr = std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)>;
using ContextPtr = std::unique_ptr<cairo_t, decltype(&cairo_destroy)>;

constexpr int kPad = 10;           // pixels around and between cells
constexpr double kLabelFont = 16;  // row and column labels, pixels
constexpr double kTitleFont = 20;  // title, pixels
constexpr const char* kFontFace = "sans-serif";

void check_image(const Image& image, const std::string& what) {
  require(image.width > 0 && image.height > 0 &&
              image.rgba.size() == static_cast<std::size_t>(image.width) * image.height * 4,
          what,
          "needs width, height > 0 and 4 * width * height bytes (got " + std::to_string(image.width) + "x" +
              std::to_string(image.height) + ", " + std::to_string(image.rgba.size()) + " bytes)",
          "pass an image made by render_mesh or read_png");
}

/// A Cairo ARGB32 (premultiplied, native-endian) surface holding `image`.
SurfacePtr to_surface(const Image& image) {
  SurfacePtr surface(cairo_image_surface_create(CAIRO_FORMAT_ARGB32, image.width, image.height),
                     &cairo_surface_destroy);
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error("cannot allocate a " + std::to_string(image.width) + "x" +
                             std::to_string(image.height) + " image");
  cairo_surface_flush(surface.get());
  unsigned char* data = cairo_image_surface_get_data(surface.get());
  const int stride = cairo_image_surface_get_stride(surface.get());
  for (int y = 0; y < image.height; ++y) {
    auto* row = reinterpret_cast<std::uint32_t*>(data + static_cast<std::ptrdiff_t>(y) * stride);
    for (int x = 0; x < image.width; ++x) {
      const std::uint8_t* p = &image.rgba[(static_cast<std::size_t>(y) * image.width + x) * 4];
      const std::uint32_t a = p[3];
      auto pre = [a](std::uint8_t c) { return (static_cast<std::uint32_t>(c) * a + 127) / 255; };
      row[x] = a << 24 | pre(p[0]) << 16 | pre(p[1]) << 8 | pre(p[2]);
    }
  }
  cairo_surface_mark_dirty(surface.get());
  return surface;
}

/// The straight-alpha RGBA image of an ARGB32 or RGB24 surface.
Image from_surface(cairo_surface_t* surface) {
  cairo_surface_flush(surface);
  Image image;
  image.width = cairo_image_surface_get_width(surface);
  image.height = cairo_image_surface_get_height(surface);
  image.rgba.resize(static_cast<std::size_t>(image.width) * image.height * 4);
  const bool has_alpha = cairo_image_surface_get_format(surface) == CAIRO_FORMAT_ARGB32;
  const unsigned char* data = cairo_image_surface_get_data(surface);
  const int stride = cairo_image_surface_get_stride(surface);
  for (int y = 0; y < image.height; ++y) {
    const auto* row = reinterpret_cast<const std::uint32_t*>(data + static_cast<std::ptrdiff_t>(y) * stride);
    for (int x = 0; x < image.width; ++x) {
      const std::uint32_t v = row[x];
      const std::uint32_t a = has_alpha ? v >> 24 : 255;
      auto straight = [a](std::uint32_t c) {
        return static_cast<std::uint8_t>(a == 0 ? 0 : std::min<std::uint32_t>(255, (c * 255 + a / 2) / a));
      };
      std::uint8_t* p = &image.rgba[(static_cast<std::size_t>(y) * image.width + x) * 4];
      p[0] = straight((v >> 16) & 0xff);
      p[1] = straight((v >> 8) & 0xff);
      p[2] = straight(v & 0xff);
      p[3] = static_cast<std::uint8_t>(a);
    }
  }
  return image;
}

double text_width(cairo_t* cr, const std::string& text, double size) {
  if (text.empty()) return 0;
  cairo_set_font_size(cr, size);
  cairo_text_extents_t ext;
  cairo_text_extents(cr, text.c_str(), &ext);
  return ext.x_advance;
}

/// Draws `text` with its horizontal start at `x` and its vertical centre at `y_centre`.
void draw_text(cairo_t* cr, const std::string& text, double x, double y_centre, double size) {
  if (text.empty()) return;
  cairo_set_font_size(cr, size);
  cairo_font_extents_t fe;
  cairo_font_extents(cr, &fe);
  cairo_move_to(cr, std::round(x), std::round(y_centre + 0.5 * (fe.ascent - fe.descent)));
  cairo_show_text(cr, text.c_str());
}

}  // namespace

void write_png(const Image& image, const std::string& path) {
  check_image(image, "write_png('" + path + "')");
  const SurfacePtr surface = to_surface(image);
  write_file_atomically(path, [&](const std::string& tmp) {
    const cairo_status_t status = cairo_surface_write_to_png(surface.get(), tmp.c_str());
    require(status == CAIRO_STATUS_SUCCESS, "write_png: " + path,
            std::string("Cairo cannot write it (") + cairo_status_to_string(status) + ")",
            "check that the folder is writable and the disk has space");
  });
}

Image read_png(const std::string& path) {
  SurfacePtr surface(cairo_image_surface_create_from_png(path.c_str()), &cairo_surface_destroy);
  const cairo_status_t status = cairo_surface_status(surface.get());
  if (status != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error("read_png: cannot read '" + path + "': " + cairo_status_to_string(status));
  const cairo_format_t format = cairo_image_surface_get_format(surface.get());
  if (format == CAIRO_FORMAT_ARGB32 || format == CAIRO_FORMAT_RGB24) return from_surface(surface.get());
  // Other formats (A8, ...): paint onto an ARGB32 surface first.
  SurfacePtr argb(
      cairo_image_surface_create(CAIRO_FORMAT_ARGB32, cairo_image_surface_get_width(surface.get()),
                                 cairo_image_surface_get_height(surface.get())),
      &cairo_surface_destroy);
  ContextPtr cr(cairo_create(argb.get()), &cairo_destroy);
  cairo_set_source_surface(cr.get(), surface.get(), 0, 0);
  cairo_paint(cr.get());
  return from_surface(argb.get());
}

Image compose_contact_sheet(const std::vector<std::vector<Image>>& grid,
                            const std::vector<std::string>& row_labels,
                            const std::vector<std::string>& column_labels, const std::string& title) {
  const int rows = static_cast<int>(grid.size());
  int cols = 0, cell_w = 0, cell_h = 0;
  for (std::size_t r = 0; r < grid.size(); ++r) {
    cols = std::max(cols, static_cast<int>(grid[r].size()));
    for (std::size_t c = 0; c < grid[r].size(); ++c) {
      check_image(grid[r][c], "contact sheet image [" + std::to_string(r) + "][" + std::to_string(c) + "]");
      cell_w = std::max(cell_w, grid[r][c].width);
      cell_h = std::max(cell_h, grid[r][c].height);
    }
  }
  require(rows > 0 && cols > 0, "contact sheet", "has no images", "pass at least one image");
  require(
      row_labels.empty() || static_cast<int>(row_labels.size()) == rows, "contact sheet row labels",
      "need one label per row (" + std::to_string(rows) + ", got " + std::to_string(row_labels.size()) + ")",
      "pass one label per method or none");
  require(column_labels.empty() || static_cast<int>(column_labels.size()) == cols,
          "contact sheet column labels",
          "need one label per column (" + std::to_string(cols) + ", got " +
              std::to_string(column_labels.size()) + ")",
          "pass one label per frame or none");

  // Layout from the text extents.
  SurfacePtr scratch(cairo_image_surface_create(CAIRO_FORMAT_ARGB32, 1, 1), &cairo_surface_destroy);
  ContextPtr measure(cairo_create(scratch.get()), &cairo_destroy);
  cairo_select_font_face(measure.get(), kFontFace, CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  double label_w = 0;
  for (const auto& l : row_labels) label_w = std::max(label_w, text_width(measure.get(), l, kLabelFont));
  const int label_col = label_w > 0 ? static_cast<int>(std::ceil(label_w)) + kPad : 0;
  const bool any_col_label = std::any_of(column_labels.begin(), column_labels.end(),
                                         [](const std::string& s) { return !s.empty(); });
  const int title_h = title.empty() ? 0 : static_cast<int>(std::ceil(1.6 * kTitleFont));
  const int col_label_h = any_col_label ? static_cast<int>(std::ceil(1.5 * kLabelFont)) : 0;
  const int x0 = kPad + label_col, y0 = kPad + title_h + col_label_h;
  cairo_select_font_face(measure.get(), kFontFace, CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
  const int title_w = static_cast<int>(std::ceil(text_width(measure.get(), title, kTitleFont))) + 2 * kPad;
  const int width = std::max(x0 + cols * (cell_w + kPad), title_w);
  const int height = y0 + rows * (cell_h + kPad);

  SurfacePtr sheet(cairo_image_surface_create(CAIRO_FORMAT_ARGB32, width, height), &cairo_surface_destroy);
  if (cairo_surface_status(sheet.get()) != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error("contact sheet: cannot allocate " + std::to_string(width) + "x" +
                             std::to_string(height) + " pixels");
  ContextPtr cr(cairo_create(sheet.get()), &cairo_destroy);
  cairo_set_source_rgb(cr.get(), 1, 1, 1);
  cairo_paint(cr.get());
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < static_cast<int>(grid[static_cast<std::size_t>(r)].size()); ++c) {
      const Image& img = grid[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)];
      const SurfacePtr s = to_surface(img);
      const int x = x0 + c * (cell_w + kPad) + (cell_w - img.width) / 2;
      const int y = y0 + r * (cell_h + kPad) + (cell_h - img.height) / 2;
      cairo_set_source_surface(cr.get(), s.get(), x, y);
      cairo_rectangle(cr.get(), x, y, img.width, img.height);
      cairo_fill(cr.get());
    }
  cairo_select_font_face(cr.get(), kFontFace, CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_source_rgb(cr.get(), 0.1, 0.1, 0.1);
  for (int r = 0; r < static_cast<int>(row_labels.size()); ++r)
    draw_text(cr.get(), row_labels[static_cast<std::size_t>(r)], kPad,
              y0 + r * (cell_h + kPad) + 0.5 * cell_h, kLabelFont);
  for (int c = 0; c < static_cast<int>(column_labels.size()); ++c) {
    const std::string& l = column_labels[static_cast<std::size_t>(c)];
    const double w = text_width(cr.get(), l, kLabelFont);
    draw_text(cr.get(), l, x0 + c * (cell_w + kPad) + 0.5 * (cell_w - w), kPad + title_h + 0.5 * col_label_h,
              kLabelFont);
  }
  if (!title.empty()) {
    cairo_select_font_face(cr.get(), kFontFace, CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
    const double w = text_width(cr.get(), title, kTitleFont);
    draw_text(cr.get(), title, 0.5 * (width - w), kPad + 0.5 * title_h, kTitleFont);
  }
  return from_surface(sheet.get());
}

void write_contact_sheet(const std::vector<std::vector<Image>>& grid,
                         const std::vector<std::string>& row_labels,
                         const std::vector<std::string>& column_labels, const std::string& title,
                         const std::string& path) {
  write_png(compose_contact_sheet(grid, row_labels, column_labels, title), path);
}

}  // namespace isokit::skinning
