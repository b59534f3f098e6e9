// SPDX-License-Identifier: MIT
// Property tests of the fold metric (folds.h): rigid motions fold nothing, an lbs bend folds the
// inside of its bend more as the angle grows, the count does not depend on how the rig is turned,
// and a crafted crumple's turned-over triangles are counted while tilted ones are not.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>

#include "isokit/core/error.h"
#include "isokit/skinning/animation.h"
#include "isokit/skinning/deform.h"
#include "isokit/skinning/folds.h"
#include "isokit/skinning/pipeline.h"
#include "isokit/skinning/procedural.h"
#include "mesh_fixture.h"

using namespace isokit;
using namespace isokit::skinning;

using testing::from_lists;
using testing::Mesh;

namespace {

Affine random_rigid(std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  Affine a = Affine::Identity();
  a.linear() = q.toRotationMatrix();
  a.translation() = Eigen::Vector3d(n(rng), n(rng), n(rng));
  return a;
}

track::Positions transformed(const Affine& a, const track::Positions& p) {
  track::Positions out(p.rows(), 3);
  for (Eigen::Index v = 0; v < p.rows(); ++v)
    out.row(v) = (a * Eigen::Vector3d(p.row(v).cast<double>().transpose())).cast<float>().transpose();
  return out;
}

std::vector<Affine> conjugated(const Affine& g, const std::vector<Affine>& skin) {
  std::vector<Affine> out;
  for (const Affine& m : skin) out.push_back(g * m * g.inverse());
  return out;
}

int sum(const std::vector<std::uint8_t>& flags) {
  int n = 0;
  for (auto f : flags) n += f;
  return n;
}

/// The cylinder's Bone1 bent by `degrees` about its local x (toward +z): the skinning matrices.
std::vector<Affine> bent(const Rig& rig, double degrees) {
  const int j = parse_bend("Bone1:x:" + std::to_string(degrees), rig).joint;
  return skinning_matrices(rig, bend_animation(rig, {BendSpec{j, 0, degrees}}, 3)[1]);
}

/// A unit-weight rig of one joint for hand-made meshes.
SkinWeights one_joint(Eigen::Index vertices) {
  SkinWeights w;
  for (Eigen::Index v = 0; v <= vertices; ++v) w.offsets.push_back(static_cast<int>(v));
  w.joints.assign(static_cast<std::size_t>(vertices), 0);
  w.weights.assign(static_cast<std::size_t>(vertices), 1.f);
  return w;
}

/// An n × n grid of unit cells in the plane z = 0, normals +z.
Mesh grid(int n) {
  std::vector<Eigen::Vector3d> v;
  std::vector<std::array<int, 3>> f;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) v.emplace_back(x, y, 0);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const int a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      f.push_back({a, b, d});
      f.push_back({a, d, c});
    }
  return from_lists(v, f);
}

}  // namespace

TEST_CASE("folds: a rigid motion of the whole rig folds nothing", "[unit][metrics][folds]") {
  const Rig rig = make_cylinder(CylinderOptions{800});
  const FoldCounter folds(rig.rest, rig.triangles, rig.weights, skinning_matrices(rig, rest_pose(rig)));
  CHECK(sum(folds.rest_folded()) == 0);
  std::mt19937 rng(7);
  for (int k = 0; k < 10; ++k) {
    const Affine g = random_rigid(rng);
    // Every joint moved by the same rigid transform: the skin is the rest mesh moved by it.
    const std::vector<Affine> skin(rig.joints.size(), g);
    CHECK(sum(folds.folded(transformed(g, rig.rest), skin)) == 0);
    // lbs and dqs of that pose agree, and fold nothing either.
    track::Positions lbs;
    linear_blend(rig.weights, skin, rig.rest, lbs);
    CHECK(sum(folds.folded(lbs, skin)) == 0);
  }
}

/// The cylinder with every vertex whose largest weight exceeds 0.9 bound to that joint alone: the
/// parts away from the joint then move rigidly with their bones.
Rig cylinder_with_rigid_ends() {
  Rig rig = make_cylinder(CylinderOptions{800});
  SkinWeights w;
  w.offsets.push_back(0);
  for (Eigen::Index v = 0; v < rig.rest.rows(); ++v) {
    const int b = rig.weights.offsets[v], e = rig.weights.offsets[v + 1];
    const int top = int(std::max_element(rig.weights.weights.begin() + b, rig.weights.weights.begin() + e) -
                        rig.weights.weights.begin());
    for (int k = b; k < e; ++k)
      if (rig.weights.weights[top] <= 0.9f || k == top) {
        w.joints.push_back(rig.weights.joints[k]);
        w.weights.push_back(rig.weights.weights[top] > 0.9f ? 1.f : rig.weights.weights[k]);
      }
    w.offsets.push_back(int(w.joints.size()));
  }
  rig.weights = w;
  return rig;
}

