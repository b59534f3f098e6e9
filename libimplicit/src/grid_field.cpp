// SPDX-License-Identifier: MIT
#include "isokit/implicit/grid_field.h"

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

GridField::GridField(int resolution, const Box3f& box, std::vector<float> nodes)
    : n_(resolution), box_(box), nodes_(std::move(nodes)) {
  check_grid(n_, box_);
  const std::size_t n = static_cast<std::size_t>(n_);
  require(nodes_.size() == 4 * n * n * n, "GridField nodes",
          "holds " + std::to_string(nodes_.size()) + " floats for " + std::to_string(n_) + "^3 nodes",
          "pass 4 floats (value, gradient) per node");
  for (float v : nodes_)
    require(std::isfinite(v), "GridField nodes", "hold a non-finite value", "compute finite node data");
}

GridField::GridField(const Field& source, const Box3f& box, const GridFieldOptions& options)
    : n_(options.resolution), box_(box.empty() ? source.support() : box) {
  check_grid(n_, box_);
  const Box3f src = source.support();
  require(box_.contains(src), "GridField box",
          box_text(box_) + " does not contain the source support " + box_text(src),
          "grow the box to cover the support, or leave it empty to use the support");

  const auto n = static_cast<std::size_t>(n_);
  nodes_.assign(4 * n * n * n, 0.f);
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
        float* node = &nodes_[4 * ((k * n + j) * n + i)];
        node[0] = s.value;
        node[1] = s.gradient.x;
        node[2] = s.gradient.y;
        node[3] = s.gradient.z;
      }
    }
  });
}

void GridField::eval_batch(const Vec3f* points, std::size_t n, FieldSample* out, std::size_t grain) const {
  const GridView g = view();
  parallel_for(n, grain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) out[i] = eval_grid(g, points[i]);
  });
}

}  // namespace isokit::implicit
