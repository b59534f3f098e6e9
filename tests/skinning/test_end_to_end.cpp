// SPDX-License-Identifier: MIT
// End-to-end properties on the built-in procedural rigs (issue 6 "must show").
#include <catch2/catch.hpp>

#include <array>
#include <cstdio>
#include <map>

#include "isokit/skinning/animation.h"
#include "isokit/skinning/pipeline.h"
#include "isokit/skinning/procedural.h"
#include "isokit/skinning/rig_io.h"
#include "isokit/skinning/weights.h"

using namespace isokit::skinning;

namespace {
SkinSetup fast_setup() {
  SkinSetup setup;
  setup.operator_resolution = 64;
  setup.operator_slices = 32;
  return setup;
}
}  // namespace

TEST_CASE("e2e: a rig with no weights gets heat weights and still skins", "[skinning][e2e][slow]") {
  Rig r = make_cylinder();
  r.weights = {};
  r.weights = heat_weights(r);
  validate(r);
  Skinner sk(r, fast_setup());
  const auto poses = bend_animation(sk.rig(), {parse_bend("Bone1:x:90", sk.rig())}, 5);
  BakeOptions o;
  o.self_intersections = false;
  const BakeResult dqs = sk.bake(Method::kDqs, poses, o);
  const BakeResult trk = sk.bake(Method::kTracking2014, poses, o);
  CHECK(dqs.frames.size() == 5);
  CHECK(trk.worst.iso_residual_max < 1e-3);
  // Issue 6's rest-recovery target (1e-3 of the diagonal) holds with heat weights too (6e-5 on
  // 2026-12-01; it was 3.6e-3 before the lazy-evaluation tracker).
  CHECK(trk.rest_recovery <= 1e-3);
}

TEST_CASE("e2e: a procedural rig written to glTF and read back skins identically", "[skinning][e2e][slow]") {
  const Rig a = make_finger();
  const std::string path = "e2e_finger_roundtrip.glb";
  save_rig(a, path);
  const Rig b = load_rig(path);
  std::remove(path.c_str());
  REQUIRE(b.joints.size() == a.joints.size());
  REQUIRE(b.rest.rows() == a.rest.rows());
  // The loader may order welded vertices differently: match them by rest position.
  std::map<std::array<float, 3>, Eigen::Index> index_b;
  for (Eigen::Index v = 0; v < b.rest.rows(); ++v) index_b[{b.rest(v, 0), b.rest(v, 1), b.rest(v, 2)}] = v;
  std::vector<Eigen::Index> to_b(static_cast<std::size_t>(a.rest.rows()), -1);
  for (Eigen::Index v = 0; v < a.rest.rows(); ++v) {
    auto it = index_b.find({a.rest(v, 0), a.rest(v, 1), a.rest(v, 2)});
    REQUIRE(it != index_b.end());
    to_b[static_cast<std::size_t>(v)] = it->second;
  }
  std::vector<BendSpec> bends = {parse_bend("Finger1:x:60", a), parse_bend("Finger2:x:90", a),
                                 parse_bend("Finger3:x:45", a)};
  const auto pa = bend_animation(a, bends, 5), pb = bend_animation(b, bends, 5);
  SkinSetup setup = fast_setup();
  Skinner sa(a, setup), sb(b, setup);
  BakeOptions o;
  o.self_intersections = false;
  const double diag = bbox_diagonal(a.rest);
  for (Method m : {Method::kLbs, Method::kDqs}) {
    const BakeResult ra = sa.bake(m, pa, o), rb = sb.bake(m, pb, o);
    for (std::size_t f = 0; f < ra.frames.size(); ++f) {
      double worst = 0;
      for (Eigen::Index v = 0; v < a.rest.rows(); ++v)
        worst =
            std::max(worst, double((ra.frames[f].row(v) - rb.frames[f].row(to_b[std::size_t(v)])).norm()));
      INFO(to_string(m) << " frame " << f);
      CHECK(worst <= 1e-5 * diag);
    }
  }
}

