// SPDX-License-Identifier: MIT
// What real rigs bring to load_rig, each built in code (no shared data needed): duplicate node
// names, a single unnamed clip, surface defects (separate parts, open borders, flipped faces),
// scale keys, several skins, an animation-only file retargeted onto a skeleton whose rest
// orientations differ, and units and axes (a rig scaled by 2^-10 and 2^10 and a z-up copy skin
// the same).
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <nlohmann/json.hpp>

#include "isokit/core/error.h"
#include "isokit/core/math.h"
#include "isokit/skinning/animation.h"
#include "isokit/skinning/bake_job.h"
#include "isokit/skinning/deform.h"
#include "isokit/skinning/pipeline.h"
#include "isokit/skinning/procedural.h"
#include "isokit/skinning/rig_io.h"
#include "pipeline_fixture.h"

using nlohmann::json;
using namespace isokit::skinning;
namespace track = isokit::track;

namespace {

// A scratch folder removed at the end of the test.
class Scratch {
 public:
  explicit Scratch(const std::string& tag)
      : root_(std::filesystem::temp_directory_path() /
              ("isokit_rig_load_" + tag + "_" + std::to_string(std::random_device{}()))) {
    std::filesystem::create_directories(root_);
  }
  ~Scratch() {
    std::error_code ignored;
    std::filesystem::remove_all(root_, ignored);
  }
  std::string operator/(const std::string& name) const { return (root_ / name).string(); }

 private:
  std::filesystem::path root_;
};

// The test capsule with a clip "animation_0" bending Bone1 about z (5 frames).
Rig clip_capsule() {
  const Rig r = testing::with_turn_clip(testing::capsule_rig(16, 12, 3), 5, 0.3);
  validate(r);
  return r;
}

json saved_json(const Rig& rig, const std::string& path) {
  save_rig(rig, path);
  std::ifstream in(path);
  return json::parse(in);
}

void write_json(const std::string& path, const json& doc) {
  std::ofstream(path) << doc.dump();
}

json& node_named(json& doc, const std::string& name) {
  for (json& n : doc["nodes"])
    if (n.value("name", "") == name) return n;
  FAIL("no node " << name);
  return doc;
}

std::string joined_warnings(const LoadReport& report) {
  std::string all;
  for (const std::string& w : report.warnings) all += w + "\n";
  return all;
}

double largest_difference(const std::vector<Pose>& a, const std::vector<Pose>& b) {
  REQUIRE(a.size() == b.size());
  double d = 0;
  for (std::size_t f = 0; f < a.size(); ++f)
    for (std::size_t j = 0; j < a[f].size(); ++j)
      d = std::max(d, (a[f][j].matrix() - b[f][j].matrix()).cwiseAbs().maxCoeff());
  return d;
}

}  // namespace

TEST_CASE("rig_load: duplicate node names load, the file's name shows, NAME#k selects", "[skinning][io]") {
  const Rig rig = clip_capsule();
  Scratch dir("dup");
  json doc = saved_json(rig, dir / "rig.gltf");
  node_named(doc, "Bone1")["name"] = "Root";  // two nodes named "Root" (glTF allows it)
  write_json(dir / "dup.gltf", doc);
  LoadReport report;
  const Rig back = load_rig(dir / "dup.gltf", {}, &report);
  REQUIRE(back.joints.size() == 2);
  CHECK(back.joints[0].name == "Root");
  CHECK(back.joints[0].file_name.empty());
  CHECK(back.joints[1].name == "Root#2");
  CHECK(back.joints[1].file_name == "Root");
  CHECK(back.joints[1].display_name() == "Root");
  CHECK_THAT(joined_warnings(report), Catch::Contains("share a name") && Catch::Contains("Root#2"));
  // Same skeleton, weights and clip as the file with unique names.
  const Rig unique = load_rig(dir / "rig.gltf");
  CHECK(back.weights.joints == unique.weights.joints);
  CHECK(largest_difference(clip_frames(back.clips[0]), clip_frames(unique.clips[0])) == 0);
  // Selection by the unique name; stable from one load to the next.
  CHECK(parse_bend("Root#2:x:-90", back).joint == 1);
  CHECK(load_rig(dir / "dup.gltf").joints[1].name == "Root#2");
}

