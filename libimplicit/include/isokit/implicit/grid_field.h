// SPDX-License-Identifier: MIT
/// \file
/// A field sampled on a regular 3D grid (value and gradient per node) and evaluated by
/// trilinear interpolation of both — the 2013 paper's 32^3 textures (Implicit Skinning §6).
///
/// Interpolating the stored gradient (rather than differentiating the interpolated value) keeps
/// the gradient continuous across cells, which Newton projection and the gradient-angle
/// controllers need. Accuracy at 32^3 is measured in tests/implicit/test_grid_field.cpp and
/// stated in docs/implicit.md.
///
/// Nodes are stored as 16-bit fixed point by default (8 bytes per node, half of float32's):
/// the error this adds is bounded in `GridField::quantisation_bound` and measured on the real
/// rigs in docs/performance.md ("Field evaluation at memory speed").
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "isokit/implicit/field.h"
#include "isokit/implicit/grid_math.h"

namespace isokit::implicit {

/// How a grid stores its nodes (grid_math.h, GridView):
/// - `fixed16` (default; not in the papers): 4 int16 per node, the value scaled by its largest
///   magnitude and the three gradient components by theirs (one scale shared by the three);
/// - `float32`: 4 floats per node (the 2013 paper's textures; the reference).
enum class GridStorage { fixed16, float32 };

struct GridFieldOptions {
  /// Nodes per axis (2013 paper: 32). Must be in [2, kMaxResolution].
  int resolution = 32;
  /// Grain size for the parallel sampling (0 = serial; same result).
  std::size_t grain = 64;
  /// Node storage (default fixed16: half the memory; see GridStorage).
  GridStorage storage = GridStorage::fixed16;
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
  GridField(int resolution, const Box3f& box, const std::vector<float>& nodes,
            GridStorage storage = GridStorage::fixed16);

  /// Copies point their view at their own nodes.
  GridField(const GridField& other);
  GridField& operator=(const GridField&) = delete;

  FieldSample eval(const Vec3f& p) const override { return eval_grid(view(), p); }
  Box3f support() const override { return box_; }
  void eval_batch(const Vec3f* points, std::size_t n, FieldSample* out,
                  std::size_t grain = kDefaultGrain) const override;
  using Field::eval_batch;

  int resolution() const { return n_; }
  GridStorage storage() const { return packed_.empty() ? GridStorage::float32 : GridStorage::fixed16; }
  /// Plain view of the node data (for CUDA uploads and the tape).
  GridView view() const { return view_; }
  /// Node data as stored, decoded to 4 floats (value, gx, gy, gz) per node, x fastest.
  std::vector<float> nodes() const;
  /// Bytes of node data (16 per node in float32, 8 in fixed16) and of the occupancy bits.
  std::size_t bytes() const { return view_.node_bytes() + occupied_.size() * sizeof(std::uint64_t); }
  /// The largest difference between this grid's `eval` and the same nodes stored as float32,
  /// for any point: per channel, half a quantisation step plus the rounding of 8 products
  /// (0 for float32). Index 0 bounds the value, 1 each gradient component.
  std::array<float, 2> quantisation_bound() const;

 private:
  void store(const std::vector<float>& nodes, GridStorage storage);
  void mark_occupied(const std::vector<float>& nodes);

  int n_;
  Box3f box_;
  std::vector<float> nodes_;             ///< float32 storage (empty in fixed16)
  std::vector<std::int16_t> packed_;     ///< fixed16 storage (empty in float32)
  std::vector<std::uint64_t> occupied_;  ///< GridView::occupied
  GridView view_{};                      ///< over whichever storage holds the nodes
};

}  // namespace isokit::implicit
