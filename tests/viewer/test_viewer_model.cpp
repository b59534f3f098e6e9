// SPDX-License-Identifier: MIT
// The skinning viewer's model (apps/skinning/viewer): edited poses bake as a bake of the same
// sequence, a drag is one undo step, clips equal bake's frames and bake each frame once, pose
// scripts round-trip, overlays flag what the metrics count.
#include <algorithm>
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <random>

#include "isokit/core/error.h"
#include "isokit/skinning/animation.h"
#include "isokit/skinning/deform.h"
#include "isokit/skinning/metrics.h"
#include "isokit/skinning/procedural.h"
#include "isokit/skinning/rig_io.h"
#include "isokit/viewer/model.h"

using namespace isokit;
using namespace isokit::skinning;
using isokit::viewer::ViewerModel;
using isokit::viewer::ViewerOptions;

namespace {

std::shared_ptr<Skinner> cylinder(bool with_clip = true) {
  Rig rig = make_cylinder();
  if (with_clip) {
    Clip c;
    c.name = "bend";
    c.fps = 30;
    c.local = bend_animation(rig, {parse_bend("Bone1:x:120", rig)}, 11);
    rig.clips.push_back(std::move(c));
  }
  return std::make_shared<Skinner>(std::move(rig));
}

ViewerOptions quick() {
  ViewerOptions o;
  o.self_intersections = false;
  return o;
}

BakeOptions quick_bake() {
  BakeOptions o;
  o.self_intersections = false;
  return o;
}

}  // namespace

TEST_CASE("viewer: edits bake as bake does over the edited poses, a drag is one undo step",
          "[viewer][unit]") {
  auto sk = cylinder();
  ViewerModel m(sk, Method::kTracking2014, quick());
  const Pose rest = rest_pose(sk->rig());
  CHECK(m.positions() == sk->bake(Method::kTracking2014, {rest}, quick_bake()).frames[0]);
  CHECK_FALSE(m.can_undo());
  m.select_joint(1);
  m.set_joint_angles(1, {60, 0, 0});
  const Pose p60 = m.edited_pose();
  CHECK(m.positions() == sk->bake(Method::kTracking2014, {rest, p60}, quick_bake()).frames[1]);
  CHECK(m.stats().tracker_calls >= 1);
  // A drag of three values is one undo step.
  m.begin_drag();
  for (double a : {70.0, 80.0, 90.0}) m.set_joint_angles(1, {a, 0, 0});
  m.end_drag();
  CHECK(m.joint_angles(1)[0] == 90.0);
  m.undo();
  CHECK(m.joint_angles(1)[0] == 60.0);
  m.undo();
  CHECK(m.joint_angles(1)[0] == 0.0);
  CHECK_FALSE(m.can_undo());
  m.redo();
  m.redo();
  CHECK(m.joint_angles(1)[0] == 90.0);
  CHECK_FALSE(m.can_redo());
  m.reset_pose();
  for (std::size_t j = 0; j < rest.size(); ++j) CHECK(m.edited_pose()[j].matrix() == rest[j].matrix());
  m.undo();
  CHECK(m.joint_angles(1)[0] == 90.0);
  // DQS shows DQS of the edited pose.
  m.set_method(Method::kDqs);
  track::Positions dqs;
  dual_quaternion_blend(sk->rig().weights, skinning_matrices(sk->rig(), m.edited_pose()), sk->rig().rest, dqs,
                        nullptr);
  CHECK(m.positions() == dqs);
  // Bad input.
  CHECK_THROWS_AS(m.select_joint(2), InputError);
  CHECK_THROWS_AS(m.set_joint_angles(5, {0, 0, 0}), InputError);
  CHECK_THROWS_AS(m.set_joint_angles(1, {std::nan(""), 0, 0}), InputError);
}

