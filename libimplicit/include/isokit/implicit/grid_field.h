// SPDX-License-Identifier: MIT
/// \file
/// A field sampled on a regular 3D grid (value and gradient per node) and evaluated by
/// trilinear interpolation of both — the 2013 paper's 32^3 textures (Implicit Skinning §6).
///
/// Interpolating the stored gradient (rather than differentiating the interpolated value) keeps
/// the gradient continuous across cells, which Newton projection and the gradient-angle
/// controllers need. Accuracy at 32^3 is measured in tests/implicit/test_grid_field.cpp and
/// stated in docs/implicit.md.
#pragma once

#include <vector>

#include "isokit/implicit/field.h"
#include "isokit/implicit/grid_math.h"

namespace isokit::implicit {

struct GridFieldOptions {
  /// Nodes per axis (2013 paper: 32). Must be in [2, kMaxResolution].
  int resolution = 32;
  /// Grain size for the parallel sampling (0 = serial; same result).
  std::size_t grain = 64;
};

class GridField final : public Field {
 public:
  /// Largest accepted resolution: 512^3 nodes take 2 GiB.
  static constexpr int kMaxResolution = 512;

  /// Samples `source` on `box` (which must contain `source.support()` so that the grid is exact
  /// where it stops: 0 outside). An empty `box` argument means `source.support()`.
  /// \throw InputError if the resolution is out of range, the box is empty, degenerate or not
  /// finite, or does not contain the source's support.
  GridField(const Field& source, const Box3f& box = Box3f{}, const GridFieldOptions& options = {});

  /// A grid from node data computed elsewhere: `nodes` holds 4 floats (value, gx, gy, gz) per
  /// node, x fastest, `resolution`³ nodes spanning `box` (first and last nodes on its faces).
  /// The caller guarantees the field vanishes on the box faces (compact support).
  /// \throw InputError if the resolution is out of range, the box is empty, degenerate or not
  /// finite, or `nodes` has the wrong size or non-finite entries.
  GridField(int resolution, const Box3f& box, std::vector<float> nodes);

  FieldSample eval(const Vec3f& p) const override { return eval_grid(view(), p); }
  Box3f support() const override { return box_; }
  void eval_batch(const Vec3f* points, std::size_t n, FieldSample* out,
                  std::size_t grain = kDefaultGrain) const override;
  using Field::eval_batch;

  int resolution() const { return n_; }
  /// Plain view of the node data (for CUDA uploads and the tape).
  GridView view() const { return {nodes_.data(), n_, box_}; }
  /// Node data, 4 floats (value, gx, gy, gz) per node, x fastest.
  const std::vector<float>& nodes() const { return nodes_; }

 private:
  int n_;
  Box3f box_;
  std::vector<float> nodes_;
};

}  // namespace isokit::implicit
