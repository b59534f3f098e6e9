// SPDX-License-Identifier: MIT
/// \file
/// Offscreen renders of skins with no display and no GPU: a small software rasterizer (z-buffer,
/// perspective camera, Lambert + ambient + rim shading, per-face or smooth normals, optional
/// per-vertex / per-face colours and wireframe, supersampled anti-aliasing), PNG output and
/// labelled contact sheets (methods x frames) through Cairo. Output is deterministic: the same
/// inputs give the same bytes, whatever the thread count.
///
/// Camera: it looks along `view_direction` at the centre of `frame` (a box shared by several
/// renders, so frames and methods line up), from the smallest distance at which all eight
/// corners of the box project inside the image shrunk by `margin`. Triangles with a corner
/// behind the near plane are skipped (geometry far outside `frame` can be cut).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "isokit/track/mesh.h"

namespace isokit::skinning {

/// An 8-bit RGBA image, rows top to bottom, straight (not premultiplied) alpha:
/// pixel `(x, y)` is `rgba[4 * (y * width + x) + {0, 1, 2, 3}]`.
struct Image {
  int width{0}, height{0};
  std::vector<std::uint8_t> rgba;
};

/// `#rows by 3` linear RGB colours in [0, 1].
using Colors = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;

enum class Shading { Flat, Smooth };

/// Options of `render_mesh`; colours are linear RGB in [0, 1]. Bad values throw InputError naming
/// the option.
struct RenderOptions {
  int width{800}, height{800};                      ///< image size in pixels, [1, 16384]
  int supersample{2};                               ///< samples per pixel along each axis, [1, 8]
  Eigen::Vector3d view_direction{0, 0, -1};         ///< camera looks along this (eye -> scene), non-zero
  Eigen::Vector3d up{0, 1, 0};                      ///< image up (made orthogonal to the view), not along it
  Eigen::AlignedBox3d frame;                        ///< box to frame; empty: the mesh's bounding box
  double field_of_view_deg{30};                     ///< vertical field of view in degrees, (0, 180)
  double margin{0.05};                              ///< free border, fraction of the half image size, [0, 1)
  Shading shading{Shading::Smooth};                 ///< face normals, or interpolated vertex normals
  Eigen::Vector3f base_color{0.82f, 0.70f, 0.58f};  ///< front faces without given colours
  Eigen::Vector3f back_color{0.35f, 0.45f, 0.80f};  ///< back faces without given colours
  Eigen::Vector3f background{1.0f, 1.0f, 1.0f};     ///< samples no triangle covers
  Colors vertex_colors;                             ///< `#V by 3`, interpolated; or empty
  Colors face_colors;                               ///< `#F by 3`, overrides `vertex_colors`; or empty
  double ambient{0.18};   ///< light floor: colour × (ambient + (1 − ambient) × diffuse)
  double rim{0.25};       ///< strength of the silhouette brightening (added to every channel)
  bool wireframe{false};  ///< draw triangle edges over the shading
  Eigen::Vector3f wire_color{0.12f, 0.12f, 0.12f};
  double wire_width_px{1.0};  ///< wire width in pixels, ≥ 0
};

/// The pinhole camera `render_mesh` uses, for placing overlays and for tests.
struct Camera {
  Eigen::Vector3d eye, forward, right, up;  ///< orthonormal; `right = forward x up`
  double focal_px{1};                       ///< focal length in pixels
  int width{0}, height{0};

  /// `(x, y, depth)`: pixel coordinates (x right, y down; pixel `i` covers `[i, i+1)`) and the
  /// distance along `forward` (≤ 0: behind the camera, x and y meaningless).
  Eigen::Vector3d project(const Eigen::Vector3d& p) const;
};

/// The camera framing `box` (must not be empty) with `options`' view, size and margin.
/// \throw InputError for a bad option (named).
Camera frame_camera(const RenderOptions& options, const Eigen::AlignedBox3d& box);

/// Renders the mesh (`#V by 3`, `#F by 3`). Both sides of every triangle are drawn; a side
/// facing away from the camera uses `back_color` (so inside-out parts show).
/// \throw InputError for an index out of range, colours of the wrong size or a bad option.
Image render_mesh(const track::Positions& positions, const track::Triangles& triangles,
                  const RenderOptions& options);

/// Writes a PNG through Cairo, atomically (isokit::write_file_atomically).
/// \throw InputError for an image whose size does not match its pixels, or naming `path` if it
/// cannot be written.
void write_png(const Image& image, const std::string& path);

/// Reads a PNG through Cairo. \throw std::runtime_error naming `path` if it cannot be read.
Image read_png(const std::string& path);

/// A labelled grid: `grid[row][column]` (rows = methods, columns = frames or poses), each cell
/// as large as the largest image, images centred in their cells, white background; row labels
/// on the left, column labels above, the title on top. Label lists are empty or one per
/// row / column; rows may be shorter than the longest (blank cells).
/// \throw InputError for a label count that does not match, or no images at all.
Image compose_contact_sheet(const std::vector<std::vector<Image>>& grid,
                            const std::vector<std::string>& row_labels,
                            const std::vector<std::string>& column_labels, const std::string& title);

/// `compose_contact_sheet` written as a PNG to `path` (same errors as both).
void write_contact_sheet(const std::vector<std::vector<Image>>& grid,
                         const std::vector<std::string>& row_labels,
                         const std::vector<std::string>& column_labels, const std::string& title,
                         const std::string& path);

}  // namespace isokit::skinning