TEST_CASE("rig_load: one clip and no animation option plays it", "[skinning][io]") {
  Scratch dir("oneclip");
  json doc = saved_json(clip_capsule(), dir / "rig.gltf");
  doc["animations"][0].erase("name");  // unnamed: the loader calls it animation_0
  write_json(dir / "unnamed.gltf", doc);
  const Rig rig = load_rig(dir / "unnamed.gltf");
  const Animation a = make_animation(rig, AnimationRequest{});
  CHECK(a.description == "clip animation_0");
  CHECK(a.poses.size() == rig.clips[0].frame_count());
}

TEST_CASE("rig_load: separate parts, open borders and flipped faces load and are reported",
          "[skinning][io]") {
  Rig rig = clip_capsule();
  // A second, separate copy of the capsule (x + 2), its first ring of faces removed (open) and
  // one face flipped.
  const Eigen::Index nv = rig.rest.rows(), nf = rig.triangles.rows();
  track::Positions rest(2 * nv, 3);
  rest << rig.rest, rig.rest.rowwise() + Eigen::RowVector3f(2, 0, 0);
  track::Triangles tris(2 * nf - 12, 3);
  tris << rig.triangles, (rig.triangles.bottomRows(nf - 12).array() + static_cast<int>(nv)).matrix();
  std::swap(tris(0, 1), tris(0, 2));
  rig.rest = rest;
  rig.triangles = tris;
  SkinWeights w = rig.weights;
  for (Eigen::Index v = 0; v < nv; ++v) {
    for (int k = rig.weights.offsets[v]; k < rig.weights.offsets[v + 1]; ++k) {
      w.joints.push_back(rig.weights.joints[k]);
      w.weights.push_back(rig.weights.weights[k]);
    }
    w.offsets.push_back(static_cast<int>(w.joints.size()));
  }
  rig.weights = w;
  Scratch dir("surface");
  save_rig(rig, dir / "parts.glb");
  LoadReport report;
  const Rig back = load_rig(dir / "parts.glb", {}, &report);
  CHECK_THAT(joined_warnings(report), Catch::Contains("orientation is not consistent"));
  const SurfaceReport s = inspect_surface(back.rest, back.triangles);
  CHECK(s.components == 2);
  CHECK(s.boundary_edges == 12);
  CHECK(s.inconsistent_edges == 3);
}

TEST_CASE("rig_load: glTF triangle strips and fans are triangulated, lines and points are skipped",
          "[skinning][io]") {
  const Rig rig = clip_capsule();
  Scratch dir("modes");
  json doc = saved_json(rig, dir / "capsule.gltf");
  json& prims = doc["meshes"][0]["primitives"];
  REQUIRE(prims.size() == 1);
  const std::size_t indices = doc["accessors"][prims[0]["indices"].get<std::size_t>()]["count"];
  // The same vertices and indices read as a strip, as a fan, and as lines (a second primitive).
  for (const int mode : {5, 6}) {
    json d = doc;
    d["meshes"][0]["primitives"][0]["mode"] = mode;
    json lines = d["meshes"][0]["primitives"][0];
    lines["mode"] = 1;
    d["meshes"][0]["primitives"].push_back(lines);
    write_json(dir / "modes.gltf", d);
    LoadReport report;
    const Rig back = load_rig(dir / "modes.gltf", {}, &report);
    INFO("mode " << mode);
    CHECK(back.output.triangles.rows() == static_cast<Eigen::Index>(indices) - 2);
    CHECK_THAT(joined_warnings(report), Catch::Contains("has no triangles"));
  }
}

TEST_CASE("rig_load: scale keys are applied", "[skinning][io]") {
  Rig rig = clip_capsule();
  for (std::size_t f = 0; f < rig.clips[0].local.size(); ++f)
    rig.clips[0].local[f][1] = rig.clips[0].local[f][1] * Affine(Eigen::Scaling(1.0 + 0.1 * f));
  Scratch dir("scale");
  const json doc = saved_json(rig, dir / "scaled.gltf");
  bool scale_channel = false;
  for (const json& c : doc["animations"][0]["channels"]) scale_channel |= c["target"]["path"] == "scale";
  REQUIRE(scale_channel);
  const Rig back = load_rig(dir / "scaled.gltf");
  const Affine last = clip_frames(back.clips[0]).back()[1];
  CHECK(last.linear().col(0).norm() == Approx(1.4).epsilon(1e-6));
  CHECK(largest_difference(clip_frames(back.clips[0]), rig.clips[0].local) < 1e-6);
}