TEST_CASE("viewer: a clip's frames are bake's, each baked once, the second method beside it",
          "[viewer][unit]") {
  auto sk = cylinder();
  ViewerModel m(sk, Method::kTracking2014, quick());
  CHECK(m.clips() == std::vector<std::string>{"bend"});
  const std::vector<Pose> poses = sk->rig().clips[0].local;
  const BakeResult trk = sk->bake(Method::kTracking2014, poses, quick_bake());
  const BakeResult lbs = sk->bake(Method::kLbs, poses, quick_bake());
  const long before = m.frames_baked();
  m.play_clip("bend");
  CHECK(m.frame_count() == 11);
  m.set_frame(6);
  CHECK(m.positions() == trk.frames[6]);
  CHECK(m.frames_baked() - before == 7);
  m.set_frame(2);  // cached
  CHECK(m.positions() == trk.frames[2]);
  CHECK(m.frames_baked() - before == 7);
  m.set_frame(99);  // clamped to the last frame
  CHECK(m.frame() == 10);
  CHECK(m.positions() == trk.frames[10]);
  CHECK(m.frames_baked() - before == 11);
  m.set_compare(Method::kLbs);
  REQUIRE(m.compare_positions() != nullptr);
  CHECK(*m.compare_positions() == lbs.frames[10]);
  // The joints follow the clip.
  const std::vector<Affine> world = world_transforms(sk->rig(), poses[10]);
  CHECK((m.joint_positions()[1] - world[1].translation()).norm() < 1e-12);
  // An edit ends the playback.
  m.set_joint_angles(1, {30, 0, 0});
  CHECK(m.clip().empty());
  CHECK_THROWS_WITH(m.play_clip("walk"), Catch::Contains("bend"));
}

TEST_CASE("viewer: the edited pose saved as a pose script loads back as that pose", "[viewer][unit]") {
  auto sk = cylinder(false);
  ViewerModel m(sk, Method::kDqs, quick());
  m.set_joint_angles(0, {5, -10, 15});
  m.set_joint_angles(1, {40, 20, -30});
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("isokit_viewer_" + std::to_string(std::random_device{}()) + ".json"))
                               .string();
  m.save_pose_script(path);
  const std::vector<Pose> back = pose_script_animation(sk->rig(), path);
  std::filesystem::remove(path);
  REQUIRE(back.size() == 1);
  for (std::size_t j = 0; j < back[0].size(); ++j)
    CHECK((back[0][j].matrix() - m.edited_pose()[j].matrix()).cwiseAbs().maxCoeff() < 1e-12);
  CHECK_THROWS_AS(m.save_pose_script("/nonexistent/dir/pose.json"), InputError);
}

TEST_CASE(
    "viewer: overlays flag the frame's intersecting, inverted and folded triangles, contacts and the mask",
    "[viewer][unit]") {
  Rig rig = make_cylinder();
  rig.relax_mask.assign(static_cast<std::size_t>(rig.rest.rows()), 1.0f);
  rig.relax_mask[0] = 0.0f;
  auto sk = std::make_shared<Skinner>(std::move(rig));
  ViewerModel m(sk, Method::kDqs);
  m.set_joint_angles(1, {150, 0, 0});
  const viewer::Overlays& dqs = m.overlays();
  SelfIntersectionDetails details;
  const int pairs = count_self_intersections(m.positions(), sk->rig().triangles, &details);
  REQUIRE(pairs > 0);  // DQS's elbow at 150° folds into itself
  int flagged = 0;
  for (std::uint8_t f : dqs.intersecting) flagged += f;
  CHECK(flagged > 0);
  for (const auto& p : details.pairs)
    CHECK((dqs.intersecting[std::size_t(p[0])] && dqs.intersecting[std::size_t(p[1])]));
  for (float d : dqs.dqs_distance) CHECK(d == 0.f);
  CHECK(std::count(dqs.mask.begin(), dqs.mask.end(), 1.0f) ==
        static_cast<long>(dqs.mask.size()));  // DQS: none
  int inverted = 0;
  for (std::uint8_t f : dqs.inverted) inverted += f;
  CHECK(inverted > 0);  // the fold's triangles face into the field
  // DQS's fold passes into itself: the triangles bounding the new overlap are flagged.
  const std::vector<int> overlap = new_overlap_triangles(sk->rig().rest, m.positions(), sk->rig().triangles);
  REQUIRE(!overlap.empty());
  for (std::size_t t = 0; t < dqs.overlap.size(); ++t)
    CHECK(dqs.overlap[t] == (std::binary_search(overlap.begin(), overlap.end(), int(t)) ? 1 : 0));
  // DQS folds the inside of the 150° bend: the folds overlay flags what the metrics count.
  const long folded = std::count(dqs.folded.begin(), dqs.folded.end(), 1);
  CHECK(folded > 0);
  CHECK(folded == sk->measure(m.edited_pose(), m.positions(), false).folded_new);
  m.set_method(Method::kTracking2014);
  const viewer::Overlays& trk = m.overlays();
  CHECK(trk.mask[0] == 0.0f);
  CHECK(trk.mask[1] == 1.0f);
  double moved = 0;
  for (float d : trk.dqs_distance) moved = std::max(moved, double(d));
  CHECK(moved > 1e-3);
  int contacts = 0;
  for (std::uint8_t c : trk.contact) contacts += c;
  CHECK(contacts > 0);
  // The tracked skin forms a contact instead: little or no triangle bounds a new overlap.
  CHECK(std::count(trk.overlap.begin(), trk.overlap.end(), 1) < static_cast<long>(overlap.size()) / 4);
}

