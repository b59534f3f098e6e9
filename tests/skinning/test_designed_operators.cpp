// SPDX-License-Identifier: MIT
// Operators designed by users in skinning (issue 20): the setup keys operators.contact_spec,
// operators.bulge_spec and joints.NAME.spec, the check that refuses a failing spec, and
// isokit-skin end to end with a spec, a temporary XDG_CACHE_HOME and the disk cache.
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "isokit/core/error.h"
#include "isokit/core/math.h"
#include "isokit/operators/cache.h"
#include "isokit/operators/spec.h"
#include "isokit/skinning/animation.h"
#include "isokit/skinning/grid_operators.h"
#include "isokit/skinning/pipeline.h"
#include "isokit/skinning/skin_field.h"
#include "isokit/track/mesh_io.h"
#include "pipeline_fixture.h"

using namespace isokit::skinning;
namespace fs = std::filesystem;
namespace ops = isokit::operators;

namespace {

/// A fresh folder, and XDG_CACHE_HOME pointing into it for the test case's lifetime.
class TempFolder {
 public:
  explicit TempFolder(const std::string& name)
      : dir_(fs::temp_directory_path() /
             ("isokit-test-designed-" + name + "-" + std::to_string(::getpid()))) {
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    const char* old = std::getenv("XDG_CACHE_HOME");
    had_ = old != nullptr;
    if (had_) old_ = old;
    ::setenv("XDG_CACHE_HOME", (dir_ / "xdg").c_str(), 1);
  }
  ~TempFolder() {
    if (had_)
      ::setenv("XDG_CACHE_HOME", old_.c_str(), 1);
    else
      ::unsetenv("XDG_CACHE_HOME");
    fs::remove_all(dir_);
  }
  const fs::path& dir() const { return dir_; }
  fs::path cache() const { return dir_ / "xdg" / "isokit" / "operators"; }

 private:
  fs::path dir_;
  bool had_{false};
  std::string old_;
};

void write_text(const fs::path& p, const std::string& text) {
  std::ofstream(p) << text;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// The contact preset with its contact line bent: at d = 1 it runs from (.5, .5) through `mid`
/// to `end` instead of straight along the diagonal to (.9, .9).
ops::OperatorSpec bent_contact(ops::Point2 mid, ops::Point2 end) {
  ops::OperatorSpec s = ops::preset_spec("contact", 32);
  s.name = "bent";
  s.slices = 32;
  for (ops::ProfileCurve& c : s.curves)
    if (c.kind == ops::CurveKind::kContact)
      c.keyframes = {{0.0, {{0.5, 0.5}, {0.5, 0.5}, {0.5, 0.5}}}, {1.0, {{0.5, 0.5}, mid, end}}};
  return s;
}

/// A boundary profile that ends off the f2 = 0 axis: valid as a spec, but its grid has a 0.5
/// iso-line the profile does not ask for (check_operator fails).
ops::OperatorSpec failing_spec() {
  ops::OperatorSpec s = ops::preset_spec("clean-union", 32);
  s.name = "broken";
  s.slices = 8;
  s.curves[0].keyframes = {{0.0, {{0, 0.5}, {0.5, 0.5}, {0.5, 0.2}}}};
  return s;
}

}  // namespace

TEST_CASE("setup: spec keys load spec files relative to the setup file", "[skinning][setup][designed]") {
  const TempFolder t("keys");
  fs::create_directories(t.dir() / "specs");
  ops::save_spec(bent_contact({0.62, 0.7}, {0.7, 0.9}), (t.dir() / "specs" / "bent.json").string());
  ops::save_spec(ops::preset_spec("bulge", 32), (t.dir() / "bulge.json").string());
  write_text(t.dir() / "s.json",
             R"({"operators": {"contact_spec": "specs/bent.json", "bulge_spec": "bulge.json"},
      "joints": {"Bone1": {"operator": "bulge", "spec": "specs/bent.json"}}})");
  const SkinSetup s = load_setup((t.dir() / "s.json").string());
  REQUIRE(s.contact_spec);
  REQUIRE(s.bulge_spec);
  CHECK(fs::equivalent(s.contact_spec->path, t.dir() / "specs" / "bent.json"));
  CHECK(s.contact_spec->spec == bent_contact({0.62, 0.7}, {0.7, 0.9}));
  CHECK(s.bulge_spec->spec.name == "bulge");
  CHECK(s.joints.at("Bone1").spec->spec.name == "bent");
  // The joint's own spec first, then the setup's per operator, else the preset.
  CHECK(s.spec_for("Bone1", JointOperator::kBulge) == &*s.joints.at("Bone1").spec);
  CHECK(s.spec_for("Bone2", JointOperator::kBulge) == &*s.bulge_spec);
  CHECK(s.spec_for("Bone2", JointOperator::kContact) == &*s.contact_spec);
  CHECK(s.spec_for("Bone2", JointOperator::kUnion) == nullptr);
  CHECK(setup_from_json("{}", "s.json").spec_for("Bone2", JointOperator::kContact) == nullptr);
  // Without a folder, a relative path is relative to the current directory: here, missing.
  CHECK_THROWS_WITH(
      setup_from_json(R"({"operators": {"contact_spec": "specs/bent.json"}})", "s.json"),
      Catch::StartsWith("s.json.operators.contact_spec: 'specs/bent.json' is not a readable file"));
  CHECK(setup_from_json(R"({"operators": {"contact_spec": "specs/bent.json"}})", "s.json", t.dir().string())
            .contact_spec->spec.name == "bent");
}

