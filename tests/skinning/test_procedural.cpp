// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "isokit/core/error.h"
#include "isokit/core/math.h"
#include "isokit/skinning/procedural.h"
#include "isokit/skinning/weights.h"

using namespace isokit::skinning;

namespace {

void check_surface(const Rig& rig, double min_angle, bool self_intersections) {
  INFO(rig.name);
  const SurfaceReport r = inspect_surface(rig.rest, rig.triangles, self_intersections);
  CHECK(r.boundary_edges == 0);
  CHECK(r.nonmanifold_edges == 0);
  CHECK(r.nonmanifold_vertices == 0);
  CHECK(r.inconsistent_edges == 0);
  CHECK(r.components == 1);
  CHECK(r.euler == 2);
  CHECK(r.volume > 0);
  CHECK(r.min_angle_deg >= min_angle);
  CHECK_FALSE(r.self_intersects);
}

bool identical(const Rig& a, const Rig& b) {
  if (a.name != b.name || a.rest.rows() != b.rest.rows() || a.triangles.rows() != b.triangles.rows() ||
      a.joints.size() != b.joints.size())
    return false;
  if (a.rest != b.rest || a.triangles != b.triangles) return false;
  if (a.weights.offsets != b.weights.offsets || a.weights.joints != b.weights.joints ||
      a.weights.weights != b.weights.weights)
    return false;
  for (std::size_t j = 0; j < a.joints.size(); ++j)
    if (a.joints[j].name != b.joints[j].name || a.joints[j].parent != b.joints[j].parent ||
        a.joints[j].rest_local.matrix() != b.joints[j].rest_local.matrix() ||
        a.joints[j].inverse_bind.matrix() != b.joints[j].inverse_bind.matrix())
      return false;
  return true;
}

/// Generalised winding number of the closed mesh around p (≈ 1 inside, ≈ 0 outside).
double winding(const Rig& rig, const Eigen::Vector3d& p) {
  double sum = 0;
  for (Eigen::Index f = 0; f < rig.triangles.rows(); ++f) {
    const Eigen::Vector3d a = rig.rest.row(rig.triangles(f, 0)).cast<double>().transpose() - p;
    const Eigen::Vector3d b = rig.rest.row(rig.triangles(f, 1)).cast<double>().transpose() - p;
    const Eigen::Vector3d c = rig.rest.row(rig.triangles(f, 2)).cast<double>().transpose() - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    sum += 2 * std::atan2(a.dot(b.cross(c)), la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb);
  }
  return sum / (4 * isokit::kPi);
}

void check_rest_identity(const Rig& rig) {
  for (const Affine& m : skinning_matrices(rig, rest_pose(rig))) CHECK(m.matrix().isIdentity(1e-9));
}

/// World position of `joint` after rotating `bent` about its local axis `axis` by `degrees`.
Eigen::Vector3d bent_position(const Rig& rig, const std::string& bent, const Eigen::Vector3d& axis,
                              double degrees, const std::string& joint) {
  std::vector<Affine> local = rest_pose(rig);
  const int j = rig.joint_index(bent);
  REQUIRE(j >= 0);
  local[static_cast<std::size_t>(j)] =
      local[static_cast<std::size_t>(j)] * Affine(Eigen::AngleAxisd(degrees * isokit::kPi / 180, axis));
  return world_transforms(rig, local)[static_cast<std::size_t>(rig.joint_index(joint))].translation();
}

const std::vector<std::string> kBodyJoints = {
    "Hips",         "Spine",       "Spine1",        "Spine2",      "Neck",         "Head",
    "LeftShoulder", "LeftArm",     "LeftForeArm",   "LeftHand",    "LeftUpLeg",    "LeftLeg",
    "LeftFoot",     "LeftToeBase", "RightShoulder", "RightArm",    "RightForeArm", "RightHand",
    "RightUpLeg",   "RightLeg",    "RightFoot",     "RightToeBase"};

}  // namespace

TEST_CASE("procedural: cylinder and finger are closed, manifold, outward, well shaped",
          "[skinning][procedural]") {
  for (int n : {200, 1000, 4000}) {
    const Rig c = make_cylinder({n, 2.0, 0.3});
    CHECK(std::abs(c.rest.rows() - n) <= 0.05 * n);
    check_surface(c, 25.0, n <= 1000);
    const Rig f = make_finger({n});
    CHECK(std::abs(f.rest.rows() - n) <= 0.05 * n);
    check_surface(f, 25.0, n <= 1000);
    CHECK_NOTHROW(validate(c));
    CHECK_NOTHROW(validate(f));
    check_rest_identity(c);
    check_rest_identity(f);
  }
  const Rig c = make_cylinder();
  CHECK(c.name == "procedural:cylinder?vertices=2000&length=2&radius=0.3");
  CHECK(c.joint_index("Bone0") == 0);
  CHECK(c.joint_index("Bone1") == 1);
  const Rig f = make_finger();
  for (const char* name : {"Finger0", "Finger1", "Finger2", "Finger3"}) CHECK(f.joint_index(name) >= 0);
  CHECK(identical(make_finger({1234}), make_finger({1234})));
  CHECK(identical(make_cylinder({777, 1.5, 0.2}), make_cylinder({777, 1.5, 0.2})));
}

