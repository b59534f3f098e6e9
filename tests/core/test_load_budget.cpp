// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>
#include <cstdint>
#include <limits>
#include <new>
#include <random>
#include <stdexcept>

#include "isokit/core/load_budget.h"
#include "isokit/core/stage.h"

using namespace isokit;

TEST_CASE("load budget: 64 bytes per input byte plus 64 MiB, saturating", "[core][unit]") {
  CHECK(load_budget_bytes(0) == LoadBudgetRule::kFixedBytes);
  CHECK(load_budget_bytes(1000) == 64000 + (std::uint64_t{64} << 20));
  CHECK(load_budget_bytes(std::numeric_limits<std::uint64_t>::max()) ==
        std::numeric_limits<std::uint64_t>::max());
  std::mt19937_64 rng(5);
  for (int i = 0; i < 200; ++i) {  // monotone in the input
    const std::uint64_t a = rng() >> (rng() % 64);
    const std::uint64_t b = rng() >> (rng() % 64);
    CHECK((a <= b ? load_budget_bytes(a) <= load_budget_bytes(b)
                  : load_budget_bytes(a) >= load_budget_bytes(b)));
    CHECK(load_budget_bytes(a) >= a);
  }
}

TEST_CASE("load budget: charges add up to the limit, then one error names the file and the item",
          "[core][unit]") {
  LoadBudget b("x.glb", 1000);
  const std::uint64_t limit = b.limit();
  b.charge(limit - 10, "first");
  CHECK(b.used() == limit - 10);
  b.charge(10, "second");  // exactly at the limit
  CHECK(b.used() == limit);
  CHECK_THROWS_WITH(b.charge(1, "accessor 3"), Catch::StartsWith("x.glb: accessor 3: declares 1 bytes") &&
                                                   Catch::Contains("past the load budget"));
  CHECK(b.used() == limit);  // a refused charge is not taken
  // Overflowing products and sums are refused, not wrapped.
  LoadBudget c("y.gltf", 10);
  CHECK_THROWS_AS(c.charge(std::uint64_t{1} << 62, 16, "huge"), InputError);
  c.charge(5, "small");
  CHECK_THROWS_AS(c.charge(std::numeric_limits<std::uint64_t>::max(), "max"), InputError);
  // An item that already names the file is not prefixed twice.
  CHECK_THROWS_WITH(c.charge(std::uint64_t{1} << 40, "y.gltf: mesh 0"),
                    Catch::StartsWith("y.gltf: mesh 0: declares"));
  // Input added later (a .gltf's buffers) raises the limit.
  const std::uint64_t before = c.limit();
  c.add_input(1 << 20);
  CHECK(c.limit() == before + (std::uint64_t{64} << 20));
}

TEST_CASE("stage: the innermost stage an exception leaves is remembered for the message", "[core][unit]") {
  Stage::clear_failed();
  CHECK(out_of_memory_message().rfind("out of memory;", 0) == 0);
  try {
    const Stage outer("reading a.glb");
    { const Stage done("a stage that ended normally"); }
    const Stage inner("decoding its accessors");
    throw std::bad_alloc();
  } catch (const std::bad_alloc&) {
  }
  CHECK(Stage::failed() == "decoding its accessors");
  CHECK(out_of_memory_message().rfind("out of memory while decoding its accessors;", 0) == 0);
  Stage::clear_failed();
  CHECK(Stage::failed().empty());
  // A stage left without an exception records nothing.
  { const Stage s("fine"); }
  CHECK(Stage::failed().empty());
}
