// SPDX-License-Identifier: MIT
// Inputs found while fuzzing the operator readers (docs/fuzzing.md), stored in tests/data/fuzz/.
#include <catch2/catch.hpp>

#include <string>

#include "fuzz_input.h"
#include "isokit/core/error.h"
#include "isokit/operators/spec.h"

using isokit::test::fuzz_input;

TEST_CASE("fuzz: a spec integer beyond int is refused, not wrapped", "[operators][fuzz]") {
  // resolution 4294967312 = 2^32 + 16 used to read as 16.
  const std::string text = fuzz_input("spec-integer-wraps.json");
  CHECK_THROWS_AS(isokit::operators::spec_from_json(text, "spec-integer-wraps.json"), isokit::InputError);
  CHECK_THROWS_WITH(isokit::operators::spec_from_json(text, "spec-integer-wraps.json"),
                    Catch::Contains("resolution") && Catch::Contains("out of range"));
}

TEST_CASE("fuzz: a JSON number too large for a double is an InputError", "[operators][fuzz]") {
  // 1e999 made nlohmann::json::parse throw out_of_range (not parse_error), which escaped
  // spec_from_json as a non-InputError exception.
  const std::string text = fuzz_input("spec-number-overflow.json");
  CHECK_THROWS_AS(isokit::operators::spec_from_json(text, "spec-number-overflow.json"), isokit::InputError);
  CHECK_THROWS_WITH(isokit::operators::spec_from_json(text, "spec-number-overflow.json"),
                    Catch::Contains("not valid JSON"));
}
