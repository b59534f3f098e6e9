// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include <cmath>

#include "isokit/core/error.h"
#include "isokit/core/math.h"
#include "isokit/operators/controller.h"

using namespace isokit;
using operators::Controller;

namespace {}

TEST_CASE("controller presets follow the papers' shapes", "[operators][controller]") {
  const Controller dc = Controller::preset("contact");
  for (double a = 0; a <= kPi / 2; a += 0.01) CHECK(dc.eval(a) == 0.0);
  CHECK(dc.eval(kPi) == 1.0);
  const Controller db = Controller::preset("bulge");
  CHECK(db.eval(0) == 0.0);
  CHECK(db.eval(0.3) > 0.0);  // the bulge starts at low angles (2014 Fig. 4b)
  CHECK(db.eval(kPi / 2) == Approx(0.5));
  CHECK(db.eval(kPi) == 1.0);
  for (double a = 0.01; a <= kPi; a += 0.01) CHECK(db.eval(a) > db.eval(a - 0.01));  // rises all the way
  const Controller db13 = Controller::preset("bulge2013");
  for (double a = kPi / 2; a <= kPi; a += 0.01) CHECK(db13.eval(a) == Approx(1.0));
  const Controller b13 = Controller::preset("blend2013");
  CHECK(b13.eval(0) == 0.0);
  CHECK(b13.eval(kPi / 4) == Approx(1.0));
  for (double a = kPi / 2; a <= kPi; a += 0.01) CHECK(b13.eval(a) == Approx(0.0).margin(1e-12));
  for (const auto& name : Controller::preset_names()) {
    const Controller c = Controller::preset(name);
    const auto t = c.table();
    // Bounded, C1 (zero slope at the knots), table within 5e-4 of the curve.
    for (double a = 0; a <= kPi; a += 0.001) {
      CHECK(c.eval(a) >= -1e-12);
      CHECK(c.eval(a) <= 1 + 1e-12);
      CHECK(t(float(a)) == Approx(c.eval(a)).margin(5e-4));
    }
    for (const auto& k : c.knots()) {
      const double h = 1e-6;
      if (k.alpha - h > 0) CHECK(std::abs(c.eval(k.alpha) - c.eval(k.alpha - h)) / h < 1e-4);
      if (k.alpha + h < kPi) CHECK(std::abs(c.eval(k.alpha + h) - c.eval(k.alpha)) / h < 1e-4);
    }
  }
  const auto dt = dc.table();
  CHECK(dt(-1.f) == 0.f);
  CHECK(dt(10.f) == 1.f);
  CHECK(dt(std::nanf("")) == 0.f);
}

TEST_CASE("controller: bad knots are rejected with the knot named", "[operators][controller]") {
  CHECK_THROWS_AS(Controller::preset("nope"), InputError);
  CHECK_THROWS_WITH(Controller({{0, 0}, {1, 2}, {kPi, 1}}), Catch::Contains("knots[1]"));
  CHECK_THROWS_WITH(Controller({{0, 0}, {2, 0.5}, {1, 0.5}, {kPi, 1}}), Catch::Contains("knots[2]"));
  CHECK_THROWS_AS(Controller({{0.5, 0}, {kPi, 1}}), InputError);
  CHECK_THROWS_AS(Controller({{0, 0}}), InputError);
}
