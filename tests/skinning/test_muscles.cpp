// SPDX-License-Identifier: MIT
// Muscles (2014 Fig. 10): an ellipsoid on a bone, scaled by a joint's bend. A biceps on the
// procedural cylinder's upper bone swells as the elbow bends and flattens back at rest, with
// both implicit methods; the setup keys and their errors.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "isokit/core/error.h"
#include "isokit/skinning/animation.h"
#include "isokit/skinning/metrics.h"
#include "isokit/skinning/pipeline.h"
#include "isokit/skinning/procedural.h"

using namespace isokit::skinning;

namespace {

// The cylinder's upper arm (Bone0, y in [0, 1], radius 0.3) carries a biceps on the inside of the
// bend (+z: bending Bone1 about +x swings it toward +z), inside the skin at rest, swelling across
// the bone to 1.8 times at 90°. The tracker's tolerance is 1e-6 of the diagonal: with the default
// 1e-5 the cylinder returns from 90° to 1.7e-4 of the diagonal with or without a muscle
// (2.1e-4 with), over the 1e-4 asked of the return here.
const char* kBiceps = R"({"version": 1, "tracker": {"tolerance": 1e-6}, "muscles": [
  {"name": "biceps", "bone": "Bone0", "driver": "Bone1", "center": [0, 0.6, 0.12],
   "radii": [0.3, 0.14, 0.14], "scale_axes": "yz", "curve": [[0, 1], [90, 1.8]]}]})";

double volume(const isokit::track::Positions& p, const Rig& rig) {
  return enclosed_volume(p, rig.triangles);
}

}  // namespace

TEST_CASE("muscles: the biceps swells as the elbow bends and flattens back at rest",
          "[skinning][muscle][unit]") {
  const Rig rig = make_cylinder();
  const SkinSetup setup = setup_from_json(kBiceps, "biceps.json");
  const std::vector<Pose> poses = bend_animation(rig, {parse_bend("Bone1:x:90", rig)}, 21);  // peak: frame 10
  BakeOptions quick;
  quick.self_intersections = false;
  const double diag = (rig.rest.colwise().maxCoeff() - rig.rest.colwise().minCoeff()).cast<double>().norm();
  SkinSetup plain;
  plain.tracker.tolerance = setup.tracker.tolerance;
  Skinner with(rig, setup), without(rig, plain);
  CHECK(with.field(TreeKind::k2014).joint_operators().back() ==
        "muscle biceps on Bone0: blend, driven by Bone1");
  for (const Method m : {Method::kTracking2014, Method::kImplicit2013}) {
    INFO(to_string(m));
    const BakeResult a = with.bake(m, poses, quick);
    const BakeResult b = without.bake(m, poses, quick);
    // At rest the muscle lies inside the skin: nothing moves.
    CHECK((a.frames[0] - rig.rest).cwiseAbs().maxCoeff() <= 1e-6 * diag);
    // The volume grows with the bend, beyond the bend's own change.
    const double r5 = volume(a.frames[5], rig) / volume(b.frames[5], rig);
    const double r10 = volume(a.frames[10], rig) / volume(b.frames[10], rig);
    INFO("volume with / without the biceps: " << r5 << " at 45 degrees, " << r10 << " at 90");
    CHECK(r5 > 1.002);
    CHECK(r10 > r5 + 0.002);
    // The bulge is the biceps': the skin moved most over it (inside of the bend, upper arm).
    Eigen::Index at = 0;
    (a.frames[10] - b.frames[10]).rowwise().norm().maxCoeff(&at);
    CHECK(rig.rest(at, 2) > 0.1f);
    CHECK(rig.rest(at, 1) > 0.25f);
    CHECK(rig.rest(at, 1) < 0.95f);
    // Back at rest: the volume and the mesh return.
    const double v0 = volume(rig.rest, rig);
    CHECK(std::abs(volume(a.frames.back(), rig) / v0 - 1.0) <= 1e-4);
    INFO("rest recovery " << a.rest_recovery << ", without the biceps " << b.rest_recovery);
    CHECK(a.rest_recovery <= 1e-4);
  }
}

TEST_CASE("muscles: setup keys, the curve and the errors", "[skinning][muscle][unit]") {
  const SkinSetup s = setup_from_json(kBiceps, "biceps.json");
  REQUIRE(s.muscles.size() == 1);
  const MuscleSetup& m = s.muscles[0];
  CHECK(m.name == "biceps");
  CHECK(m.bone == "Bone0");
  CHECK(m.driver == "Bone1");
  CHECK(m.radii.x() == 0.3);
  CHECK(m.scaled == std::array<bool, 3>{false, true, true});
  CHECK(m.op == JointOperator::kBlend);
  CHECK(m.scale_at(0.0) == 1.0);
  CHECK(m.scale_at(isokit::kPi / 4) == Approx(1.4));
  CHECK(m.scale_at(isokit::kPi) == Approx(1.8));  // constant past the last knot
  auto error = [](const std::string& muscle) {
    try {
      setup_from_json(R"({"muscles": [)" + muscle + "]}", "s.json");
    } catch (const isokit::InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string base =
      R"("bone": "Bone0", "driver": "Bone1", "center": [0, 0.5, 0], "radii": [0.2, 0.1, 0.1])";
  CHECK_THAT(error(R"({"driver": "Bone1", "center": [0, 0, 0], "radii": [1, 1, 1]})"),
             Catch::Contains("s.json.muscles[0].bone") && Catch::Contains("missing"));
  CHECK_THAT(error("{" + base + R"(, "scale_axes": "yw"})"),
             Catch::Contains("scale_axes") && Catch::Contains("'w'"));
  CHECK_THAT(error("{" + base + R"(, "curve": [[90, 1], [45, 2]]})"), Catch::Contains("ascend"));
  CHECK_THAT(error("{" + base + R"(, "curve": [[0, 0]]})"), Catch::Contains("curve"));
  CHECK_THAT(error("{" + base + R"(, "operator": "contact"})"), Catch::Contains("operator"));
  CHECK_THAT(error(R"({"bone": "Bone0", "driver": "Bone1", "center": [0, 0.5], "radii": [1, 1, 1]})"),
             Catch::Contains("center") && Catch::Contains("3 numbers"));
  CHECK_THAT(error(R"({"bone": "Bone0", "driver": "Bone1", "center": [0, 0.5, 0], "radii": [1, 0, 1]})"),
             Catch::Contains("radii"));
  CHECK_THAT(error("{" + base + R"(, "size": 2})"), Catch::Contains("unknown key"));
  // Names are checked against the rig when the field is built.
  const Rig rig = make_cylinder();
  for (const auto& [muscle, what] : std::vector<std::pair<std::string, std::string>>{
           {R"("bone": "Arm")", ".bone"}, {R"("driver": "Bone0")", ".driver"}}) {
    SkinSetup bad = setup_from_json(kBiceps, "biceps.json");
    if (what == ".bone")
      bad.muscles[0].bone = "Arm";
    else
      bad.muscles[0].driver = "Bone0";  // the root: no bend
    Skinner sk(rig, bad);
    CHECK_THROWS_WITH(sk.field(TreeKind::k2014), Catch::Contains("muscles[0] ('biceps')" + what));
  }
}