TEST_CASE("e2e: humanoid elbow at 150 degrees: every joint fits, LBS and DQS intersect",
          "[skinning][e2e][slow]") {
  Skinner sk(make_humanoid({4000, false}), fast_setup());
  const Rig& rig = sk.rig();
  const std::vector<int> owner = dominant_joint(rig.weights, static_cast<int>(rig.rest.rows()));
  for (const BonePart& b : sk.fitted().bones()) {
    const std::string& name = rig.joints[b.joint].name;
    INFO(name << ": " << b.error);
    CHECK((b.fitted || b.vertices == 0));
    // Every joint with skin gets its own primitive, the hips (a part with three holes, closed at
    // its child joints) included; the shoulders' skin (an open band over the clavicle) does not
    // fit and goes to the chest (docs/skinning.md, "fitting").
    const bool had_skin = b.error != "no vertices";
    if (had_skin && name != "LeftShoulder" && name != "RightShoulder") CHECK(b.fitted);
    if (!b.fitted && had_skin) CHECK(rig.joints[static_cast<std::size_t>(b.merged_into)].name == "Spine2");
    // No thigh primitive reaches into the belly (it did when the hips' skin was merged into
    // the left thigh: its field held 81 Spine vertices at rest).
    if (b.fitted && (name == "LeftUpLeg" || name == "RightUpLeg")) {
      int inside = 0;
      for (Eigen::Index v = 0; v < rig.rest.rows(); ++v) {
        if (rig.joints[static_cast<std::size_t>(owner[static_cast<std::size_t>(v)])].name.rfind("Spine", 0) !=
            0)
          continue;
        const isokit::Vec3d p =
            b.fit.local_to_world.apply_inverse(isokit::Vec3d{rig.rest(v, 0), rig.rest(v, 1), rig.rest(v, 2)});
        if (b.fit.field()->eval(isokit::Vec3f{float(p.x), float(p.y), float(p.z)}).value > 0.5f) ++inside;
      }
      CHECK(inside == 0);
    }
  }
  // The same through the fit report: the thighs hold (almost) no vertex of unrelated joints
  // (183 in the left thigh before the fix).
  for (const PrimitiveCoverage& c : primitive_coverage(sk.fitted())) {
    const std::string& name = rig.joints[static_cast<std::size_t>(c.joint)].name;
    INFO(name << ": own " << c.own << ", related " << c.related << ", unrelated " << c.unrelated);
    if (name == "LeftUpLeg" || name == "RightUpLeg") CHECK(c.unrelated <= 5);
  }
  const auto poses = bend_animation(sk.rig(), {parse_bend("LeftForeArm:x:150", sk.rig())}, 9);
  const BakeResult lbs = sk.bake(Method::kLbs, poses);
  const BakeResult dqs = sk.bake(Method::kDqs, poses);
  CHECK(lbs.stats[0].metrics.self_intersections == 0);  // the rest mesh is clean
  CHECK(lbs.stats[0].metrics.new_inverted_triangles == 0);
  CHECK(lbs.worst.self_intersections > 0);
  CHECK(dqs.worst.self_intersections > 0);
  // tracking2014: no intersections (issue 6's target; the inverted-triangle half is the case
  // below), back at rest, and the tracker's active set only iterates the vertices near the
  // bending elbow (a fraction of the body).
  const BakeResult trk = sk.bake(Method::kTracking2014, poses);
  CHECK(trk.worst.self_intersections == 0);
  CHECK(trk.rest_recovery <= 1e-3);
  double updates = 0, full = 0;
  for (const FrameStats& s : trk.stats) {
    updates += s.vertex_updates;
    full += double(s.iterations) * double(sk.rig().rest.rows());
  }
  INFO("vertex updates " << updates << " of " << full);
  CHECK(updates < 0.25 * full);
}

// Issue 6's inverted-triangle target on the humanoid (the intersection and rest-recovery halves
// are checked by the case above): 5 new inverted triangles at the fold's apex before the fold
// repair, 1 before the orientation repair (2026-12-01), 0 with it.
TEST_CASE("e2e: humanoid elbow at 150 degrees without inverted triangles with tracking2014",
          "[skinning][e2e][slow]") {
  Skinner sk(make_humanoid({4000, false}), fast_setup());
  const auto poses = bend_animation(sk.rig(), {parse_bend("LeftForeArm:x:150", sk.rig())}, 9);
  const BakeResult trk = sk.bake(Method::kTracking2014, poses);
  INFO("new inverted " << trk.worst.new_inverted_triangles);
  CHECK(trk.worst.new_inverted_triangles == 0);
}

