// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include "isokit/core/error.h"
#include "isokit/core/math.h"
#include "test_util.h"

using namespace isokit;

TEST_CASE("rigid transforms invert and compose", "[core]") {
  test::Rng rng(1);
  for (int trial = 0; trial < 200; ++trial) {
    const Rigid3d a{rng.rotation(), rng.vec(-5, 5)}, b{rng.rotation(), rng.vec(-5, 5)};
    const Vec3d p = rng.vec(-3, 3);
    const Vec3d back = a.apply_inverse(a.apply(p));
    CHECK(norm(back - p) < 1e-12);
    const Vec3d composed = (a * b).apply(p), sequential = a.apply(b.apply(p));
    CHECK(norm(composed - sequential) < 1e-12);
    CHECK(std::abs(norm(a.rotate(p)) - norm(p)) < 1e-12);
    CHECK(norm(a.rotate_inverse(a.rotate(p)) - p) < 1e-12);
  }
}

TEST_CASE("boxes: empty by default, extend, contain", "[core]") {
  Box3d b;
  CHECK(b.empty());
  CHECK_FALSE(b.contains(Vec3d{0.5, 0.5, 0.5}));
  b.extend({1, 2, 3});
  CHECK_FALSE(b.empty());
  CHECK(b.contains(Vec3d{1, 2, 3}));
  b.extend({-1, 0, 5});
  CHECK(b.lo == Vec3d{-1, 0, 3});
  CHECK(b.hi == Vec3d{1, 2, 5});
  CHECK(b.contains(Box3d{{0, 1, 4}, {1, 2, 5}}));
  CHECK_FALSE(b.contains(Box3d{{0, 1, 4}, {1, 2, 6}}));
  CHECK(b.contains(Box3d{}));  // the empty box is inside every box
}

TEST_CASE("require names the item and the fix", "[core]") {
  try {
    require(false, "GridField resolution", "must be >= 2 (got 1)", "use 32");
    FAIL("require(false) did not throw");
  } catch (const InputError& e) {
    const std::string msg = e.what();
    CHECK(msg.find("GridField resolution") != std::string::npos);
    CHECK(msg.find("got 1") != std::string::npos);
    CHECK(msg.find("use 32") != std::string::npos);
  }
  CHECK(format_number(std::nan("")) == "NaN");
  CHECK(format_number(-INFINITY) == "-inf");
  CHECK(format_number(0.25) == "0.25");
}
