// SPDX-License-Identifier: MIT
// The stored inputs of fuzzing findings (tests/data/fuzz/, docs/fuzzing.md), for the regression
// tests of the test executables that define ISOKIT_TEST_SOURCE_DIR.
#pragma once

#include <catch2/catch.hpp>

#include <fstream>
#include <iterator>
#include <string>

namespace isokit::test {

/// The bytes of tests/data/fuzz/`name`.
inline std::string fuzz_input(const std::string& name) {
  std::ifstream in(std::string(ISOKIT_TEST_SOURCE_DIR) + "/data/fuzz/" + name, std::ios::binary);
  REQUIRE(in.is_open());
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace isokit::test