TEST_CASE("viewer: a ray picks the joint it passes nearest to", "[viewer][unit]") {
  auto sk = cylinder(false);
  ViewerModel m(sk, Method::kDqs, quick());
  const std::vector<Eigen::Vector3d> at = m.joint_positions();
  const Eigen::Vector3d from = at[1] + Eigen::Vector3d(0, 0, 5);
  CHECK(m.pick_joint(from, at[1] - from, 0.05) == 1);
  CHECK(m.pick_joint(from, at[0] - from, 0.05) == 0);
  CHECK(m.pick_joint(from, Eigen::Vector3d(1, 0, 0), 0.05) == -1);
}

TEST_CASE("viewer: baking in the background shows the last finished frame, then the synchronous result",
          "[viewer][unit]") {
  auto sk = cylinder();
  ViewerOptions bg = quick();
  bg.background = true;
  bg.edit_slice_ms = 0;  // edits baked whole: the frames equal the synchronous ones bit for bit
  ViewerModel a(sk, Method::kTracking2014, bg);
  ViewerModel b(cylinder(), Method::kTracking2014, quick());  // its own skinner: a's worker uses sk
  CHECK(a.positions() == b.positions());                      // the first frame is waited for
  CHECK_FALSE(a.pending());
  for (const double angle : {40.0, 80.0}) {
    a.set_joint_angles(1, {angle, 0, 0});
    b.set_joint_angles(1, {angle, 0, 0});
    CHECK(a.pending());  // nothing is published before poll()
    a.wait_idle();
    CHECK_FALSE(a.pending());
    CHECK(a.shown_id() == a.request_id());
    CHECK(a.positions() == b.positions());  // one request at a time: the same frames
  }
  // A burst of edits: each replaces the one not yet started; the last is shown in the end.
  a.begin_drag();
  for (int k = 1; k <= 20; ++k) a.set_joint_angles(1, {80.0 - 2.0 * k, 0, 0});
  a.end_drag();
  a.wait_idle();
  CHECK(a.shown_id() == a.request_id());
  CHECK(a.joint_angles(1)[0] == 40.0);
  // A clip frame and the compared method, from the worker.
  a.set_compare(Method::kDqs);
  a.play_clip("bend");
  a.set_frame(5);
  a.wait_idle();
  const std::vector<Pose>& poses = sk->rig().clips[0].local;
  CHECK(a.positions() == sk->bake(Method::kTracking2014, poses, quick_bake()).frames[5]);
  REQUIRE(a.compare_positions() != nullptr);
  CHECK(*a.compare_positions() == sk->bake(Method::kDqs, poses, quick_bake()).frames[5]);
  const viewer::Overlays& o = a.overlays();
  CHECK(o.dqs_distance.size() == static_cast<std::size_t>(sk->rig().rest.rows()));
}

