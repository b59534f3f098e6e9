// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include <atomic>
#include <thread>
#include <vector>

#include "isokit/core/parallel.h"

using namespace isokit;

TEST_CASE("parallel_for covers every index exactly once", "[core][parallel]") {
  for (std::size_t n : {0u, 1u, 7u, 1000u, 100003u}) {
    for (std::size_t grain : {0u, 1u, 13u, 1024u, 1000000u}) {
      std::vector<std::atomic<int>> hits(n);
      parallel_for(n, grain, [&](std::size_t b, std::size_t e) {
        REQUIRE(b < e);
        REQUIRE(e <= n);
        for (std::size_t i = b; i < e; ++i) hits[i]++;
      });
      for (std::size_t i = 0; i < n; ++i) REQUIRE(hits[i] == 1);
    }
  }
}

TEST_CASE("grain 0 runs serially on the calling thread", "[core][parallel]") {
  const auto caller = std::this_thread::get_id();
  int calls = 0;
  parallel_for(50000, 0, [&](std::size_t b, std::size_t e) {
    ++calls;
    CHECK(b == 0);
    CHECK(e == 50000);
    CHECK(std::this_thread::get_id() == caller);
  });
  CHECK(calls == 1);
}