TEST_CASE("rig_load: several skins load into one rig, skins that disagree are refused by name",
          "[skinning][io]") {
  Rig rig = clip_capsule();
  Scratch dir("skins");
  json doc = saved_json(rig, dir / "rig.gltf");
  // Split the mesh in two meshes on two nodes, the second with its own (equal) skin.
  json mesh = doc["meshes"][0];
  json& prims = doc["meshes"][0]["primitives"];
  REQUIRE(prims.size() == 1);
  json second = mesh;
  second["name"] = "second";
  doc["meshes"].push_back(second);
  doc["skins"].push_back(doc["skins"][0]);
  json node = node_named(doc, "isokit_mesh");
  node["name"] = "second_node";
  node["mesh"] = 1;
  node["skin"] = 1;
  doc["nodes"].push_back(node);
  doc["scenes"][0]["nodes"].push_back(doc["nodes"].size() - 1);
  // (Both meshes hold the same positions: they weld; the output keeps both primitives.)
  write_json(dir / "two.gltf", doc);
  LoadReport report;
  const Rig two = load_rig(dir / "two.gltf", {}, &report);
  CHECK(report.meshes == 2);
  CHECK(two.joints.size() == 2);
  CHECK(two.output.primitive_offsets.size() == 3);
  // A second skin whose joints are swapped binds Root where the first binds Bone1: refused, the
  // message names both meshes.
  std::swap(doc["skins"][1]["joints"][0], doc["skins"][1]["joints"][1]);
  write_json(dir / "bad.gltf", doc);
  try {
    load_rig(dir / "bad.gltf");
    FAIL("no error");
  } catch (const isokit::InputError& e) {
    CHECK_THAT(e.what(), Catch::Contains("bind it at different poses") && Catch::Contains("second"));
  }
}

namespace {

// `rig` with each joint's rest frame turned by `turn[j]` (world frames W_j -> W_j * turn[j]):
// the same mesh, weights and bone positions, other joint orientations.
Rig turn_joint_frames(Rig rig, const std::vector<Eigen::Matrix3d>& turn) {
  std::vector<Affine> world = world_transforms(rig, rest_pose(rig));
  for (std::size_t j = 0; j < world.size(); ++j) world[j].linear() = world[j].linear() * turn[j];
  for (std::size_t j = 0; j < world.size(); ++j) {
    const int p = rig.joints[j].parent;
    rig.joints[j].rest_local =
        p < 0 ? world[j] : Affine(world[static_cast<std::size_t>(p)].inverse(Eigen::Affine) * world[j]);
    rig.joints[j].inverse_bind = world[j].inverse(Eigen::Affine);
  }
  rig.clips.clear();
  return rig;
}

track::Positions skin_lbs(const Rig& rig, const Pose& pose) {
  track::Positions out;
  linear_blend(rig.weights, skinning_matrices(rig, pose), rig.rest, out);
  return out;
}

}  // namespace

