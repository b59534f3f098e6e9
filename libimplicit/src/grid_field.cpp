// SPDX-License-Identifier: MIT
#include "isokit/implicit/grid_field.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "isokit/core/error.h"

namespace isokit::implicit {
namespace {

std::string box_text(const Box3f& b) {
  auto v = [](const Vec3f& p) {
    return "(" + format_number(p.x) + ", " + format_number(p.y) + ", " + format_number(p.z) + ")";
  };
  return "[" + v(b.lo) + " .. " + v(b.hi) + "]";
}

void check_grid(int n, const Box3f& box) {
  require(n >= 2 && n <= GridField::kMaxResolution, "GridField resolution",
          "must be in [2, " + std::to_string(GridField::kMaxResolution) + "] (got " + std::to_string(n) + ")",
          "use the paper's 32, or another resolution in range");
  bool finite = true;
  for (int a = 0; a < 3; ++a) finite = finite && std::isfinite(box.lo[a]) && std::isfinite(box.hi[a]);
  require(finite, "GridField box", "is not finite " + box_text(box),
          "pass a finite box (or a source with a finite support)");
  require(!box.empty() && box.hi.x > box.lo.x && box.hi.y > box.lo.y && box.hi.z > box.lo.z, "GridField box",
          "is empty or flat " + box_text(box), "pass a box with positive extent on every axis");
}

}  // namespace

GridField::GridField(int resolution, const Box3f& box, const std::vector<float>& nodes, GridStorage storage)
    : n_(resolution), box_(box) {
  check_grid(n_, box_);
  const std::size_t n = static_cast<std::size_t>(n_);
  require(nodes.size() == 4 * n * n * n, "GridField nodes",
          "holds " + std::to_string(nodes.size()) + " floats for " + std::to_string(n_) + "^3 nodes",
          "pass 4 floats (value, gradient) per node");
  for (float v : nodes)
    if (!std::isfinite(v))
      require(false, "GridField nodes", "hold a non-finite value", "compute finite node data");
  store(nodes, storage);
}

GridField::GridField(const GridField& other)
    : Field(other),
      n_(other.n_),
      box_(other.box_),
      nodes_(other.nodes_),
      packed_(other.packed_),
      occupied_(other.occupied_),
      view_(other.view_) {
  view_.nodes = nodes_.empty() ? nullptr : nodes_.data();
  view_.packed = packed_.empty() ? nullptr : packed_.data();
  view_.occupied = occupied_.data();
}

void GridField::mark_occupied(const std::vector<float>& stored) {
  // A brick is occupied when a node of its cells (nodes kBrick b .. kBrick b + kBrick, clamped)
  // stores a non-zero value.
  const int B = GridView::kBrick, cells = n_ - 1, nb = (cells + B - 1) / B;
  occupied_.assign((std::size_t(nb) * std::size_t(nb) * std::size_t(nb) + 63) / 64, 0);
  const auto n = std::size_t(n_);
  for (std::size_t k = 0; k < n; ++k)
    for (std::size_t j = 0; j < n; ++j)
      for (std::size_t i = 0; i < n; ++i) {
        if (stored[4 * ((k * n + j) * n + i)] == 0.f) continue;
        // Node i is a corner of cells i - 1 and i: of the bricks holding either.
        const int idx[3] = {int(i), int(j), int(k)};
        int lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
          lo[a] = std::max(0, idx[a] - 1) / B;
          hi[a] = std::min(cells - 1, idx[a]) / B;
        }
        for (int z = lo[2]; z <= hi[2]; ++z)
          for (int y = lo[1]; y <= hi[1]; ++y)
            for (int x = lo[0]; x <= hi[0]; ++x) {
              const std::size_t b =
                  (std::size_t(z) * std::size_t(nb) + std::size_t(y)) * std::size_t(nb) + std::size_t(x);
              occupied_[b / 64] |= std::uint64_t(1) << (b % 64);
            }
      }
  view_.occupied = occupied_.data();
  view_.bricks = nb;
}

void GridField::store(const std::vector<float>& nodes, GridStorage storage) {
  view_ = GridView{nullptr, n_, box_};
  if (storage == GridStorage::float32) {
    nodes_ = nodes;
    view_.nodes = nodes_.data();
    mark_occupied(nodes_);
    return;
  }
  // One scale for the value, one for the three gradient components (the error of a gradient
  // does not depend on its direction): the largest magnitude maps to 32767, 0 stays exactly 0.
  float largest[2] = {0.f, 0.f};
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    float& m = largest[i % 4 == 0 ? 0 : 1];
    m = std::max(m, std::fabs(nodes[i]));
  }
  float* scale = view_.scale;
  for (int c = 0; c < 4; ++c) scale[c] = largest[c == 0 ? 0 : 1] / 32767.f;
  packed_.resize(nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const float s = scale[i % 4];
    const float q = s > 0.f ? std::round(nodes[i] / s) : 0.f;
    packed_[i] = static_cast<std::int16_t>(std::clamp(q, -32767.f, 32767.f));
  }
  view_.packed = packed_.data();
  mark_occupied(this->nodes());
}

std::vector<float> GridField::nodes() const {
  if (packed_.empty()) return nodes_;
  std::vector<float> out(packed_.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = float(packed_[i]) * view_.scale[i % 4];
  return out;
}

std::array<float, 2> GridField::quantisation_bound() const {
  if (packed_.empty()) return {0.f, 0.f};
  // Half a step at every node (a convex combination keeps it), plus the float rounding of the
  // two interpolations: 8 products and sums of magnitudes up to 32767 steps, and the scaling.
  const float rounding = 16.f * 32767.f * 6e-8f;
  return {view_.scale[0] * (0.5f + rounding), view_.scale[1] * (0.5f + rounding)};
}

GridField::GridField(const Field& source, const Box3f& box, const GridFieldOptions& options)
    : n_(options.resolution), box_(box.empty() ? source.support() : box) {
  check_grid(n_, box_);
  const Box3f src = source.support();
  require(box_.contains(src), "GridField box",
          box_text(box_) + " does not contain the source support " + box_text(src),
          "grow the box to cover the support, or leave it empty to use the support");

  const auto n = static_cast<std::size_t>(n_);
  std::vector<float> nodes(4 * n * n * n, 0.f);
  const Vec3f step = box_.size() / float(n_ - 1);
  parallel_for(n * n, options.grain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t jk = begin; jk < end; ++jk) {
      const std::size_t j = jk % n, k = jk / n;
      for (std::size_t i = 0; i < n; ++i) {
        // The last node sits exactly on hi (no rounding drift past the box).
        const Vec3f p{i + 1 == n ? box_.hi.x : box_.lo.x + step.x * float(i),
                      j + 1 == n ? box_.hi.y : box_.lo.y + step.y * float(j),
                      k + 1 == n ? box_.hi.z : box_.lo.z + step.z * float(k)};
        const FieldSample s = source.eval(p);
        float* node = &nodes[4 * ((k * n + j) * n + i)];
        node[0] = s.value;
        node[1] = s.gradient.x;
        node[2] = s.gradient.y;
        node[3] = s.gradient.z;
      }
    }
  });
  store(nodes, options.storage);
}

void GridField::eval_batch(const Vec3f* points, std::size_t n, FieldSample* out, std::size_t grain) const {
  const GridView g = view();
  parallel_for(n, grain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) out[i] = eval_grid(g, points[i]);
  });
}

}  // namespace isokit::implicit
