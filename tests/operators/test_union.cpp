// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include "isokit/operators/operator.h"
#include "test_util.h"

using namespace isokit;

TEST_CASE("union (max): value and partial derivatives", "[operators]") {
  test::Rng rng(3);
  for (int i = 0; i < 2000; ++i) {
    const float f1 = float(rng.uniform(0, 1)), f2 = float(rng.uniform(0, 1));
    const auto s = operators::union_max(f1, f2);
    CHECK(s.g == std::max(f1, f2));
    if (std::abs(f1 - f2) > 1e-3f) {  // away from the tie the operator is differentiable
      const float h = 1e-4f;
      const float d1 = (operators::union_max(f1 + h, f2).g - operators::union_max(f1 - h, f2).g) / (2 * h);
      const float d2 = (operators::union_max(f1, f2 + h).g - operators::union_max(f1, f2 - h).g) / (2 * h);
      CHECK(s.dg1 == Approx(d1).margin(1e-3));
      CHECK(s.dg2 == Approx(d2).margin(1e-3));
    }
    CHECK(s.dg1 + s.dg2 == 1.f);  // always the gradient of exactly one operand
  }
  const auto tie = operators::union_max(0.5f, 0.5f);
  CHECK(tie.dg1 == 1.f);
  CHECK(tie.dg2 == 0.f);
  // Boundary behaviour of a union: g(f, 0) = f and g(0, f) = f.
  for (float f : {0.f, 0.25f, 0.5f, 1.f}) {
    CHECK(operators::union_max(f, 0.f).g == f);
    CHECK(operators::union_max(0.f, f).g == f);
  }
}