TEST_CASE("rig_load: a clip file is retargeted by joint name from each skeleton's own rest pose",
          "[skinning][io]") {
  Rig source = clip_capsule();
  for (std::size_t f = 0; f < source.clips[0].local.size(); ++f)
    source.clips[0].local[f][0] = source.clips[0].local[f][0] *
                                  Affine(Eigen::AngleAxisd(0.1 * f, Eigen::Vector3d::UnitX())) *
                                  Affine(Eigen::Translation3d(0.05 * f, 0, 0));
  // The animation-only file: the source's skeleton and clip, no mesh, no skin.
  Scratch dir("clipfile");
  json doc = saved_json(source, dir / "source.gltf");
  REQUIRE(doc["nodes"].back()["name"] == "isokit_mesh");
  const std::size_t mesh_node = doc["nodes"].size() - 1;
  doc["nodes"].erase(mesh_node);
  doc.erase("meshes");
  doc.erase("skins");
  json roots = json::array();
  for (const json& n : doc["scenes"][0]["nodes"])
    if (n.get<std::size_t>() != mesh_node) roots.push_back(n);
  doc["scenes"][0]["nodes"] = roots;
  write_json(dir / "clip.gltf", doc);
  CHECK_THROWS_WITH(load_rig(dir / "clip.gltf"), Catch::Contains("--clip-file"));

  // The target: the same body, its joint frames turned (rest orientations differ), one extra
  // joint the clip does not know.
  Rig target = turn_joint_frames(
      source, {Eigen::Matrix3d(Eigen::AngleAxisd(isokit::kPi / 2, Eigen::Vector3d::UnitX())),
               Eigen::Matrix3d(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitY()))});
  Joint extra{"Extra", 1, Affine(Eigen::Translation3d(0, 0.5, 0)), Affine::Identity()};
  target.joints.push_back(extra);
  target.joints[2].inverse_bind = world_transforms(target, rest_pose(target))[2].inverse(Eigen::Affine);
  validate(target);

  AnimationRequest request;
  request.clip_file = dir / "clip.gltf";
  const Animation a = make_animation(target, request);
  REQUIRE(a.poses.size() == source.clips[0].local.size());
  REQUIRE(a.warnings.size() == 1);
  CHECK_THAT(a.warnings[0], Catch::Contains("1 joint(s) of the rig") && Catch::Contains("Extra"));
  // The body moves as the source's does.
  for (std::size_t f = 0; f < a.poses.size(); ++f) {
    INFO("frame " << f);
    CHECK((skin_lbs(target, a.poses[f]) - skin_lbs(source, source.clips[0].local[f])).cwiseAbs().maxCoeff() <
          1e-5);
  }
  request.clip = "nothing";
  CHECK_THROWS_WITH(make_animation(target, request), Catch::Contains("animation_0"));
}

namespace {

// `rig` in other units and axes: every point p -> s R p (joint frames stay rigid: world rest
// frames W -> T W S^-1 with T = [sR | 0], S = s I; local transforms keep their rotations, their
// translations scale by s).
Rig similar_rig(Rig rig, double s, const Eigen::Matrix3d& r) {
  sample_clips(rig);
  const Affine t(Eigen::Matrix3d(s * r));
  auto child = [s](Affine a) {
    a.translation() *= s;
    return a;
  };
  auto root = [&](const Affine& a) { return Affine(t * a * Eigen::Scaling(1.0 / s)); };
  rig.rest = (rig.rest.cast<double>() * (s * r).transpose()).cast<float>();
  for (Joint& j : rig.joints) j.rest_local = j.parent < 0 ? root(j.rest_local) : child(j.rest_local);
  const std::vector<Affine> world = world_transforms(rig, rest_pose(rig));
  for (std::size_t j = 0; j < world.size(); ++j) rig.joints[j].inverse_bind = world[j].inverse(Eigen::Affine);
  for (Clip& c : rig.clips)
    for (Pose& pose : c.local)
      for (std::size_t j = 0; j < pose.size(); ++j)
        pose[j] = rig.joints[j].parent < 0 ? root(pose[j]) : child(pose[j]);
  return rig;
}

// Counts identical; relative metrics within `tolerance`.
void check_same_skinning(const BakeResult& a, const BakeResult& b, double volume_scale, double tolerance) {
  REQUIRE(a.stats.size() == b.stats.size());
  for (std::size_t f = 0; f < a.stats.size(); ++f) {
    const FrameMetrics& x = a.stats[f].metrics;
    const FrameMetrics& y = b.stats[f].metrics;
    INFO("frame " << f);
    CHECK(x.self_intersections == y.self_intersections);
    CHECK(x.inverted_triangles == y.inverted_triangles);
    CHECK(x.new_inverted_triangles == y.new_inverted_triangles);
    CHECK(x.contact_vertices == y.contact_vertices);
    CHECK(y.volume == Approx(x.volume * volume_scale).epsilon(tolerance));
    CHECK(y.volume_ratio == Approx(x.volume_ratio).epsilon(tolerance));
    CHECK(y.edge_distortion_mean == Approx(x.edge_distortion_mean).margin(tolerance));
    CHECK(y.edge_distortion_max == Approx(x.edge_distortion_max).margin(tolerance));
    CHECK(y.rest_distance == Approx(x.rest_distance).margin(tolerance));
    CHECK(y.iso_residual_max == Approx(x.iso_residual_max).margin(tolerance));
  }
  CHECK(b.rest_recovery == Approx(a.rest_recovery).margin(tolerance));
}

}  // namespace

