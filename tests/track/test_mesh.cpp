// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include <algorithm>

#include "isokit/core/error.h"
#include "isokit/track/mesh.h"

using namespace isokit;
using namespace isokit::track;

namespace {
// Closed octahedron (6 vertices, 8 faces, 12 edges).
Triangles octahedron() {
  Triangles F(8, 3);
  F << 0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5;
  return F;
}
}  // namespace

TEST_CASE("one-ring adjacency: symmetric, sorted, Euler-consistent", "[track][mesh]") {
  const Triangles F = octahedron();
  const Adjacency adj = vertex_adjacency(F, 6);
  REQUIRE(adj.offsets.size() == 7);
  CHECK(adj.neighbors.size() == 2 * 12);  // closed mesh: sum of degrees = 2E = 3F
  for (int v = 0; v < 6; ++v) {
    CHECK(adj.degree(v) == 4);
    const auto b = adj.neighbors.begin() + adj.offsets[v], e = adj.neighbors.begin() + adj.offsets[v + 1];
    CHECK(std::is_sorted(b, e));
    CHECK(std::adjacent_find(b, e) == e);
    for (auto it = b; it != e; ++it) {
      const int w = *it;
      CHECK(w != v);
      const auto wb = adj.neighbors.begin() + adj.offsets[w], we = adj.neighbors.begin() + adj.offsets[w + 1];
      CHECK(std::binary_search(wb, we, v));  // symmetric
    }
  }
  // An isolated extra vertex has no neighbours.
  const Adjacency with_isolated = vertex_adjacency(F, 7);
  CHECK(with_isolated.degree(6) == 0);
}

TEST_CASE("adjacency rejects bad faces naming the triangle", "[track][mesh][errors]") {
  Triangles F(2, 3);
  F << 0, 1, 2, 0, 2, 7;
  CHECK_THROWS_WITH(vertex_adjacency(F, 4), Catch::Contains("triangle 1") && Catch::Contains("7"));
  F << 0, 1, 2, 0, 2, 2;
  CHECK_THROWS_WITH(vertex_adjacency(F, 4), Catch::Contains("triangle 1") && Catch::Contains("repeats"));
  F << 0, 1, -1, 0, 2, 3;
  CHECK_THROWS_WITH(vertex_adjacency(F, 4), Catch::Contains("triangle 0"));
  CHECK_THROWS_AS(vertex_adjacency(F, -1), InputError);
}
