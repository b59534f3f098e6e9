// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include <algorithm>
#include <limits>

#include "isokit/core/error.h"
#include "isokit/skinning/animation.h"
#include "isokit/skinning/pipeline.h"
#include "isokit/skinning/procedural.h"
#include "isokit/skinning/rigid_pieces.h"

using namespace isokit::skinning;

namespace {

/// `rig` plus a closed tetrahedron at `at` whose four vertices have the influences `inf` (one
/// list of (joint, weight) per vertex).
void add_tetrahedron(Rig& rig, const Eigen::Vector3f& at,
                     const std::vector<std::vector<std::pair<int, float>>>& inf) {
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
  add_tetrahedron(rig, {5, 0, 0},
                  {{{0, .2f}, {1, .8f}}, {{0, .3f}, {1, .7f}}, {{0, .2f}, {1, .8f}}, {{0, .2f}, {1, .8f}}});
  const std::vector<RigidPiece> pieces = find_rigid_pieces(rig);
  REQUIRE(pieces.size() == 2);
  CHECK(pieces[0].vertices == std::vector<int>{int(skin_vertices), int(skin_vertices) + 1,
                                               int(skin_vertices) + 2, int(skin_vertices) + 3});
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

TEST_CASE(
    "rigid pieces: with tracker.rigid_pieces they move exactly with their bone, the skin is still tracked",
    "[skinning][rigid][unit]") {
  Rig rig = make_cylinder();
  const auto skin_vertices = rig.rest.rows();
  // A prop on Bone1 straddling the skin by the joint, where the composed field differs from the
  // bone's transform: the tracker would move it.
  add_tetrahedron(rig, {0.25f, 1.05f, 0.f}, {{{1, 1.f}}, {{1, 1.f}}, {{1, 1.f}}, {{1, 1.f}}});
  const std::vector<Pose> poses = bend_animation(rig, {parse_bend("Bone1:x:60", rig)}, 5);
  const double diag = (rig.rest.colwise().maxCoeff() - rig.rest.colwise().minCoeff()).cast<double>().norm();
  BakeOptions quick;
  quick.self_intersections = false;
  const BakeResult dqs = Skinner(rig).bake(Method::kDqs, poses, quick);
  for (const bool rigid : {false, true}) {
    SkinSetup setup;
    setup.rigid_pieces = rigid;
    Skinner sk(rig, setup);
    for (const Method m : {Method::kTracking2014, Method::kImplicit2013}) {
      const BakeResult r = sk.bake(m, poses, quick);
      double prop = 0, skin = 0;
      for (std::size_t f = 0; f < poses.size(); ++f) {
        prop = std::max(
            prop, double((r.frames[f].bottomRows(4) - dqs.frames[f].bottomRows(4)).cwiseAbs().maxCoeff()));
        skin =
            std::max(skin, double((r.frames[f].topRows(skin_vertices) - dqs.frames[f].topRows(skin_vertices))
                                      .cwiseAbs()
                                      .maxCoeff()));
      }
      INFO(to_string(m) << (rigid ? " with" : " without") << " rigid pieces: prop " << prop / diag
                        << ", skin " << skin / diag);
      if (rigid)
        CHECK(prop <= 1e-6 * diag);  // exactly its bone's transform
      else
        CHECK(prop > 1e-4 * diag);  // projected onto the field like skin
      CHECK(skin > 1e-4 * diag);    // the skin is tracked, not skinned
    }
  }
}

namespace {

/// The cylinder bent at Bone1 by 60° in 5 frames, its Bone1 part (the fitted partition) and the
/// bbox diagonal.
struct MaskScene {
  Rig rig = make_cylinder();
  std::vector<Pose> poses = bend_animation(rig, {parse_bend("Bone1:x:60", rig)}, 5);
  std::vector<int> part;  ///< vertices of Bone1's part
  double diag = (rig.rest.colwise().maxCoeff() - rig.rest.colwise().minCoeff()).cast<double>().norm();
  BakeOptions quick;

  MaskScene() {
    quick.self_intersections = false;
    const std::vector<int> partition = Skinner(rig).fitted().partition();  // a copy: the Skinner goes
    for (std::size_t v = 0; v < partition.size(); ++v)
      if (partition[v] == 1) part.push_back(static_cast<int>(v));
  }

  /// Largest distance of the part's vertices to their rigid positions (Bone1's transform), over
  /// the frames of `r`.
  double from_rigid(const BakeResult& r) const {
    double d = 0;
    for (std::size_t f = 0; f < poses.size(); ++f) {
      const Affine m = skinning_matrices(rig, poses[f])[1];
      for (int v : part) {
        const Eigen::Vector3d rigid = m * rig.rest.row(v).cast<double>().transpose();
        d = std::max(d, (r.frames[f].row(v).cast<double>().transpose() - rigid).norm());
      }
    }
    return d;
  }
};

}  // namespace

TEST_CASE("relaxation mask: 0 moves the vertices rigidly with their bone, from the setup or the file",
          "[skinning][rigid][mask][unit]") {
  MaskScene sc;
  REQUIRE(sc.part.size() > 20);
  SkinSetup by_joint;
  by_joint.joints["Bone1"].relaxation = 0.0f;
  Rig painted = sc.rig;
  painted.relax_mask.assign(static_cast<std::size_t>(sc.rig.rest.rows()), 1.0f);
  for (int v : sc.part) painted.relax_mask[static_cast<std::size_t>(v)] = 0.0f;
  const BakeResult dqs = Skinner(sc.rig).bake(Method::kDqs, sc.poses, sc.quick);
  for (const Method m : {Method::kTracking2014, Method::kImplicit2013}) {
    INFO(to_string(m));
    const BakeResult a = Skinner(sc.rig, by_joint).bake(m, sc.poses, sc.quick);
    const BakeResult b = Skinner(painted).bake(m, sc.poses, sc.quick);
    const BakeResult free = Skinner(sc.rig).bake(m, sc.poses, sc.quick);
    CHECK(sc.from_rigid(a) <= 1e-6 * sc.diag);
    CHECK(sc.from_rigid(free) > 1e-4 * sc.diag);  // tracked without the mask
    for (std::size_t f = 0; f < sc.poses.size(); ++f) CHECK(a.frames[f] == b.frames[f]);  // the same mask
    // The rest of the skin is still tracked.
    double skin = 0;
    std::vector<char> in_part(static_cast<std::size_t>(sc.rig.rest.rows()), 0);
    for (int v : sc.part) in_part[static_cast<std::size_t>(v)] = 1;
    for (std::size_t f = 0; f < sc.poses.size(); ++f)
      for (Eigen::Index v = 0; v < sc.rig.rest.rows(); ++v)
        if (!in_part[static_cast<std::size_t>(v)])
          skin = std::max(skin, double((a.frames[f].row(v) - dqs.frames[f].row(v)).norm()));
    CHECK(skin > 1e-4 * sc.diag);
    CHECK(a.frames.back().allFinite());
  }
}

TEST_CASE("relaxation mask: a value between 0 and 1 pulls toward the rigid position, more as it falls",
          "[skinning][rigid][mask][unit]") {
  MaskScene sc;
  for (const Method m : {Method::kTracking2014, Method::kImplicit2013}) {
    INFO(to_string(m));
    double last = std::numeric_limits<double>::infinity();
    for (const float value : {1.0f, 0.6f, 0.2f, 0.0f}) {
      INFO("mask " << value);
      Rig rig = sc.rig;
      rig.relax_mask.assign(static_cast<std::size_t>(rig.rest.rows()), 1.0f);
      for (int v : sc.part) rig.relax_mask[static_cast<std::size_t>(v)] = value;
      const double d = sc.from_rigid(Skinner(rig).bake(m, sc.poses, sc.quick));
      CHECK(d < last);
      last = d;
    }
    CHECK(last <= 1e-6 * sc.diag);
  }
}

namespace {

/// The cylinder with a block on Bone0 beside the elbow, off the skin at rest: bending Bone1 by 90°
/// about x swings the forearm (+y) toward +z, through where the block is. The block's vertices
/// weigh on Bone0 alone: a rigid piece.
struct BlockScene {
  Rig rig = make_cylinder();
  Eigen::Index skin_vertices = rig.rest.rows();
  Eigen::Vector3f lo{-0.12f, 0.62f, 0.34f}, hi{0.12f, 0.9f, 0.6f};
  std::vector<Pose> poses;
  BakeOptions quick;

  BlockScene() {
    const auto base = static_cast<int>(rig.rest.rows());
    rig.rest.conservativeResize(base + 8, 3);
    for (int c = 0; c < 8; ++c)
      rig.rest.row(base + c) << ((c & 1) ? hi.x() : lo.x()), ((c & 2) ? hi.y() : lo.y()),
          ((c & 4) ? hi.z() : lo.z());
    const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                             {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    const auto t0 = rig.triangles.rows();
    rig.triangles.conservativeResize(t0 + 12, 3);
    for (int q = 0; q < 6; ++q) {
      rig.triangles.row(t0 + 2 * q) << base + quads[q][0], base + quads[q][1], base + quads[q][2];
      rig.triangles.row(t0 + 2 * q + 1) << base + quads[q][0], base + quads[q][2], base + quads[q][3];
    }
    for (int c = 0; c < 8; ++c) {
      rig.weights.joints.push_back(0);
      rig.weights.weights.push_back(1.f);
      rig.weights.offsets.push_back(static_cast<int>(rig.weights.joints.size()));
    }
    poses = bend_animation(rig, {parse_bend("Bone1:x:90", rig)}, 21);
    quick.self_intersections = false;
  }
  /// Forearm skin vertices inside the block (shrunk by 1 % of its size: on its face is a touch).
  int inside(const isokit::track::Positions& p) const {
    const Eigen::Vector3f pad = 0.01f * (hi - lo);
    int n = 0;
    for (Eigen::Index v = 0; v < skin_vertices; ++v) {
      const Eigen::Vector3f q = p.row(v).transpose();
      if (rig.rest(v, 1) > 1.0f && (q.array() > (lo + pad).array()).all() &&
          (q.array() < (hi - pad).array()).all())
        ++n;
    }
    return n;
  }
  /// The composed 2014 field at the block's centre, at rest.
  float field_at_block(Skinner& sk) const {
    SkinField& field = sk.field(TreeKind::k2014);
    field.set_pose(skinning_matrices(rig, rest_pose(rig)));
    const Eigen::Vector3f c = 0.5f * (lo + hi);
    isokit::Vec3f at{c.x(), c.y(), c.z()}, g;
    float value = 0.f;
    std::uint8_t contact = 0;
    field.function()(&at, 1, &value, &g, &contact);
    return value;
  }
  /// The block stays exactly where its bone holds it, every frame.
  void check_block_rigid(const BakeResult& r) const {
    for (const isokit::track::Positions& f : r.frames)
      CHECK((f.bottomRows(8) - rig.rest.bottomRows(8)).cwiseAbs().maxCoeff() == 0.f);
  }
};

}  // namespace

TEST_CASE("rigid pieces: a piece the skin runs into does not give way", "[skinning][rigid][unit]") {
  const BlockScene sc;
  REQUIRE(find_rigid_pieces(sc.rig).size() == 1);
  const BakeResult dqs = Skinner(sc.rig).bake(Method::kDqs, sc.poses, sc.quick);
  const BakeResult trk = Skinner(sc.rig).bake(Method::kTracking2014, sc.poses, sc.quick);
  INFO("forearm vertices inside the block at 90 degrees: dqs "
       << sc.inside(dqs.frames[10]) << ", tracking2014 " << sc.inside(trk.frames[10]));
  CHECK(sc.inside(dqs.frames[10]) > 10);  // the forearm does reach the block
  // Known limit (docs/skinning.md, "Rigid parts and the relaxation mask"): the tracked skin does
  // not stop on the block either (28 vertices inside under DQS, 43 tracked when measured); see
  // the next test for what holds it there.
  sc.check_block_rigid(trk);
}

TEST_CASE(
    "rigid pieces: with tracker.piece_fields a piece has its own field, which the contact stages override",
    "[skinning][rigid][unit]") {
  const BlockScene sc;
  Skinner plain(sc.rig);
  SkinSetup with;
  with.piece_fields = true;
  Skinner pieced(sc.rig, with);
  // Bone0's part field barely covers so small a piece; the piece's own distance field does.
  const float bare = sc.field_at_block(plain), own = sc.field_at_block(pieced);
  INFO("composed field at the block's centre: " << bare << " without, " << own << " with its own field");
  CHECK(bare < 0.6f);
  CHECK(own > 0.9f);
  const BakeResult trk = pieced.bake(Method::kTracking2014, sc.poses, sc.quick);
  sc.check_block_rigid(trk);
  // The field now holds the forearm out of the block, once the contact stages let it: without the
  // angle and fold contacts and the contact smoothing, fewer forearm vertices end inside (13 when
  // measured with the default fixed16 grids, 7 with float32 ones — the tracker turns the grids'
  // 1.5e-5 quantisation into that —, against 28 under DQS; the skin folds around the block then);
  // with them (the defaults) the vertices turned against the block's gradient are taken for
  // contacts and left inside (37 when measured).
  SkinSetup bare_tracker = with;
  bare_tracker.tracker.angle_contacts = false;
  bare_tracker.tracker.fold_contacts = false;
  bare_tracker.tracker.smoothing.smoothing_steps = 0;
  const BakeResult held = Skinner(sc.rig, bare_tracker).bake(Method::kTracking2014, sc.poses, sc.quick);
  const BakeResult dqs = plain.bake(Method::kDqs, sc.poses, sc.quick);
  INFO("inside at 90 degrees: dqs " << sc.inside(dqs.frames[10]) << ", defaults " << sc.inside(trk.frames[10])
                                    << ", without the contact stages " << sc.inside(held.frames[10]));
  CHECK(sc.inside(held.frames[10]) * 2 <= sc.inside(dqs.frames[10]));
  sc.check_block_rigid(held);
}

TEST_CASE("small parts: their relaxation mask pulls them toward DQS, 0 skins them by DQS",
          "[skinning][rigid][mask][unit]") {
  MaskScene sc;
  const BakeResult dqs = Skinner(sc.rig).bake(Method::kDqs, sc.poses, sc.quick);
  auto from_dqs = [&](const BakeResult& r) {
    double d = 0;
    for (std::size_t f = 0; f < sc.poses.size(); ++f)
      d = std::max(d, double((r.frames[f] - dqs.frames[f]).cwiseAbs().maxCoeff()));
    return d / sc.diag;
  };
  for (const Method m : {Method::kTracking2014, Method::kImplicit2013}) {
    INFO(to_string(m));
    double last = std::numeric_limits<double>::infinity();
    for (const float value : {1.0f, 0.5f, 0.0f}) {
      SkinSetup setup;
      setup.small_part_mask = value;
      setup.small_part_vertices = 1 << 30;  // every part counts as small
      const double d = from_dqs(Skinner(sc.rig, setup).bake(m, sc.poses, sc.quick));
      INFO("mask " << value << ": " << d << " of the diagonal from DQS");
      CHECK(d < last);
      last = d;
    }
    CHECK(last == 0.0);  // pinned at their DQS positions
    // Parts at or above the size are left alone.
    SkinSetup none;
    none.small_part_mask = 0.0f;
    none.small_part_vertices = 10;
    CHECK(from_dqs(Skinner(sc.rig, none).bake(m, sc.poses, sc.quick)) ==
          from_dqs(Skinner(sc.rig).bake(m, sc.poses, sc.quick)));
  }
  CHECK_THROWS_WITH(setup_from_json(R"({"tracker": {"small_part_mask": 1.5}})", "s.json"),
                    Catch::Contains("s.json.tracker.small_part_mask"));
  CHECK_THROWS_WITH(setup_from_json(R"({"tracker": {"small_part_vertices": -1}})", "s.json"),
                    Catch::Contains("small_part_vertices"));
}