TEST_CASE("folds: a part that moves rigidly with its bone folds nothing, however far the joint bends",
          "[unit][metrics][folds]") {
  const Rig rig = cylinder_with_rigid_ends();
  const FoldCounter folds(rig.rest, rig.triangles, rig.weights, skinning_matrices(rig, rest_pose(rig)));
  for (const double degrees : {60.0, 120.0, 150.0, 170.0}) {
    const std::vector<Affine> skin = bent(rig, degrees);
    track::Positions lbs;
    linear_blend(rig.weights, skin, rig.rest, lbs);
    const std::vector<std::uint8_t> flags = folds.folded(lbs, skin);
    int rigid = 0;
    for (Eigen::Index f = 0; f < rig.triangles.rows(); ++f) {
      // A triangle whose corners follow one joint alone moves rigidly with it.
      bool one_joint_only = true;
      int joint = -1;
      for (int c = 0; c < 3; ++c) {
        const int v = rig.triangles(f, c);
        for (int k = rig.weights.offsets[v]; k < rig.weights.offsets[v + 1]; ++k)
          if (rig.weights.weights[k] > 1e-6f) {
            if (joint >= 0 && joint != rig.weights.joints[k]) one_joint_only = false;
            if (rig.weights.weights[k] < 1 - 1e-6f) one_joint_only = false;
            joint = rig.weights.joints[k];
          }
      }
      if (!one_joint_only) continue;
      ++rigid;
      CHECK(flags[static_cast<std::size_t>(f)] == 0);
    }
    CHECK(rigid > rig.triangles.rows() / 4);
  }
}

TEST_CASE("folds: a cylinder bent by lbs folds the inside of its bend, more as the angle grows",
          "[unit][metrics][folds]") {
  const Rig rig = make_cylinder();
  const FoldCounter folds(rig.rest, rig.triangles, rig.weights, skinning_matrices(rig, rest_pose(rig)));
  int previous = 0;
  for (const double degrees : {45.0, 90.0, 120.0, 150.0, 170.0}) {
    const std::vector<Affine> skin = bent(rig, degrees);
    track::Positions lbs, dqs;
    linear_blend(rig.weights, skin, rig.rest, lbs);
    const std::vector<std::uint8_t> flags = folds.folded(lbs, skin);
    const int count = folds.count(flags).folded_new;
    INFO(degrees << "°: " << count << " folded");
    CHECK(count >= previous);
    if (degrees <= 45) CHECK(count == 0);
    if (degrees >= 150) CHECK(count > 0);
    if (degrees == 170) CHECK(count > previous);
    previous = count;
    // Every folded triangle lies on the inside of the bend (the +z side), by the joint (y = 1).
    for (Eigen::Index f = 0; f < rig.triangles.rows(); ++f) {
      if (!flags[static_cast<std::size_t>(f)]) continue;
      Eigen::Vector3f c = Eigen::Vector3f::Zero();
      for (int k = 0; k < 3; ++k) c += rig.rest.row(rig.triangles(f, k)).transpose() / 3.f;
      CHECK(c.z() > 0);
      CHECK(std::abs(c.y() - 1.f) < 0.5f);
    }
    // dqs keeps the bend's volume: it folds fewer triangles than lbs.
    dual_quaternion_blend(rig.weights, skin, rig.rest, dqs, nullptr);
    CHECK(folds.count(folds.folded(dqs, skin)).folded_new <= count);
  }
}

TEST_CASE("folds: the count does not depend on how the rig is turned", "[unit][metrics][folds]") {
  const Rig rig = make_cylinder(CylinderOptions{1200});
  const std::vector<Affine> rest_skin = skinning_matrices(rig, rest_pose(rig));
  const FoldCounter folds(rig.rest, rig.triangles, rig.weights, rest_skin);
  const std::vector<Affine> skin = bent(rig, 160);
  track::Positions lbs;
  linear_blend(rig.weights, skin, rig.rest, lbs);
  const std::vector<std::uint8_t> flags = folds.folded(lbs, skin);
  REQUIRE(sum(flags) > 0);
  std::mt19937 rng(11);
  for (int k = 0; k < 8; ++k) {
    // The same rig turned (and moved) by g: rest mesh, bind and pose all moved by it.
    const Affine g = random_rigid(rng);
    const FoldCounter turned(transformed(g, rig.rest), rig.triangles, rig.weights, conjugated(g, rest_skin));
    CHECK(turned.folded(transformed(g, lbs), conjugated(g, skin)) == flags);
  }
}