TEST_CASE("setup: bad spec keys name the key, the file and the fix", "[skinning][setup][designed]") {
  const TempFolder t("badkeys");
  ops::save_spec(ops::preset_spec("contact", 32), (t.dir() / "c.json").string());
  write_text(t.dir() / "junk.json", "{ \"format\": \"something else\" }");
  const std::string dir = t.dir().string();
  CHECK_THROWS_WITH(setup_from_json(R"({"operators": {"bulge_spec": "missing.json"}})", "s.json", dir),
                    Catch::StartsWith("s.json.operators.bulge_spec: ") && Catch::Contains("missing.json"));
  CHECK_THROWS_WITH(setup_from_json(R"({"operators": {"contact_spec": "junk.json"}})", "s.json", dir),
                    Catch::StartsWith("s.json.operators.contact_spec: ") && Catch::Contains("junk.json"));
  CHECK_THROWS_WITH(setup_from_json(R"({"operators": {"contact_spec": "."}})", "s.json", dir),
                    Catch::Contains("is not a readable file"));  // a folder
  CHECK_THROWS_WITH(setup_from_json(R"({"operators": {"contact_spec": ""}})", "s.json", dir),
                    Catch::Contains("s.json.operators.contact_spec: is empty"));
  CHECK_THROWS_WITH(setup_from_json(R"({"operators": {"contact_spec": 3}})", "s.json", dir),
                    Catch::Contains("s.json.operators.contact_spec: wrong type"));
  SECTION("a joint spec needs a contact or bulge joint") {
    CHECK_THROWS_WITH(
        setup_from_json(R"({"joints": {"Elbow": {"operator": "union", "spec": "c.json"}}})", "s.json", dir),
        Catch::StartsWith("s.json.joints.Elbow.spec: joint 'Elbow'") && Catch::Contains("'union'") &&
            Catch::Contains("set joints.Elbow.operator to \"contact\" or \"bulge\""));
    CHECK_THROWS_WITH(
        setup_from_json(R"({"default_operator": "blend", "joints": {"Elbow": {"spec": "c.json"}}})", "s.json",
                        dir),
        Catch::Contains("'blend' (default_operator)"));
    // "auto" resolves by tree: contact in the 2014 tree, blend in the 2013 tree.
    const SkinSetup s = setup_from_json(R"({"joints": {"Elbow": {"spec": "c.json"}}})", "s.json", dir);
    const JointOperator op2014 = s.operator_for("Elbow", TreeKind::k2014);
    CHECK(describe_joint_operator(s, "Elbow", op2014).rfind("contact (spec ", 0) == 0);
    CHECK_THROWS_WITH(describe_joint_operator(s, "Elbow", s.operator_for("Elbow", TreeKind::k2013)),
                      Catch::Contains("'blend' (as resolved for this tree)"));
  }
}

TEST_CASE("designed operators: descriptions, controllers and resolution", "[skinning][designed]") {
  const TempFolder t("describe");
  ops::OperatorSpec bent = bent_contact({0.62, 0.7}, {0.7, 0.9});
  bent.resolution = 64;  // replaced by the setup's
  bent.controller_knots = {{0.0, 0.0}, {1.0, 0.25}, {isokit::kPi, 1.0}};
  ops::save_spec(bent, (t.dir() / "bent.json").string());
  const SkinSetup s =
      setup_from_json(R"({"operators": {"resolution": 32, "slices": 16, "contact_spec": "bent.json"}})",
                      "s.json", t.dir().string());
  const ops::OperatorSpec used =
      grid_spec(s, s.spec_for("A", JointOperator::kContact), JointOperator::kContact);
  CHECK(used.resolution == 32);
  CHECK(used.slices == 16);
  const std::string hex = ops::hex_key(ops::operator_cache_key(used));
  CHECK(describe_joint_operator(s, "A", JointOperator::kContact) ==
        "contact (spec " + (t.dir() / "bent.json").string() + ", hash " + hex + ")");
  CHECK(describe_joint_operator(s, "A", JointOperator::kBulge) == "bulge (preset)");
  CHECK(describe_joint_operator(s, "A", JointOperator::kUnion) == "union");
  std::vector<std::string> lines;
  const Progress progress = [&](const std::string& stage, int, int) { lines.push_back(stage); };
  const JointGridOperator g = joint_grid_operator(s, "A", JointOperator::kContact, progress);
  CHECK(g.grid->nf() == 32);
  CHECK(g.grid->nd() == 16);
  CHECK(g.controller.eval(1.0) == Approx(0.25));  // the spec's own controller
  CHECK(fs::exists(t.cache() / ("bent-" + hex + ".npy")));
  // A preset keeps the setup's controller.
  const JointGridOperator b = joint_grid_operator(s, "A", JointOperator::kBulge, {});
  CHECK(b.controller.eval(2.0) == Approx(ops::Controller::preset(s.bulge_controller).eval(2.0)));
}