TEST_CASE("viewer: an edit cut short is shown at once and settles as the whole bake", "[viewer][unit]") {
  auto sk = cylinder(false);
  ViewerOptions sliced = quick();
  sliced.background = true;
  sliced.edit_slice_ms = 1e-6;  // the first call is cut short before its first iteration
  ViewerModel a(sk, Method::kTracking2014, sliced);
  ViewerModel b(cylinder(false), Method::kTracking2014, quick());
  const double diagonal = (sk->rig().rest.colwise().maxCoeff() - sk->rig().rest.colwise().minCoeff()).norm();
  const int budget = sk->setup().tracker.max_iterations;
  const float iso_tolerance = sk->setup().tracker.iso_tolerance;
  auto settled_as_whole = [&](const char* what) {
    const FrameStats& sa = a.stats();
    const FrameStats& sb = b.stats();
    const FrameMetrics& ma = sa.metrics;
    const FrameMetrics& mb = sb.metrics;
    INFO(what << ": whole " << sb.iterations << " iterations, sliced " << sa.iterations << " in "
              << sa.tracker_calls << " calls; edge mean " << ma.edge_distortion_mean << " / "
              << mb.edge_distortion_mean << ", iso max " << ma.iso_residual_max << " / "
              << mb.iso_residual_max);
    REQUIRE(a.metrics_shown());                  // measured once the pose rested
    CHECK(sa.tracker_calls == sa.substeps + 1);  // cut short, then the rest at the same pose
    for (int k = 0; k < sa.substeps; ++k) CHECK(sa.call_iterations[std::size_t(k)] == 0);
    CHECK(sa.iterations <= budget * sa.substeps);  // no more work than the whole bake may do
    CHECK(ma.edge_distortion_mean <= 1.1 * mb.edge_distortion_mean + 1e-3);
    CHECK(ma.edge_distortion_max <= 1.25 * mb.edge_distortion_max + 1e-2);
    // Within twice the whole bake's, or within the tracker's own iso tolerance: where both end at
    // the iteration cap (the drag below), where each stops depends on where the slicing left it,
    // and under load the slices fall elsewhere (seen: 1.26e-4 against 1.10e-4 allowed).
    CHECK(ma.iso_residual_max <= std::max(2 * mb.iso_residual_max + 1e-5, double(iso_tolerance)));
    CHECK(std::abs(ma.volume_ratio - mb.volume_ratio) <= 5e-3);
    CHECK(ma.new_inverted_triangles <= mb.new_inverted_triangles);
    CHECK((a.positions() - b.positions()).rowwise().norm().maxCoeff() <= 1.5e-2 * diagonal);
  };
  for (const double angle : {50.0, 100.0, 20.0}) {
    a.set_joint_angles(1, {angle, 0, 0});
    b.set_joint_angles(1, {angle, 0, 0});
    CHECK(a.poll(60e3));  // returns once the first part (or already the rest) is published
    CHECK(a.shown_id() == a.request_id());
    a.wait_idle();
    settled_as_whole("one edit");
  }
  // A burst: the edits replace each other or cut the slicing short; the last settles.
  a.begin_drag();
  b.begin_drag();
  for (int k = 1; k <= 10; ++k) {
    a.set_joint_angles(1, {20.0 + 8.0 * k, 0, 0});
    b.set_joint_angles(1, {20.0 + 8.0 * k, 0, 0});
  }
  a.end_drag();
  b.end_drag();
  a.wait_idle();
  CHECK(a.shown_id() == a.request_id());
  settled_as_whole("a drag");
}

TEST_CASE("viewer: a clip exported from the viewer is the glb bake writes", "[viewer][unit]") {
  auto sk = cylinder();
  ViewerModel m(sk, Method::kTracking2014, quick());
  CHECK_THROWS_WITH(m.export_clip("x.glb"), Catch::Contains("no clip"));
  m.play_clip("bend");
  m.set_frame(3);
  const auto dir = std::filesystem::temp_directory_path() /
                   ("isokit_viewer_export_" + std::to_string(std::random_device{}()));
  std::filesystem::create_directories(dir);
  m.export_clip((dir / "viewer.glb").string());
  CHECK(m.frame() == 3);  // the shown frame stays
  const BakeResult b = sk->bake(Method::kTracking2014, sk->rig().clips[0].local, quick_bake());
  write_baked_glb(sk->rig(), b.frames, sk->rig().clips[0].fps, (dir / "bake.glb").string());
  auto bytes = [](const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  CHECK(bytes(dir / "viewer.glb") == bytes(dir / "bake.glb"));
  std::filesystem::remove_all(dir);
}