// The built-in cylinder (the 2014 paper's Fig. 2; polygonized, 2,000 vertices, radius 0.3) at 150
// degrees: its contact fold leaves tangled triangles that the contact smoothing alone does not
// undo (37 self-intersecting pairs, 36 inverted triangles on 2026-12-01); the fold repair does
// (and so does the orientation repair alone: 0 pairs, 2 inverted triangles).
TEST_CASE("e2e: the built-in cylinder at 150 degrees: no intersections with the fold repair",
          "[skinning][e2e][slow]") {
  SkinSetup off;  // the defaults, as `isokit-skin bake procedural:cylinder` runs, without repairs
  off.tracker.fold_repair.rounds = 0;
  off.tracker.orientation_repair.rounds = 0;
  Skinner plain(make_cylinder(), off);
  const auto poses = bend_animation(plain.rig(), {parse_bend("Bone1:z:150", plain.rig())}, 31);
  const BakeResult before = plain.bake(Method::kTracking2014, poses);
  Skinner sk(make_cylinder(), SkinSetup{});
  const BakeResult trk = sk.bake(Method::kTracking2014, poses);
  INFO("without the repairs: " << before.worst.self_intersections << " pairs, "
                               << before.worst.new_inverted_triangles
                               << " inverted; with: " << trk.worst.self_intersections << " pairs, "
                               << trk.worst.new_inverted_triangles << " inverted; rest "
                               << trk.rest_recovery);
  CHECK(before.worst.self_intersections > 0);
  CHECK(trk.worst.self_intersections == 0);
  CHECK(trk.worst.new_inverted_triangles * 2 < before.worst.new_inverted_triangles);
  CHECK(trk.rest_recovery <= 1e-3);
  CHECK(trk.worst.iso_residual_max < 1e-3);
}

// Interpenetration as a user sees it: at 150 degrees DQS passes the cylinder's two halves into
// each other (volume enclosed twice), the tracked skin forms a contact instead (issue 42's
// must-show: DQS > 0.5 % of the volume, tracking2014 <= 1e-4) and returns to rest. A contact
// fold without a bulge gives up the volume DQS overlaps and the flattened crease: measured 0.87
// (LBS 0.80, implicit2013 0.855; 2026-12-06); below 0.85 the skin is shrinking.
TEST_CASE("e2e: the built-in cylinder at 150 degrees: DQS interpenetrates and tracking2014 does not",
          "[skinning][e2e][slow]") {
  Skinner sk(make_cylinder(), SkinSetup{});
  const auto poses = bend_animation(sk.rig(), {parse_bend("Bone1:z:150", sk.rig())}, 31);
  BakeOptions o;
  o.self_intersections = false;
  const BakeResult dqs = sk.bake(Method::kDqs, poses, o);
  const BakeResult trk = sk.bake(Method::kTracking2014, poses, o);
  INFO("new overlap: dqs " << dqs.worst.self_overlap_new << ", tracking2014 " << trk.worst.self_overlap_new
                           << "; tracking2014 volume " << trk.worst.volume_ratio);
  CHECK(dqs.worst.self_overlap_new > 5e-3);
  CHECK(trk.worst.self_overlap_new <= 1e-4);
  CHECK(trk.worst.volume_ratio >= 0.85);
  CHECK(trk.rest_recovery <= 1e-3);
}

// Past what the field can fold (170 degrees: the limbs' fields merge) the tracker pushes vertices
// through their bone's axis; without the axis guard the forearm-like half flattened into a sheet
// on the way back and the mesh never returned (rest recovery 0.17 of the diagonal, 2026-12-01).
TEST_CASE("e2e: the built-in cylinder bent to 170 degrees comes back to rest", "[skinning][e2e][slow]") {
  SkinSetup off;
  off.axis_guard = false;
  Skinner plain(make_cylinder(), off);
  const auto poses = bend_animation(plain.rig(), {parse_bend("Bone1:z:170", plain.rig())}, 31);
  BakeOptions fast;
  fast.self_intersections = false;
  const BakeResult before = plain.bake(Method::kTracking2014, poses, fast);
  Skinner sk(make_cylinder(), SkinSetup{});
  const BakeResult trk = sk.bake(Method::kTracking2014, poses, fast);
  int moves = 0;
  for (const FrameStats& s : trk.stats) moves += s.axis_guard_moves;
  INFO("rest recovery without the guard " << before.rest_recovery << ", with " << trk.rest_recovery << " ("
                                          << moves << " vertices put back)");
  CHECK(before.rest_recovery > 1e-2);
  CHECK(trk.rest_recovery <= 1e-3);
  CHECK(moves > 0);
  CHECK(trk.worst.volume_ratio > 0.6);
}

