// SPDX-License-Identifier: MIT
#include "isokit/studio/view.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "isokit/core/error.h"

namespace isokit::studio {

plot::Point2 PlotMapping::to_screen(const plot::Point2& p) const {
  return {left + width * (p[0] - x0) / (x1 - x0), top + height * (y1 - p[1]) / (y1 - y0)};
}

plot::Point2 PlotMapping::to_domain(const plot::Point2& px) const {
  return {x0 + (x1 - x0) * (px[0] - left) / width, y1 - (y1 - y0) * (px[1] - top) / height};
}

bool PlotMapping::contains(const plot::Point2& px) const {
  return px[0] >= left && px[0] <= left + width && px[1] >= top && px[1] <= top + height;
}

plot::ScalarGrid slice_grid(const float* values, int nf) {
  require(values != nullptr && nf >= 2, "operator slice", "is missing or has fewer than 2 nodes per axis",
          "pass one slice of nf x nf values");
  plot::ScalarGrid g;
  g.nx = g.ny = nf;
  g.values.resize(static_cast<std::size_t>(nf) * nf);
  // Generator order values[i1 * nf + i2]; grid order values[j * nx + i] with x = f1, y = f2.
  for (int i1 = 0; i1 < nf; ++i1)
    for (int i2 = 0; i2 < nf; ++i2)
      g.values[static_cast<std::size_t>(i2) * nf + i1] = values[static_cast<std::size_t>(i1) * nf + i2];
  return g;
}

plot::ScalarGrid slice_grid(const operators::GridOperator& grid, int k) {
  require(k >= 0 && k < grid.nd(), "slice " + std::to_string(k), "is out of range",
          "the operator has " + std::to_string(grid.nd()) + " slices");
  return slice_grid(grid.slice(k), grid.nf());
}

plot::RgbaImage colour_image(const plot::ScalarGrid& grid, double vmin, double vmax) {
  require(grid.nx >= 1 && grid.ny >= 1 && grid.values.size() == static_cast<std::size_t>(grid.nx) * grid.ny,
          "scalar grid", "is empty or its value count does not match nx * ny", "fill nx * ny values");
  plot::RgbaImage img;
  img.width = grid.nx;
  img.height = grid.ny;
  img.pixels.resize(4 * grid.values.size());
  const double span = vmax > vmin ? vmax - vmin : 1.0;
  for (int row = 0; row < grid.ny; ++row)
    for (int i = 0; i < grid.nx; ++i) {
      const double t = std::clamp((grid.at(i, grid.ny - 1 - row) - vmin) / span, 0.0, 1.0);
      const plot::Rgb c = plot::colormap(t);
      std::uint8_t* p = &img.pixels[4 * (static_cast<std::size_t>(row) * grid.nx + i)];
      for (int ch = 0; ch < 3; ++ch) p[ch] = std::uint8_t(std::lround(255.0 * std::clamp(c[ch], 0.0, 1.0)));
      p[3] = 255;
    }
  return img;
}

std::vector<IsoLineSet> decile_iso_lines(const plot::ScalarGrid& grid) {
  std::vector<IsoLineSet> out;
  for (int l = 1; l <= 9; ++l) out.push_back({0.1f * float(l), plot::iso_segments(grid, 0.1f * float(l))});
  return out;
}

}  // namespace isokit::studio
