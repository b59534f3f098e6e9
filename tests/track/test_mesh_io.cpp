// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include <cstdio>
#include <fstream>

#include "isokit/core/error.h"
#include "isokit/track/mesh_io.h"
#include "track/track_fixtures.h"

using namespace isokit;
using namespace isokit::track;

TEST_CASE("mesh files round-trip through OpenMesh", "[track][mesh]") {
  const test::Mesh m = test::capsule_mesh(0.3f, 0.5f, 10, 4, 3);
  const std::string path = "isokit_test_mesh_io.off";
  write_mesh(path, m.V, m.F);
  const TriangleMesh r = read_mesh(path);
  std::remove(path.c_str());
  REQUIRE(r.vertices.rows() == m.V.rows());
  REQUIRE(r.triangles.rows() == m.F.rows());
  CHECK(r.triangles == m.F);
  CHECK((r.vertices - m.V).cwiseAbs().maxCoeff() <= 1e-5f);
}

TEST_CASE("mesh files: quads are triangulated, bad files are rejected", "[track][mesh][errors]") {
  const std::string quad = "isokit_test_quad.off";
  {
    std::ofstream f(quad);
    f << "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
  }
  const TriangleMesh r = read_mesh(quad);
  std::remove(quad.c_str());
  CHECK(r.vertices.rows() == 4);
  CHECK(r.triangles.rows() == 2);
  CHECK_THROWS_WITH(read_mesh("does/not/exist.obj"), Catch::Contains("does/not/exist.obj"));
  Triangles bad(1, 3);
  bad << 0, 1, 99;
  CHECK_THROWS_AS(write_mesh("never_written.off", test::capsule_mesh(0.3f, 0.f, 4, 0, 2).V, bad), InputError);
}