// Issue 6's inverted-triangle target on the built-in cylinder. The fold repair leaves a few
// triangles across the floor of the contact valley, their centroids a hair on the wrong side
// (8 on 2026-12-01); the orientation repair moves single vertices to turn them.
TEST_CASE("e2e: the built-in cylinder at 150 degrees without inverted triangles", "[skinning][e2e][slow]") {
  SkinSetup off;
  off.tracker.orientation_repair.rounds = 0;
  Skinner plain(make_cylinder(), off);
  const auto poses = bend_animation(plain.rig(), {parse_bend("Bone1:z:150", plain.rig())}, 31);
  BakeOptions no_pairs;
  no_pairs.self_intersections = false;
  const BakeResult before = plain.bake(Method::kTracking2014, poses, no_pairs);
  Skinner sk(make_cylinder(), SkinSetup{});
  const BakeResult trk = sk.bake(Method::kTracking2014, poses);
  int oriented = 0;
  for (const FrameStats& s : trk.stats) oriented += s.oriented_vertices;
  INFO("new inverted without the orientation repair " << before.worst.new_inverted_triangles << ", with "
                                                      << trk.worst.new_inverted_triangles << " (" << oriented
                                                      << " vertex moves)");
  CHECK(before.worst.new_inverted_triangles > 0);
  CHECK(trk.worst.new_inverted_triangles == 0);
  CHECK(trk.worst.self_intersections == 0);
  CHECK(oriented > 0);
  CHECK(trk.rest_recovery <= 1e-3);
}

// The full-body crouch of the Table 1 benchmark (41 joints bent together, 0.05 rad per frame):
// before the hips had their own primitive, belly vertices ended on a bloated thigh primitive's
// surface (edge distortion max 7.0, rest recovery 1.1e-3; docs/skinning.md, "Known limits").
TEST_CASE("e2e: full-body crouch on the 13k humanoid: no intersections, no captured skin, back at rest",
          "[skinning][e2e][slow]") {
  Skinner sk(make_humanoid({13000, true}), fast_setup());
  const std::vector<BendSpec> bends = crouch_bends(sk.rig());
  CHECK(bends.size() == 41);
  const auto poses = bend_animation(sk.rig(), bends, 65);
  const BakeResult trk = sk.bake(Method::kTracking2014, poses);
  INFO("self-intersections " << trk.worst.self_intersections << ", edge distortion max "
                             << trk.worst.edge_distortion_max << ", rest " << trk.rest_recovery
                             << ", new inverted " << trk.worst.new_inverted_triangles);
  CHECK(trk.worst.self_intersections == 0);
  CHECK(trk.worst.edge_distortion_max < 1.0);  // dqs: 0.80; a captured vertex stretches its edges 4-8x
  CHECK(trk.rest_recovery <= 1e-3);
}

// A `bulge` joint without the gate, with the controller at 1 from 90° (`bulge2013`, the bulge
// preset before 2026-12-01): inside the finger at rest the two phalanges' caps overlap with
// gradients more than 90° apart, the controller is 1 there and the operator's contact line makes
// a valley inside the limb; skin that slides into it during the bend stays (rest recovery 9.8e-2
// on 2026-12-01). The gate caps the controller by the joint's bend.
TEST_CASE("e2e: a bulge joint returns to rest with the bulge gate", "[skinning][e2e][slow]") {
  SkinSetup on = fast_setup();
  on.joints["Finger2"].op = JointOperator::kBulge;
  on.bulge_controller = "bulge2013";
  SkinSetup off = on;
  off.bulge_gate = false;
  Skinner gated(make_finger(), on), plain(make_finger(), off);
  const auto poses = bend_animation(gated.rig(), {parse_bend("Finger2:x:60", gated.rig())}, 31);
  BakeOptions fast;
  fast.self_intersections = false;
  const BakeResult with = gated.bake(Method::kTracking2014, poses, fast);
  const BakeResult without = plain.bake(Method::kTracking2014, poses, fast);
  INFO("rest recovery with the gate " << with.rest_recovery << ", without " << without.rest_recovery);
  CHECK(without.rest_recovery > 1e-2);
  CHECK(with.rest_recovery <= 1e-3);
  CHECK(with.worst.new_inverted_triangles == 0);
  // At the bend the gate is open: the bulge is there (the volume grows past the contact
  // operator's).
  Skinner contact(make_finger(), fast_setup());
  const BakeResult c = contact.bake(Method::kTracking2014, poses, fast);
  INFO("volume ratio at the bend: bulge " << with.stats[15].metrics.volume_ratio << ", contact "
                                          << c.stats[15].metrics.volume_ratio);
  CHECK(with.stats[15].metrics.volume_ratio > c.stats[15].metrics.volume_ratio);
}

