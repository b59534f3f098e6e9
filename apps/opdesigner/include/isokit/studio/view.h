// SPDX-License-Identifier: MIT
/// \file
/// The CPU side of the design studio's window (`isokit-opdesigner gui`), free of OpenGL and ImGui
/// so it is unit-tested: the map between a plot's domain and screen pixels, a slice as a scalar
/// grid, its colour image (uploaded as a GL texture) and its iso-lines. The studio's state and
/// edits are the model's (isokit/studio/model.h).
/// \note Field convention (ARCHITECTURE.md): g in [0, 1], the surface is g = 0.5, inside > 0.5.
#pragma once

#include <vector>

#include "isokit/operators/grid_operator.h"
#include "isokit/plot/figure.h"

namespace isokit::studio {

/// Maps a domain rectangle `[x0, x1] x [y0, y1]` (y up; the operator plot uses (f1, f2) in
/// [0, 1]²) onto a screen rectangle in pixels (`left`, `top`, `width`, `height`; y down).
struct PlotMapping {
  double left{0}, top{0}, width{1}, height{1};
  double x0{0}, y0{0}, x1{1}, y1{1};

  plot::Point2 to_screen(const plot::Point2& domain) const;
  plot::Point2 to_domain(const plot::Point2& pixel) const;
  /// True when `pixel` lies inside the screen rectangle.
  bool contains(const plot::Point2& pixel) const;
};

/// Slice `k` of `grid` over (f1, f2) ∈ [0, 1]² with x = f1 and y = f2 (`values[j * nf + i]` =
/// g(f1_i, f2_j)). \throw isokit::InputError when k is out of range.
plot::ScalarGrid slice_grid(const operators::GridOperator& grid, int k);
/// The same from one slice's `nf * nf` values in the generator's order (`values[i1 * nf + i2]`,
/// e.g. StudioModel::slice_values()).
plot::ScalarGrid slice_grid(const float* values, int nf);

/// The colour map (plot::colormap over [vmin, vmax]) of `grid`, one pixel per sample; row 0 is
/// the top of the plot (y = y1), so the image can be drawn as is.
plot::RgbaImage colour_image(const plot::ScalarGrid& grid, double vmin = 0.0, double vmax = 1.0);

/// The iso-lines at `level` (marching squares, plot::iso_segments).
struct IsoLineSet {
  float level{0};
  std::vector<plot::Segment2> segments;
};
/// Iso-lines every 0.1 from 0.1 to 0.9 (the studio draws the 0.5 line thick).
std::vector<IsoLineSet> decile_iso_lines(const plot::ScalarGrid& grid);

}  // namespace isokit::studio