TEST_CASE("rig_load: units and axes: a rig scaled by 2^-10 and 2^10 and a z-up copy skin the same",
          "[skinning][io][units]") {
  const Rig rig = clip_capsule();
  Scratch dir("units");
  const Eigen::Matrix3d z_up =
      Eigen::AngleAxisd(isokit::kPi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix().array().round();
  struct Copy {
    const char* name;
    double scale;
    Eigen::Matrix3d axes;
  };
  const std::vector<Copy> copies = {{"milli.glb", std::ldexp(1.0, -10), Eigen::Matrix3d::Identity()},
                                    {"kilo.glb", std::ldexp(1.0, 10), Eigen::Matrix3d::Identity()},
                                    {"zup.glb", 1.0, z_up}};
  save_rig(rig, dir / "base.glb");
  const Rig base = load_rig(dir / "base.glb");
  auto bend = [](const Rig& r) { return bend_animation(r, {parse_bend("Bone1:x:120", r)}, 5); };
  const Method method = GENERATE(Method::kDqs, Method::kImplicit2013, Method::kTracking2014);
  INFO(to_string(method));
  Skinner reference(base);
  const BakeResult expected = reference.bake(method, bend(base));
  for (const Copy& c : copies) {
    INFO(c.name);
    save_rig(similar_rig(rig, c.scale, c.axes), dir / c.name);
    const Rig copy = load_rig(dir / c.name);
    REQUIRE(copy.rest.rows() == base.rest.rows());
    Skinner skinner(copy);
    // Known limit: the 2014 tracker turns the float rounding of the z-up copy's joint frames
    // (a 90° quaternion is not exact in float) into differences of ~1e-4 – 1e-3 in its continuous
    // metrics (counts stay identical; 1.1e-3 in the largest edge distortion since the smoothed
    // vertices are re-projected). The same rounding moves a fixed16 grid node across a rounding
    // boundary now and then: one step, 1/32767 of the field, so ~3e-5 in implicit2013's metrics.
    // Scaled copies are exact (a power of two scales the nodes and their scale alike).
    const bool rotated = c.scale == 1.0;
    const double tolerance = !rotated                          ? 1e-6
                             : method == Method::kTracking2014 ? 2e-3
                             : method == Method::kImplicit2013 ? 1e-4
                                                               : 1e-6;
    check_same_skinning(expected, skinner.bake(method, bend(copy)), c.scale * c.scale * c.scale, tolerance);
  }
}

TEST_CASE("rig_load: the shared rigs named by ISOKIT_SHARED_DATA load, jog.fbx plays on arnaud.fbx",
          "[skinning][io][samples]") {
  const char* folder = std::getenv("ISOKIT_SHARED_DATA");
  if (folder == nullptr) return;  // optional: only where the shared data folder exists
  const std::filesystem::path root(folder);
  for (const auto& dir : {root, root / "rigs"}) {
    if (!std::filesystem::is_directory(dir)) continue;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      const std::string ext = entry.path().extension().string();
      if (ext != ".glb" && ext != ".gltf" && ext != ".fbx") continue;
      if (entry.path().filename() == "jog.fbx") continue;  // animation only: below
      INFO(entry.path().string());
      LoadReport report;
      const Rig rig = load_rig(entry.path().string(), {}, &report);
      CHECK(rig.rest.rows() > 0);
      CHECK_NOTHROW(validate(rig));
    }
  }
  const std::string arnaud = (root / "rigs" / "arnaud.fbx").string();
  const std::string jog = (root / "rigs" / "jog.fbx").string();
  if (!std::filesystem::exists(arnaud) || !std::filesystem::exists(jog)) return;
  const Rig rig = load_rig(arnaud);
  AnimationRequest request;
  request.clip_file = jog;
  const Animation a = make_animation(rig, request);
  REQUIRE(a.poses.size() > 10);
  const double diag = (rig.rest.colwise().maxCoeff() - rig.rest.colwise().minCoeff()).norm();
  for (const Pose& pose : a.poses) {
    const track::Positions p = skin_lbs(rig, pose);
    REQUIRE(p.allFinite());
    CHECK((p.colwise().maxCoeff() - p.colwise().minCoeff()).norm() < 2 * diag);
  }
}
