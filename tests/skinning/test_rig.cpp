// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include "isokit/core/error.h"
#include "isokit/skinning/rig.h"

using namespace isokit::skinning;

namespace {
Rig two_joint_rig() {
  Rig r;
  r.name = "test-rig";
  r.rest.resize(3, 3);
  r.rest << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  r.triangles.resize(1, 3);
  r.triangles << 0, 1, 2;
  Joint a{"A", -1, Affine::Identity(), Affine::Identity()};
  Joint b{"B", 0, Affine(Eigen::Translation3d(0, 1, 0)), Affine(Eigen::Translation3d(0, -1, 0))};
  r.joints = {a, b};
  return r;
}
}  // namespace

TEST_CASE("rig: rest pose gives identity skinning matrices and joint positions", "[skinning]") {
  Rig r = two_joint_rig();
  validate(r);
  for (const Affine& m : skinning_matrices(r, rest_pose(r))) CHECK(m.matrix().isIdentity(1e-12));
  auto p = rest_joint_positions(r);
  CHECK(p[1].isApprox(Eigen::Vector3d(0, 1, 0)));
  CHECK(r.joint_index("B") == 1);
  CHECK(r.joint_index("C") == -1);
}

TEST_CASE("rig: weights are normalised, merged and pruned, dominant joint", "[skinning]") {
  SkinWeights w;
  w.offsets = {0, 3, 4};
  w.joints = {0, 1, 0, 1};
  w.weights = {1.f, 2.f, 1.f, 0.f + 5.f};
  normalize_weights(w, 2, 0.0f);
  REQUIRE(w.count(0) == 2);
  CHECK(w.weights[0] == Approx(0.5));
  CHECK(w.weights[1] == Approx(0.5));
  CHECK(dominant_joint(w, 2) == std::vector<int>{0, 1});
  SkinWeights bad;
  bad.offsets = {0, 1};
  bad.joints = {0};
  bad.weights = {0.f};
  CHECK_THROWS_AS(normalize_weights(bad, 1), isokit::InputError);
}

TEST_CASE("rig: validation names the broken item", "[skinning]") {
  Rig r = two_joint_rig();
  r.joints[0].parent = 1;
  CHECK_THROWS_WITH(validate(r), Catch::Contains("joint 0 'A'"));
  r = two_joint_rig();
  r.triangles(0, 2) = 7;
  CHECK_THROWS_WITH(validate(r), Catch::Contains("triangle 0"));
  r = two_joint_rig();
  r.weights.offsets = {0, 1, 2, 3};
  r.weights.joints = {0, 0, 1};
  r.weights.weights = {1.f, 0.5f, 1.f};
  CHECK_THROWS_WITH(validate(r), Catch::Contains("vertex 1"));
}