TEST_CASE("folds: a crumple's turned-over triangles are counted, tilted ones are not",
          "[unit][metrics][folds]") {
  const Mesh m = grid(6);
  const SkinWeights w = one_joint(m.v.rows());
  const std::vector<Affine> identity{Affine::Identity()};
  const FoldCounter folds(m.v, m.f, w, identity);
  const int centre = 3 * 7 + 3;
  SECTION("a vertex pushed across its neighbours turns some triangles over") {
    track::Positions p = m.v;
    p(centre, 0) += 1.6f;  // past the next column of vertices, in the plane
    p(centre, 1) += 0.3f;
    const std::vector<std::uint8_t> flags = folds.folded(p, identity);
    int turned = 0;
    for (Eigen::Index f = 0; f < m.f.rows(); ++f) {
      const Eigen::Vector3f a = p.row(m.f(f, 0)), b = p.row(m.f(f, 1)), c = p.row(m.f(f, 2));
      const bool over = (b - a).cross(c - a).z() < 0;
      turned += over ? 1 : 0;
      CHECK(flags[static_cast<std::size_t>(f)] == (over ? 1 : 0));
    }
    CHECK(turned > 0);
    CHECK(folds.count(flags).folded_new == turned);
  }
  SECTION("a vertex lifted far out of the plane tilts its triangles without turning them over") {
    track::Positions p = m.v;
    p(centre, 2) += 50.f;  // its six triangles tilt by almost 90°
    CHECK(sum(folds.folded(p, identity)) == 0);
    p(centre, 2) -= 100.f;
    CHECK(sum(folds.folded(p, identity)) == 0);
  }
  SECTION("a triangle turned about an edge counts from 90°") {
    // The grid's first triangle (0, 1, 8): turn its corner 8 about the edge 0-1 (the x axis).
    for (const double degrees : {30.0, 80.0, 89.0, 91.0, 100.0, 150.0, 180.0}) {
      track::Positions p = m.v;
      const Eigen::Vector3d r = Eigen::AngleAxisd(degrees * kPi / 180, Eigen::Vector3d::UnitX()) *
                                Eigen::Vector3d(p.row(8).cast<double>().transpose());
      p.row(8) = r.cast<float>().transpose();
      INFO(degrees << "°");
      CHECK(folds.folded(p, identity)[0] == (degrees > 90 ? 1 : 0));
    }
  }
  SECTION("the skeleton's rotation is the reference: the grid turned over with its bone is not folded") {
    Affine flip = Affine::Identity();
    flip.linear() = Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitX()).toRotationMatrix();
    CHECK(sum(folds.folded(transformed(flip, m.v), {flip})) == 0);
    CHECK(sum(folds.folded(transformed(flip, m.v), identity)) == m.f.rows());
  }
  SECTION("bad input is a one-line error") {
    CHECK_THROWS_AS(folds.folded(m.v, {}), isokit::InputError);
    CHECK_THROWS_AS(folds.folded(m.v.topRows(5), identity), isokit::InputError);
    CHECK_THROWS_AS(FoldCounter(m.v, m.f, SkinWeights{}, identity), isokit::InputError);
  }
}

TEST_CASE("folds: every method's metrics carry them, and dqs at rest folds nothing",
          "[unit][metrics][folds]") {
  const Rig rig = make_cylinder(CylinderOptions{600});
  Skinner sk(rig);
  const std::vector<Pose> poses = bend_animation(rig, {parse_bend("Bone1:x:150", rig)}, 5);
  BakeOptions o;
  o.self_intersections = false;
  for (const Method m : {Method::kLbs, Method::kDqs}) {
    const BakeResult r = sk.bake(m, poses, o);
    CHECK(r.stats.front().metrics.folded_new == 0);
    CHECK(r.stats.back().metrics.folded_new == 0);
    CHECK(r.worst.folded_new >= 0);
    CHECK(r.worst.folded_triangles >= r.worst.folded_new);
    // The cylinder has no rigid piece: the skin's overlap is the whole mesh's.
    CHECK(r.worst.skin_overlap_new == r.worst.self_overlap_new);
  }
  // lbs folds the inside of the 150° bend at the peak; dqs fewer.
  const BakeResult lbs = sk.bake(Method::kLbs, poses, o), dqs = sk.bake(Method::kDqs, poses, o);
  CHECK(lbs.stats[2].metrics.folded_new > 0);
  CHECK(dqs.stats[2].metrics.folded_new <= lbs.stats[2].metrics.folded_new);
}
