// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include "isokit/core/error.h"
#include "isokit/skinning/procedural.h"
#include "isokit/skinning/rigid_pieces.h"

using namespace isokit::skinning;

namespace {

/// `rig` plus a closed tetrahedron at `at` whose four vertices have the influences `inf` (one
/// list of (joint, weight) per vertex).
void add_tetrahedron(Rig& rig, const Eigen::Vector3f& at, const std::vector<std::vector<std::pair<int, float>>>& inf) {
  const auto base = static_cast<int>(rig.rest.rows());
  rig.rest.conservativeResize(base + 4, 3);
  rig.rest.row(base) = at.transpose();
  rig.rest.row(base + 1) = (at + Eigen::Vector3f(0.1f, 0, 0)).transpose();
  rig.rest.row(base + 2) = (at + Eigen::Vector3f(0, 0.1f, 0)).transpose();
  rig.rest.row(base + 3) = (at + Eigen::Vector3f(0, 0, 0.1f)).transpose();
  const auto t = rig.triangles.rows();
  rig.triangles.conservativeResize(t + 4, 3);
  rig.triangles.row(t) << base, base + 2, base + 1;
  rig.triangles.row(t + 1) << base, base + 1, base + 3;
  rig.triangles.row(t + 2) << base, base + 3, base + 2;
  rig.triangles.row(t + 3) << base + 1, base + 2, base + 3;
  for (const auto& list : inf) {
    for (const auto& [j, w] : list) {
      rig.weights.joints.push_back(j);
      rig.weights.weights.push_back(w);
    }
    rig.weights.offsets.push_back(static_cast<int>(rig.weights.joints.size()));
  }
}

}  // namespace

TEST_CASE("rigid pieces: components that follow one transform, not a rigidly weighted skin",
          "[skinning][rigid][unit]") {
  Rig rig = make_cylinder();  // a connected skin blended over two joints
  const auto skin_vertices = rig.rest.rows();
  REQUIRE(find_rigid_pieces(rig).empty());
  // A prop on joint 1 alone, a prop with the same blend at every vertex, a piece whose vertices
  // follow different joints with one influence each (skin, 2014 Fig. 8), and a piece whose blend
  // differs by more than the tolerance.
  add_tetrahedron(rig, {2, 0, 0}, {{{1, 1.f}}, {{1, 1.f}}, {{1, 1.f}}, {{1, 1.f}}});
  add_tetrahedron(rig, {3, 0, 0},
                  {{{0, .2f}, {1, .8f}}, {{1, .8f}, {0, .2f}}, {{0, .2f}, {1, .8f}}, {{0, .2f}, {1, .8f}}});
  add_tetrahedron(rig, {4, 0, 0}, {{{0, 1.f}}, {{1, 1.f}}, {{1, 1.f}}, {{1, 1.f}}});
  add_tetrahedron(rig, {5, 0, 0}, {{{0, .2f}, {1, .8f}}, {{0, .3f}, {1, .7f}}, {{0, .2f}, {1, .8f}}, {{0, .2f}, {1, .8f}}});
  const std::vector<RigidPiece> pieces = find_rigid_pieces(rig);
  REQUIRE(pieces.size() == 2);
  CHECK(pieces[0].vertices == std::vector<int>{int(skin_vertices), int(skin_vertices) + 1, int(skin_vertices) + 2,
                                               int(skin_vertices) + 3});
  CHECK(pieces[0].joints == std::vector<int>{1});
  CHECK(pieces[0].triangles == 4);
  CHECK(pieces[1].joints == std::vector<int>{0, 1});  // sorted, whatever the order in the weights
  CHECK(pieces[1].weights[0] == Approx(0.2f));
  CHECK(pieces[1].vertices.front() == skin_vertices + 4);
  // The tolerance decides the near-identical blend.
  CHECK(find_rigid_pieces(rig, 0.2).size() == 3);
  CHECK_THROWS_AS(find_rigid_pieces(rig, -1), isokit::InputError);
  // Without weights there is nothing to tell.
  rig.weights = SkinWeights{};
  CHECK(find_rigid_pieces(rig).empty());
}
