// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "isokit/core/error.h"
#include "isokit/skinning/procedural.h"
#include "isokit/skinning/weights.h"

using namespace isokit::skinning;

namespace {

float weight_of(const SkinWeights& w, int v, int j) {
  for (int k = w.offsets[v]; k < w.offsets[v + 1]; ++k)
    if (w.joints[k] == j) return w.weights[k];
  return 0.f;
}

void check_normalised(const SkinWeights& w, int nv, int nj) {
  REQUIRE(static_cast<int>(w.offsets.size()) == nv + 1);
  for (int v = 0; v < nv; ++v) {
    REQUIRE(w.count(v) >= 1);
    double sum = 0;
    for (int k = w.offsets[v]; k < w.offsets[v + 1]; ++k) {
      REQUIRE(w.weights[k] >= 0.f);
      REQUIRE(w.joints[k] >= 0);
      REQUIRE(w.joints[k] < nj);
      sum += w.weights[k];
    }
    REQUIRE(sum == Approx(1.0).margin(1e-5));
  }
}

/// A chain of joints along +y at the given heights (parent = previous joint).
Rig chain(const std::vector<double>& heights) {
  Rig r;
  r.name = "chain";
  r.rest.resize(3, 3);
  r.rest << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  r.triangles.resize(1, 3);
  r.triangles << 0, 1, 2;
  double prev = 0;
  for (std::size_t j = 0; j < heights.size(); ++j) {
    Joint jt;
    jt.name = "J" + std::to_string(j);
    jt.parent = static_cast<int>(j) - 1;
    jt.rest_local = Affine(Eigen::Translation3d(0, heights[j] - prev, 0));
    jt.inverse_bind = Affine(Eigen::Translation3d(0, -heights[j], 0));
    prev = heights[j];
    r.joints.push_back(jt);
  }
  return r;
}

}  // namespace

TEST_CASE("weights: joint segments follow the documented rule", "[skinning][weights]") {
  SECTION("bones to children; a leaf continues its parent bone by leaf_fraction") {
    const auto s = joint_segments(chain({0.0, 1.0, 3.0}));
    REQUIRE(s.size() == 3);
    CHECK(s[0][0].b.isApprox(Eigen::Vector3d(0, 1, 0)));
    CHECK(s[1][0].b.isApprox(Eigen::Vector3d(0, 3, 0)));
    CHECK(s[2][0].a.isApprox(Eigen::Vector3d(0, 3, 0)));
    CHECK(s[2][0].b.isApprox(Eigen::Vector3d(0, 4, 0)));  // 0.5 × the parent bone (length 2)
    const auto s2 = joint_segments(chain({0.0, 1.0, 3.0}), 0.25);
    CHECK(s2[2][0].b.isApprox(Eigen::Vector3d(0, 3.5, 0)));
  }
  SECTION("a child on top of its parent adds no zero-length bone; the leaf looks further up") {
    const auto s = joint_segments(chain({0.0, 1.0, 1.0}));
    REQUIRE(s[1].size() == 1);  // J1 has only a coincident child: treated as a leaf
    CHECK((s[1][0].b - s[1][0].a).norm() == Approx(0.5));
    CHECK((s[2][0].b - s[2][0].a).norm() == Approx(0.5));  // J2's parent coincides: J0 → J2 used
    for (const auto& list : s)
      for (const Segment& seg : list) CHECK(seg.a.allFinite());
  }
  SECTION("a lone root gets a point bone") {
    const auto s = joint_segments(chain({0.5}));
    REQUIRE(s[0].size() == 1);
    CHECK(s[0][0].a == s[0][0].b);
    CHECK(segment_distance(Eigen::Vector3d(0, 0.5, 2), s[0][0]) == Approx(2));
  }
}

