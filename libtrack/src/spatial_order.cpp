// SPDX-License-Identifier: MIT
#include "spatial_order.h"

#include <algorithm>
#include <cstdint>

namespace isokit::track::detail {

namespace {

// Spreads the low 21 bits of x to every third bit.
std::uint64_t spread_bits(std::uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffull;
  x = (x | x << 16) & 0x1f0000ff0000ffull;
  x = (x | x << 8) & 0x100f00f00f00f00full;
  x = (x | x << 4) & 0x10c30c30c30c30c3ull;
  x = (x | x << 2) & 0x1249249249249249ull;
  return x;
}

}  // namespace

std::vector<int> spatial_order(const std::vector<Vec3f>& pts) {
  Vec3f lo{0, 0, 0}, hi{0, 0, 0};
  if (!pts.empty()) lo = hi = pts[0];
  for (const Vec3f& p : pts) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  const float extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z, 1e-30f});
  const double scale = double((1 << 21) - 1) / double(extent);
  std::vector<std::uint64_t> key(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Vec3f d = pts[i] - lo;
    key[i] = spread_bits(std::uint64_t(double(d.x) * scale)) |
             spread_bits(std::uint64_t(double(d.y) * scale)) << 1 |
             spread_bits(std::uint64_t(double(d.z) * scale)) << 2;
  }
  std::vector<int> order(pts.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return key[a] != key[b] ? key[a] < key[b] : a < b; });
  return order;
}

}  // namespace isokit::track::detail