TEST_CASE("designed operators: a spec whose grid fails its check is refused in one line",
          "[skinning][designed]") {
  const TempFolder t("failing");
  ops::save_spec(failing_spec(), (t.dir() / "my_op.json").string());
  const SkinSetup s =
      setup_from_json(R"({"operators": {"resolution": 32, "slices": 8, "contact_spec": "my_op.json"}})",
                      "s.json", t.dir().string());
  const std::string path = (t.dir() / "my_op.json").string();
  for (int run = 0; run < 2; ++run) {  // generated, then from the cache: refused both times
    try {
      joint_grid_operator(s, "A", JointOperator::kContact, {});
      FAIL("a failing spec was accepted");
    } catch (const isokit::InputError& e) {
      const std::string m = e.what();
      CHECK(m.rfind(path + ": slice 0 (d = 0.000): 0.5 iso-line against the profile failed: ", 0) == 0);
      CHECK(m.find("cells from a 0.5 crossing to the profile") != std::string::npos);
      CHECK(m.find("make the boundary curve run from the f1 = 0 side") != std::string::npos);
      CHECK(m.find('\n') == std::string::npos);
    }
  }
}

TEST_CASE("designed operators: a bulge spec's controller drives its node and its bulge gate",
          "[skinning][designed]") {
  // The capsule's Bone1 as a bulge joint. The spec's controller is "constant1" (d = 1 at every
  // angle), so the gate, which caps the node by the same controller of the joint's bend, leaves
  // it at 1; the preset keeps the bulge controller (d_b(90°) = 0.5).
  const TempFolder t("bulge");
  SkinSetup setup;
  setup.operator_resolution = 32;
  setup.operator_slices = 16;
  setup.joints["Bone1"].op = JointOperator::kBulge;
  SkinSetup designed = setup;
  ops::OperatorSpec spec = ops::preset_spec("bulge", 32);
  spec.controller = "constant1";
  designed.bulge_spec = SpecFile{"test.operators.bulge_spec", "my_bulge.json", spec};
  auto max_bulge_d = [](SkinSetup s) {
    Skinner sk(testing::capsule_rig(), s);
    SkinField& field = sk.field(TreeKind::k2014);
    const auto bent = bend_animation(sk.rig(), {parse_bend("Bone1:x:90", sk.rig())}, 3)[1];
    field.set_pose(skinning_matrices(sk.rig(), bent));
    float d = -1.f;
    const auto& instr = field.program().instructions();
    for (std::size_t i = 0; i < instr.size(); ++i)
      if (instr[i].leaf < 0 && field.program().tag(i).role == isokit::implicit::NodeRole::Bulge)
        for (float v : field.pose().controller(field.program(), i).values) d = std::max(d, v);
    const std::vector<std::string> ops = field.joint_operators();
    return std::make_pair(d, ops);
  };
  const auto [preset_d, preset_ops] = max_bulge_d(setup);
  const auto [designed_d, designed_ops] = max_bulge_d(designed);
  CHECK(preset_d == Approx(0.5).margin(0.02));
  CHECK(designed_d == 1.f);
  CHECK(std::find(preset_ops.begin(), preset_ops.end(), "Bone1: bulge (preset)") != preset_ops.end());
  CHECK(std::count_if(designed_ops.begin(), designed_ops.end(), [](const std::string& o) {
          return o.rfind("Bone1: bulge (spec my_bulge.json, hash ", 0) == 0;
        }) == 1);
}

