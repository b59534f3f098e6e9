// SPDX-License-Identifier: MIT
#include "points.h"

#include "isokit/core/error.h"

namespace isokit::track::detail {

std::vector<Vec3f> to_points(const Positions& p, const std::string& what) {
  std::vector<Vec3f> out(static_cast<std::size_t>(p.rows()));
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    out[static_cast<std::size_t>(i)] = row(p, i);
    if (!finite(out[static_cast<std::size_t>(i)]))  // message built only on failure (hot path)
      require(false, what + " vertex " + std::to_string(i), "is not finite", "pass finite coordinates");
  }
  return out;
}

void from_points(const std::vector<Vec3f>& pts, Positions& p) {
  p.resize(static_cast<Eigen::Index>(pts.size()), 3);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const auto r = static_cast<Eigen::Index>(i);
    p(r, 0) = pts[i].x, p(r, 1) = pts[i].y, p(r, 2) = pts[i].z;
  }
}

}  // namespace isokit::track::detail