TEST_CASE("weights: heat weights on the cylinder are normalised, local and monotone", "[skinning][weights]") {
  Rig rig = make_cylinder({1500, 2.0, 0.3});
  rig.weights = {};
  const int nv = static_cast<int>(rig.rest.rows());
  SECTION("a rig without weights, with the generic joint segments") {
    const SkinWeights w = heat_weights(rig);
    check_normalised(w, nv, 2);
    const std::vector<int> dom = dominant_joint(w, nv);
    for (int v = 0; v < nv; ++v)
      if (std::abs(rig.rest(v, 1) - 1.0f) > 0.1f)
        CHECK(dom[static_cast<std::size_t>(v)] == (rig.rest(v, 1) > 1.0f));
  }
  // The cylinder's own bones: Bone0 from y = 0 to 1, Bone1 from 1 to 2.
  const Eigen::Vector3d y0(0, 0, 0), y1(0, 1, 0), y2(0, 2, 0);
  int calls = 0, last_done = -1, last_total = -1;
  HeatWeightOptions opt;
  opt.progress = [&](int done, int total) {
    ++calls;
    last_done = done;
    last_total = total;
  };
  const SkinWeights w = heat_weights(rig.rest, rig.triangles, {{{y0, y1}}, {{y1, y2}}}, opt);
  check_normalised(w, nv, 2);
  CHECK(calls >= 1);
  CHECK(last_done == last_total);
  rig.weights = w;
  CHECK_NOTHROW(validate(rig));

  // Far from the joint (y = 1) each vertex belongs to its own bone (heat weights decay over
  // about a radius: ~99 % at the ends of this 1.0-long, 0.3-thick bone, ~88 % half-way).
  for (int v = 0; v < nv; ++v) {
    const double y = rig.rest(v, 1);
    if (y < 0.1) CHECK(weight_of(w, v, 0) > 0.97f);
    if (y > 1.9) CHECK(weight_of(w, v, 1) > 0.97f);
    if (y < 0.5) CHECK(weight_of(w, v, 0) > 0.85f);
    if (y > 1.5) CHECK(weight_of(w, v, 1) > 0.85f);
  }
  // Bone1's weight grows with y: ring averages are monotone, each vertex close to its ring's.
  std::map<float, std::pair<double, int>> rings;
  for (int v = 0; v < nv; ++v) {
    auto& r = rings[rig.rest(v, 1)];
    r.first += weight_of(w, v, 1);
    r.second += 1;
  }
  double prev = -1;
  for (const auto& [y, r] : rings) {
    const double mean = r.first / r.second;
    CHECK(mean >= prev - 1e-4);
    prev = mean;
  }
  for (int v = 0; v < nv; ++v) {
    const auto& r = rings[rig.rest(v, 1)];
    CHECK(weight_of(w, v, 1) == Approx(r.first / r.second).margin(0.03));
  }
  // Smooth across the joint: neighbours differ little, and the joint ring is shared.
  double max_jump = 0;
  for (Eigen::Index f = 0; f < rig.triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      max_jump = std::max(max_jump, std::abs(static_cast<double>(weight_of(w, rig.triangles(f, k), 1)) -
                                             weight_of(w, rig.triangles(f, (k + 1) % 3), 1)));
  CHECK(max_jump < 0.2);
  double mid = 0;
  for (const auto& [y, r] : rings)
    if (std::abs(y - 1.0f) < 0.06f) mid = r.first / r.second;
  CHECK(mid == Approx(0.5).margin(0.15));
}

TEST_CASE("weights: the dominant joint's bone is near the vertex (finger)", "[skinning][weights]") {
  const Rig rig = make_finger({2000});
  const int nv = static_cast<int>(rig.rest.rows());
  check_normalised(rig.weights, nv, 4);
  const std::vector<int> dom = dominant_joint(rig.weights, nv);
  const double joint_y[4] = {0.0, 0.15, 0.55, 0.80};
  for (int v = 0; v < nv; ++v) {
    const double y = rig.rest(v, 1);
    int own = 0;
    for (int j = 1; j < 4; ++j)
      if (y >= joint_y[j]) own = j;
    const int d = dom[static_cast<std::size_t>(v)];
    if (d == own) continue;
    // Otherwise only just across a joint (within about a finger radius).
    const int boundary = std::max(d, own);
    CHECK(std::abs(d - own) == 1);
    CHECK(std::abs(y - joint_y[boundary]) < 0.1);
  }
}

TEST_CASE("weights: excluded joints, isolated vertices, min_weight", "[skinning][weights]") {
  Rig rig = make_cylinder({600, 2.0, 0.3});
  const auto seg = joint_segments(rig);
  SECTION("an excluded joint gets no weight") {
    HeatWeightOptions opt;
    opt.excluded_joints = {0};
    const SkinWeights w = heat_weights(rig.rest, rig.triangles, seg, opt);
    for (int v = 0; v < static_cast<int>(rig.rest.rows()); ++v) CHECK(weight_of(w, v, 1) == 1.0f);
  }
  SECTION("a vertex used by no triangle takes its nearest bone") {
    isokit::track::Positions p(rig.rest.rows() + 1, 3);
    p.topRows(rig.rest.rows()) = rig.rest;
    p.row(rig.rest.rows()) << 0.f, 1.8f, 0.f;
    const SkinWeights w = heat_weights(p, rig.triangles, seg);
    check_normalised(w, static_cast<int>(p.rows()), 2);
    CHECK(weight_of(w, static_cast<int>(rig.rest.rows()), 1) == 1.0f);
  }
  SECTION("min_weight prunes small weights") {
    HeatWeightOptions opt;
    opt.min_weight = 0.2f;
    const SkinWeights w = heat_weights(rig.rest, rig.triangles, seg, opt);
    for (float x : w.weights) CHECK(x >= 0.2f - 1e-6f);
    opt.min_weight = 0.0f;
    const SkinWeights all = heat_weights(rig.rest, rig.triangles, seg, opt);
    CHECK(all.joints.size() > w.joints.size());
  }
}

TEST_CASE("weights: bad input gives clear errors", "[skinning][weights]") {
  const Rig rig = make_cylinder({300, 2.0, 0.3});
  const auto seg = joint_segments(rig);
  using isokit::InputError;
  CHECK_THROWS_WITH(heat_weights(rig.rest, isokit::track::Triangles(0, 3), seg),
                    Catch::Contains("no triangles"));
  isokit::track::Positions nan = rig.rest;
  nan(7, 1) = std::numeric_limits<float>::quiet_NaN();
  CHECK_THROWS_WITH(heat_weights(nan, rig.triangles, seg), Catch::Contains("vertex 7"));
  isokit::track::Triangles bad = rig.triangles;
  bad(3, 2) = static_cast<int>(rig.rest.rows());
  CHECK_THROWS_WITH(heat_weights(rig.rest, bad, seg), Catch::Contains("triangle 3"));
  HeatWeightOptions all;
  all.excluded_joints = {0, 1};
  CHECK_THROWS_WITH(heat_weights(rig.rest, rig.triangles, seg, all), Catch::Contains("no joint has a bone"));
  HeatWeightOptions wrong;
  wrong.excluded_joints = {5};
  CHECK_THROWS_AS(heat_weights(rig.rest, rig.triangles, seg, wrong), InputError);
  CHECK_THROWS_AS(heat_weights(rig.rest, rig.triangles, {}), InputError);
  auto nan_seg = seg;
  nan_seg[1][0].b.x() = std::nan("");
  CHECK_THROWS_WITH(heat_weights(rig.rest, rig.triangles, nan_seg), Catch::Contains("joint 1"));
}