TEST_CASE("procedural: bending the cylinder and finger about +x swings toward +z", "[skinning][procedural]") {
  const Rig c = make_cylinder();
  // Bone1's bone end (y = length) follows Bone1: its skinning matrix moves the top cap forward.
  std::vector<Affine> local = rest_pose(c);
  local[1] = local[1] * Affine(Eigen::AngleAxisd(isokit::kPi / 2, Eigen::Vector3d::UnitX()));
  const Affine m = skinning_matrices(c, local)[1];
  const Eigen::Vector3d top = m * Eigen::Vector3d(0, 2.0, 0);
  CHECK(top.z() == Approx(1.0).margin(1e-9));
  CHECK(top.y() == Approx(1.0).margin(1e-9));
  const Rig f = make_finger();
  const Eigen::Vector3d rest = bent_position(f, "Finger2", Eigen::Vector3d::UnitX(), 0, "Finger3");
  const Eigen::Vector3d bent = bent_position(f, "Finger2", Eigen::Vector3d::UnitX(), 90, "Finger3");
  CHECK(bent.z() > rest.z() + 0.2);  // the palm side
}

/// The 3000-vertex humanoid, built once for all sections.
const Rig& humanoid_3k() {
  static const Rig rig = make_humanoid({3000, true});
  return rig;
}

TEST_CASE("procedural: humanoid surface, joints and frames", "[skinning][procedural]") {
  const Rig& h = humanoid_3k();
  CHECK(h.name == "procedural:humanoid?vertices=3000&fingers=1");
  CHECK(std::abs(h.rest.rows() - 3000) <= 0.15 * 3000);
  check_surface(h, 25.0, true);
  CHECK_NOTHROW(validate(h));
  check_rest_identity(h);
  REQUIRE(h.joints.size() == 46);
  for (const std::string& n : kBodyJoints) CHECK(h.joint_index(n) >= 0);
  for (const char* side : {"Left", "Right"})
    for (const char* finger : {"Thumb", "Index", "Middle", "Pinky"})
      for (int k = 1; k <= 3; ++k)
        CHECK(h.joint_index(std::string(side) + "Hand" + finger + std::to_string(k)) >= 0);

  // Size and orientation: ~1.8 tall, feet at y = 0, left at +x.
  const Eigen::Vector3f lo = h.rest.colwise().minCoeff(), hi = h.rest.colwise().maxCoeff();
  CHECK(hi.y() - lo.y() == Approx(1.8).margin(0.03));
  CHECK(lo.y() == Approx(0.0).margin(0.01));
  const auto pos = rest_joint_positions(h);
  CHECK(pos[static_cast<std::size_t>(h.joint_index("LeftHand"))].x() > 0.5);

  const Eigen::Vector3d x = Eigen::Vector3d::UnitX();
  SECTION("every joint lies inside the skin; fingers are apart from each other") {
    for (std::size_t j = 0; j < pos.size(); ++j) {
      INFO(h.joints[j].name);
      CHECK(winding(h, pos[j]) > 0.99);
    }
    auto at = [&](const char* name) { return pos[static_cast<std::size_t>(h.joint_index(name))]; };
    for (const char* side : {"Left", "Right"}) {
      const std::string s = std::string(side) + "Hand";
      for (const auto& [f, g] : {std::pair<const char*, const char*>{"Index", "Middle"}, {"Middle", "Pinky"}})
        for (const char* k : {"2", "3"}) {
          INFO(s << f << k << " / " << s << g << k);
          CHECK(winding(h, 0.5 * (at((s + f + k).c_str()) + at((s + g + k).c_str()))) < 0.01);
        }
      CHECK(winding(h, 0.5 * (at((s + "Thumb3").c_str()) + at((s + "Index2").c_str()))) < 0.01);
    }
  }
  SECTION("elbow +150° about local x: the hand comes forward and back toward the shoulder") {
    for (const char* side : {"Left", "Right"}) {
      const std::string s = side;
      const Eigen::Vector3d arm = pos[static_cast<std::size_t>(h.joint_index(s + "Arm"))];
      const Eigen::Vector3d rest = bent_position(h, s + "ForeArm", x, 0, s + "Hand");
      const Eigen::Vector3d bent = bent_position(h, s + "ForeArm", x, 150, s + "Hand");
      CHECK(bent.z() > rest.z() + 0.1);
      CHECK((bent - arm).norm() < 0.5 * (rest - arm).norm());
      CHECK(bent.y() == Approx(rest.y()).margin(1e-6));  // folds in the horizontal plane
    }
  }
  SECTION("knee +150° about local x: the foot goes back and up") {
    for (const char* side : {"Left", "Right"}) {
      const std::string s = side;
      const Eigen::Vector3d rest = bent_position(h, s + "Leg", x, 0, s + "Foot");
      const Eigen::Vector3d bent = bent_position(h, s + "Leg", x, 150, s + "Foot");
      CHECK(bent.z() < rest.z() - 0.1);
      CHECK(bent.y() > rest.y() + 0.3);
    }
  }
  SECTION("fingers curl toward the palm (down), the spine bends forward") {
    const Eigen::Vector3d rest = bent_position(h, "LeftHandIndex1", x, 0, "LeftHandIndex3");
    const Eigen::Vector3d bent = bent_position(h, "LeftHandIndex1", x, 60, "LeftHandIndex3");
    CHECK(bent.y() < rest.y() - 0.02);
    const Eigen::Vector3d head0 = bent_position(h, "Spine1", x, 0, "Head");
    const Eigen::Vector3d head1 = bent_position(h, "Spine1", x, 30, "Head");
    CHECK(head1.z() > head0.z() + 0.1);
  }
  SECTION("weights: each vertex's dominant joint has a bone near it") {
    const auto seg = joint_segments(h);
    const std::vector<int> dom = dominant_joint(h.weights, static_cast<int>(h.rest.rows()));
    int far = 0;
    for (Eigen::Index v = 0; v < h.rest.rows(); ++v) {
      const Eigen::Vector3d p = h.rest.row(v).cast<double>().transpose();
      double nearest = 1e9, own = 1e9;
      for (std::size_t j = 0; j < seg.size(); ++j)
        for (const Segment& s : seg[j]) {
          nearest = std::min(nearest, segment_distance(p, s));
          if (static_cast<int>(j) == dom[static_cast<std::size_t>(v)])
            own = std::min(own, segment_distance(p, s));
        }
      if (own > nearest + 0.08) ++far;
    }
    CHECK(far == 0);
  }
}