TEST_CASE("e2e: the bulge gate finds every bulge joint, chained ones too, in both trees",
          "[skinning][e2e][slow]") {
  // Three bulge joints in a chain: the 2014 builder pairs (Finger0, Finger1) and (Finger2,
  // Finger3) at the bottom and joins the pairs by Finger2's bulge operator; the 2013 builder
  // has one bulge pair per joint. At rest every gated node's controller is 0; bent, it opens.
  for (TreeKind kind : {TreeKind::k2014, TreeKind::k2013}) {
    for (bool gate : {true, false}) {
      SkinSetup setup = fast_setup();
      setup.bulge_gate = gate;
      for (const char* j : {"Finger1", "Finger2", "Finger3"}) setup.joints[j].op = JointOperator::kBulge;
      Skinner sk(make_finger(), setup);
      SkinField& field = sk.field(kind);
      auto closed = [&]() {
        int n = 0;
        const auto& instr = field.program().instructions();
        for (std::size_t i = 0; i < instr.size(); ++i)
          if (instr[i].leaf < 0 && instr[i].kind == isokit::implicit::OpKind::Grid &&
              field.pose().controller(field.program(), i).values[255] == 0.f)
            ++n;
        return n;
      };
      field.set_pose(skinning_matrices(sk.rig(), rest_pose(sk.rig())));
      INFO((kind == TreeKind::k2014 ? "2014" : "2013") << " tree, gate " << gate);
      CHECK(closed() == (gate ? 3 : 0));
      const auto bent = bend_animation(sk.rig(), {parse_bend("Finger2:x:90", sk.rig())}, 3)[1];
      field.set_pose(skinning_matrices(sk.rig(), bent));
      CHECK(closed() == (gate ? 2 : 0));  // Finger2's node opens (d_b(90°) = 0.5), the others stay shut
    }
  }
}

// The bulge controller rising over [0, π] (docs/operators.md, "Decision: the bulge controller"):
// the bulge operator folds like the contact operator. With the controller at 1 from 90° the
// built-in cylinder at 150° had 158 self-intersecting pairs (2026-12-01).
TEST_CASE("e2e: the built-in cylinder folds to 150 degrees with the bulge operator",
          "[skinning][e2e][slow]") {
  SkinSetup setup = fast_setup();
  setup.joints["Bone1"].op = JointOperator::kBulge;
  SkinSetup early = setup;
  early.bulge_controller = "bulge2013";
  Skinner sk(make_cylinder(), setup), old(make_cylinder(), early);
  const auto poses = bend_animation(sk.rig(), {parse_bend("Bone1:z:150", sk.rig())}, 31);
  const BakeResult trk = sk.bake(Method::kTracking2014, poses),
                   before = old.bake(Method::kTracking2014, poses);
  INFO("bulge: " << trk.worst.self_intersections << " pairs, overlap " << trk.worst.self_overlap_new << ", "
                 << trk.worst.new_inverted_triangles << " inverted, rest " << trk.rest_recovery
                 << "; controller at 1 from 90 degrees: " << before.worst.self_intersections
                 << " pairs, overlap " << before.worst.self_overlap_new);
  // Judged by the interpenetration volume (a few pairs of skin pressed flat on the contact cross
  // without passing into each other).
  CHECK(before.worst.self_overlap_new > 5e-5);
  CHECK(trk.worst.self_overlap_new <= 1e-5);
  CHECK(trk.worst.new_inverted_triangles <= 5);
  CHECK(trk.rest_recovery <= 1e-3);
}
