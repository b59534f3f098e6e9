// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include "isokit/core/error.h"
#include "isokit/opdesigner/designer.h"
#include "isokit/operators/biharmonic.h"

using namespace isokit;
using namespace isokit::operators;

namespace {
StoredOperator make(const std::string& preset, int res) {
  StoredOperator s;
  s.spec = preset_spec(preset, res);
  s.grid = generate_operator(s.spec);
  return s;
}
}  // namespace

TEST_CASE("compose: contact grows with d for g_dc, none for the clean union", "[opdesigner]") {
  const StoredOperator dc = make("contact", 32), cu = make("clean-union", 32);
  opdesigner::ComposeOptions o;
  o.samples = 201;
  o.angle_deg = 130;
  double prev = -1;
  for (double d : {0.0, 0.3, 0.6, 1.0}) {
    o.d = d;
    const double len = opdesigner::compose(dc, o, "").contact_length;
    INFO("d = " << d << " contact length " << len);
    if (d == 0.0) CHECK(len == 0.0);
    if (d > 0.0) CHECK(len > prev);
    prev = len;
  }
  o.d.reset();
  CHECK(opdesigner::compose(cu, o, "").contact_length == 0.0);
  // With the contact controller: no contact for a slight bend, contact for a deep one.
  o.angle_deg = 45;
  CHECK(opdesigner::compose(dc, o, "").contact_length == 0.0);
  o.angle_deg = 150;
  CHECK(opdesigner::compose(dc, o, "").contact_length > 0.05);
}

TEST_CASE("opdesigner: bad arguments are InputErrors", "[opdesigner]") {
  const StoredOperator dc = make("contact", 16);
  opdesigner::ComposeOptions o;
  o.angle_deg = 200;
  CHECK_THROWS_AS(opdesigner::compose(dc, o, ""), InputError);
  o.angle_deg = 90;
  o.d = 1.5;
  CHECK_THROWS_AS(opdesigner::compose(dc, o, ""), InputError);
  CHECK_THROWS_AS(opdesigner::plot_slice(dc, -0.1, "x.png"), InputError);
}