TEST_CASE("procedural: humanoid without fingers, determinism", "[skinning][procedural]") {
  const Rig a = make_humanoid({2000, false});
  REQUIRE(a.joints.size() == 22);
  for (const std::string& n : kBodyJoints) CHECK(a.joint_index(n) >= 0);
  CHECK(a.joint_index("LeftHandIndex1") == -1);
  check_surface(a, 25.0, false);
  CHECK(identical(a, make_humanoid({2000, false})));
}

TEST_CASE("procedural: humanoid vertex counts and quality across sizes", "[skinning][procedural][slow]") {
  for (int n : {6000, 13000, 40000}) {
    const Rig h = make_procedural("humanoid?vertices=" + std::to_string(n));
    INFO(n << " -> " << h.rest.rows());
    CHECK(std::abs(h.rest.rows() - n) <= 0.15 * n);
    check_surface(h, 25.0, n <= 13000);
    const SurfaceReport r = inspect_surface(h.rest, h.triangles);
    CHECK(r.fraction_below_20deg == 0.0);
  }
}

TEST_CASE("procedural: spec parsing", "[skinning][procedural]") {
  const Rig c = make_procedural("cylinder?vertices=500&radius=0.25");
  CHECK(c.name == "procedural:cylinder?vertices=500&length=2&radius=0.25");
  CHECK(make_procedural("finger").name == "procedural:finger?vertices=3000");
  using isokit::InputError;
  CHECK_THROWS_WITH(make_procedural("sphere"), Catch::Contains("cylinder, finger, humanoid"));
  CHECK_THROWS_WITH(make_procedural("cylinder?verts=10"), Catch::Contains("vertices,length,radius"));
  CHECK_THROWS_WITH(make_procedural("humanoid?fingers=2"), Catch::Contains("fingers"));
  CHECK_THROWS_WITH(make_procedural("humanoid?vertices=abc"), Catch::Contains("not a non-negative integer"));
  CHECK_THROWS_WITH(make_procedural("humanoid?vertices=10"), Catch::Contains("between 3000 and 400000"));
  CHECK_THROWS_WITH(make_procedural("humanoid?vertices=10&fingers=0"),
                    Catch::Contains("between 2000 and 400000"));
  CHECK_THROWS_AS(make_procedural("cylinder?radius=-1"), InputError);
  CHECK_THROWS_AS(make_procedural("cylinder?vertices"), InputError);
  CHECK_THROWS_AS(make_procedural("finger?vertices=12x"), InputError);
}