#ifdef ISOKIT_SKIN_EXE
namespace {

/// Runs isokit-skin with `args` (XDG_CACHE_HOME inherited); stdout and stderr go to `log`.
int run_skin(const std::string& args, const fs::path& log) {
  const std::string cmd =
      std::string("\"") + ISOKIT_SKIN_EXE + "\" " + args + " > \"" + log.string() + "\" 2>&1";
  return std::system(cmd.c_str());
}

/// Bakes the procedural cylinder bent to 120° over 5 frames (peak: frame 2) with `setup`,
/// writing PLY frames to `out`/ply; returns the log.
std::string bake_cylinder(const fs::path& setup, const fs::path& out) {
  const int rc = run_skin(
      "bake procedural:cylinder --method tracking2014 --bend Bone1:x:120 --frames 5 "
      "--no-self-intersections --setup \"" +
          setup.string() + "\" --out \"" + (out / "out.glb").string() + "\" --ply \"" +
          (out / "ply").string() + "\"",
      out.string() + ".log");
  const std::string log = read_text(out.string() + ".log");
  INFO(log);
  REQUIRE(rc == 0);
  return log;
}

/// Largest vertex distance between two frames, over the bounding-box diagonal of `a`.
double max_distance_over_diagonal(const fs::path& a, const fs::path& b) {
  const isokit::track::Positions pa = isokit::track::read_mesh(a.string()).vertices;
  const isokit::track::Positions pb = isokit::track::read_mesh(b.string()).vertices;
  REQUIRE(pa.rows() == pb.rows());
  const double diagonal = (pa.colwise().maxCoeff() - pa.colwise().minCoeff()).norm();
  return (pa - pb).rowwise().norm().maxCoeff() / diagonal;
}

std::vector<fs::path> cache_entries(const fs::path& dir) {
  std::vector<fs::path> out;
  if (fs::exists(dir))
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().extension() == ".npy") out.push_back(e.path());
  return out;
}

}  // namespace

TEST_CASE("isokit-skin: a designed contact operator from the setup changes the bake, and is cached",
          "[skinning][designed][cli]") {
  const TempFolder t("e2e");
  const fs::path& d = t.dir();
  ops::save_spec(bent_contact({0.62, 0.7}, {0.7, 0.9}), (d / "bent.json").string());
  write_text(d / "spec.json",
             R"({"operators": {"resolution": 32, "slices": 32, "contact_spec": "bent.json"}})");
  write_text(d / "preset.json", R"({"operators": {"resolution": 32, "slices": 32}})");
  const SkinSetup setup = load_setup((d / "spec.json").string());
  const std::string hex = ops::hex_key(ops::operator_cache_key(
      grid_spec(setup, setup.spec_for("Bone1", JointOperator::kContact), JointOperator::kContact)));
  const fs::path entry = t.cache() / ("bent-" + hex + ".npy");

  // First run: generated (progress per slice) and stored.
  const std::string first = bake_cylinder(d / "spec.json", d / "first");
  CHECK(first.find("operator bent.json: cache hit") == std::string::npos);
  CHECK(first.find("operator bent.json ") != std::string::npos);
  REQUIRE(fs::exists(entry));
  const auto stored_at = fs::last_write_time(entry);

  // Second run: a cache hit, the entry untouched, the same frames bit for bit.
  const std::string second = bake_cylinder(d / "spec.json", d / "second");
  CHECK(second.find("operator bent.json: cache hit " + entry.string()) != std::string::npos);
  CHECK(fs::last_write_time(entry) == stored_at);
  for (const char* f : {"frame_0000.ply", "frame_0002.ply", "frame_0004.ply"})
    CHECK(read_text(d / "first" / "ply" / f) == read_text(d / "second" / "ply" / f));

  // The preset's bake differs at the peak frame by more than 1e-3 of the diagonal.
  bake_cylinder(d / "preset.json", d / "preset");
  const double peak = max_distance_over_diagonal(d / "preset" / "ply" / "frame_0002.ply",
                                                 d / "first" / "ply" / "frame_0002.ply");
  WARN("peak frame, designed vs preset contact operator: max distance " << peak << " of the diagonal");
  CHECK(peak >= 1e-3);

  // A changed spec: regenerated into a new entry, the old one kept.
  ops::save_spec(bent_contact({0.6, 0.72}, {0.66, 0.92}), (d / "bent.json").string());
  const std::string third = bake_cylinder(d / "spec.json", d / "third");
  CHECK(third.find("cache hit") == std::string::npos);
  CHECK(cache_entries(t.cache()).size() == 3);  // bent (2 versions) + the contact preset
  CHECK(fs::exists(entry));

  // info --fit names the joints' operators without generating anything.
  REQUIRE(run_skin("info procedural:cylinder --fit --setup \"" + (d / "spec.json").string() + "\"",
                   d / "info.log") == 0);
  const std::string info = read_text(d / "info.log");
  INFO(info);
  CHECK(info.find("contact (spec " + (d / "bent.json").string() + ", hash ") != std::string::npos);
  CHECK(info.find("blend") != std::string::npos);  // the 2013 tree's default
}
#endif
