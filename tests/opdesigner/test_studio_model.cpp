// SPDX-License-Identifier: MIT
// The studio model (isokit-opdesigner gui) driven without a window: edits, background solving,
// undo/redo, files. Resolution 32 with 32 slices keeps every case at a few seconds.
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <thread>

#include "isokit/core/error.h"
#include "isokit/operators/io.h"
#include "isokit/studio/model.h"

using namespace isokit;
using namespace isokit::operators;
using namespace isokit::studio;

namespace {

// Schur (edit band) against a fresh generate(): the schemes agree to this margin
// (test_biharmonic.cpp, "schemes ... agree").
constexpr double kSchemeMargin = 1e-5;

OperatorSpec small_spec(const std::string& preset) {
  OperatorSpec spec = preset_spec(preset, 32);
  spec.slices = 32;
  return spec;
}

StudioOptions test_options() {
  StudioOptions o;
  o.recent_files_path = "";  // never the user's preferences
  return o;
}

std::filesystem::path temp_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("isokit-studio-" + name + "-" + std::to_string(std::random_device{}()));
  std::filesystem::create_directories(dir);
  return dir;
}

// Largest |a - b| over slice k.
double slice_difference(const float* a, const float* b, int nf) {
  double worst = 0;
  for (int i = 0; i < nf * nf; ++i) worst = std::max(worst, double(std::abs(a[i] - b[i])));
  return worst;
}

// The invariant of a fully solved model: its grid is generate() of its spec.
void check_grid_is_generated(StudioModel& model) {
  model.wait_until_solved();
  REQUIRE(model.fully_solved());
  const GridOperator ref = generate_operator(model.spec());
  const GridOperator& grid = model.grid();
  REQUIRE(grid.nd() == ref.nd());
  for (int k = 0; k < ref.nd(); ++k) {
    INFO("slice " << k);
    CHECK(slice_difference(grid.slice(k), ref.slice(k), ref.nf()) <= kSchemeMargin);
  }
}

// The displayed slice against a fresh solve of the current spec.
void check_displayed_is_current(const StudioModel& model) {
  BiharmonicOperatorGenerator fresh(model.spec());
  const std::vector<float> ref = fresh.solve_slice(model.d());
  CHECK(model.slice_solved(model.slice()));
  CHECK(slice_difference(model.slice_values(), ref.data(), model.spec().resolution) <= kSchemeMargin);
}

// Slices whose control points differ (an independent reading of the model's rule).
std::vector<int> profile_changes(const OperatorSpec& a, const OperatorSpec& b) {
  std::vector<int> out;
  for (int k = 0; k < a.slices; ++k) {
    const double d = double(k) / (a.slices - 1);
    for (std::size_t c = 0; c < a.curves.size(); ++c)
      if (a.curves[c].control_points(d) != b.curves[c].control_points(d)) {
        out.push_back(k);
        break;
      }
  }
  return out;
}

// The contact line's end point (curve 1, last point) of the "contact" preset.
CurvePoint contact_end(const StudioModel& model) {
  return CurvePoint{1, int(model.spec().curves[1].keyframes[0].points.size()) - 1};
}

}  // namespace

TEST_CASE("studio: a new model is solved in the background to generate()", "[studio]") {
  for (const char* preset : {"contact", "bulge"}) {
    StudioModel model(small_spec(preset), test_options());
    CHECK(model.slice() == 0);
    CHECK(model.slice_solved(0));
    check_grid_is_generated(model);
    CHECK(model.progress().total == 0);
    CHECK(!model.can_undo());
    CHECK(!model.modified());
  }
}

TEST_CASE("studio: a drag re-solves the displayed slice at once and the changed ones behind", "[studio]") {
  StudioModel model(small_spec("contact"), test_options());
  model.wait_until_solved();
  const OperatorSpec before = model.spec();
  const std::vector<float> grid_before = model.grid().data();
  model.set_d(0.52);  // snaps to slice 16 (d = 16/31)
  CHECK(model.slice() == 16);
  CHECK(model.d() == Approx(16.0 / 31));
  const CurvePoint end = contact_end(model);
  const Point2 start = model.control_points(end.curve)[std::size_t(end.point)];
  CHECK(model.pick({start[0] + 0.01, start[1]}, 0.02) == std::optional<CurvePoint>(end));
  REQUIRE(model.begin_drag(end));
  for (int i = 1; i <= 5; ++i) {
    REQUIRE(model.drag_to({start[0] + 0.01 * i, start[1] - 0.005 * i}));
    check_displayed_is_current(model);
  }
  model.end_drag();
  // Keyframe semantics: the drag inserted a keyframe at the slice's d, between d = 0 and 1.
  const auto& keyframes = model.spec().curves[1].keyframes;
  REQUIRE(keyframes.size() == 3);
  CHECK(keyframes[1].d == Approx(16.0 / 31));
  CHECK(keyframes[1].points.back()[0] == Approx(start[0] + 0.05));
  check_grid_is_generated(model);
  const std::vector<int> changed = profile_changes(before, model.spec());
  CHECK(changed.size() > 20);  // the profile is interpolated over d: one edit changes most slices
  const int nn = 32 * 32;
  for (int k = 0; k < 32; ++k)
    if (std::find(changed.begin(), changed.end(), k) == changed.end())
      CHECK(std::equal(grid_before.begin() + k * nn, grid_before.begin() + (k + 1) * nn,
                       model.grid().slice(k)));
  // One drag, one undo step; undo and redo restore spec and grid bit for bit.
  const OperatorSpec after = model.spec();
  const std::vector<float> grid_after = model.grid().data();
  REQUIRE(model.undo());
  CHECK(!model.can_undo());
  CHECK(model.spec() == before);
  model.wait_until_solved();
  CHECK(model.grid().data() == grid_before);
  REQUIRE(model.redo());
  CHECK(model.spec() == after);
  model.wait_until_solved();
  CHECK(model.grid().data() == grid_after);
}

TEST_CASE("studio: dragging at an existing keyframe moves it, undo before the background ends", "[studio]") {
  StudioOptions o = test_options();
  o.background_thread = GENERATE(true, false);  // false: queued slices wait for the undo
  INFO("background thread " << o.background_thread);
  StudioModel model(small_spec("contact"), o);
  model.wait_until_solved();
  const OperatorSpec original = model.spec();
  const std::vector<float> original_grid = model.grid().data();
  model.set_d(1.0);
  const CurvePoint end = contact_end(model);
  REQUIRE(model.begin_drag(end));
  REQUIRE(model.drag_to({0.8, 0.82}));
  model.end_drag();
  CHECK(model.spec().curves[1].keyframes.size() == 2);  // moved the keyframe at d = 1
  CHECK(model.spec().curves[1].keyframes[1].points.back() == Point2{0.8, 0.82});
  // A second edit while the first is still being solved, then undo both.
  model.set_d(0.5);
  REQUIRE(model.begin_drag(end));
  REQUIRE(model.drag_to({0.6, 0.65}));
  model.end_drag();
  check_displayed_is_current(model);
  REQUIRE(model.undo());
  REQUIRE(model.undo());
  CHECK(model.spec() == original);
  model.wait_until_solved();
  CHECK(model.grid().data() == original_grid);
  CHECK(model.can_redo());
}

TEST_CASE("studio: invalid edits are refused and change nothing", "[studio]") {
  StudioModel model(small_spec("contact"), test_options());
  model.wait_until_solved();
  const OperatorSpec spec = model.spec();
  const std::vector<float> grid = model.grid().data();
  auto unchanged = [&] {
    CHECK(model.spec() == spec);
    CHECK(model.grid().data() == grid);
    CHECK(!model.can_undo());
  };
  // The boundary's corner onto the f1 = 0 axis (g(0, f2) = f2 there): refused.
  REQUIRE(model.begin_drag({0, 1}));
  const EditResult r = model.drag_to({-0.3, 0.2});  // clamped to (0, 0.2), still invalid
  CHECK(!r);
  CHECK_THAT(r.message, Catch::Contains("axis"));
  model.end_drag();
  unchanged();
  // Below the minimum number of points, a missing curve, the last boundary curve.
  CHECK(!model.delete_point({1, 0}));  // the contact polyline has the minimum, 2
  CHECK(!model.delete_point({7, 0}));
  CHECK(!model.delete_curve(0));
  CHECK(!model.add_point(0, 5));
  CHECK(!model.delete_knot(0));
  CHECK(!model.add_curve(CurveKind::kContact, CurveType::kPolyline, {{0.3, 0.3}, {1.5, 0.3}}));
  CHECK(!model.begin_drag({0, 9}));
  CHECK(!model.drag_to({0.4, 0.4}));
  unchanged();
}

TEST_CASE("studio: point, keyframe and curve edits keep the grid generated", "[studio]") {
  StudioModel model(small_spec("contact"), test_options());
  model.wait_until_solved();
  // Points: a point on every keyframe at the interpolated position.
  REQUIRE(model.add_point(0, 0, 0.5));
  CHECK(model.selection() == std::optional<CurvePoint>(CurvePoint{0, 1}));
  CHECK(model.spec().curves[0].keyframes[0].points[1] == Point2{0.25, 0.5});
  REQUIRE(model.begin_drag({0, 1}));
  REQUIRE(model.drag_to({0.25, 0.45}));
  model.end_drag();
  check_displayed_is_current(model);
  REQUIRE(model.delete_point({0, 1}));
  // A keyframe at the displayed d, refused twice; a second contact curve, then deleted.
  model.set_slice(10);
  REQUIRE(model.add_keyframe(1));
  CHECK(!model.add_keyframe(1));
  REQUIRE(model.add_curve(CurveKind::kContact, CurveType::kPolyline, {{0.2, 0.7}, {0.3, 0.8}}));
  check_displayed_is_current(model);
  check_grid_is_generated(model);
  REQUIRE(model.delete_curve(2));
  REQUIRE(model.delete_keyframe(1, 1));
  check_grid_is_generated(model);
  CHECK(model.can_undo());
}

TEST_CASE("studio: controller knots", "[studio]") {
  StudioModel model(small_spec("contact"), test_options());
  model.wait_until_solved();
  const std::vector<float> grid = model.grid().data();
  const auto preset = model.controller_knots();
  REQUIRE(preset.size() >= 2);
  REQUIRE(model.add_knot(1.0, 0.2));
  auto knots = model.controller_knots();
  CHECK(knots.size() == preset.size() + 1);
  REQUIRE(model.move_knot(0, 0.7, 0.1));  // the first knot keeps α = 0
  CHECK(model.controller_knots().front().alpha == 0.0);
  CHECK(model.controller_knots().front().d == 0.1);
  CHECK(!model.move_knot(0, 0.0, 1.5));  // d outside [0, 1]
  CHECK(!model.delete_knot(int(knots.size()) - 1));
  CHECK(!model.add_knot(4.0, 0.5));
  CHECK(model.grid().data() == grid);  // the controller is not part of the grid
  REQUIRE(model.undo());
  REQUIRE(model.undo());
  CHECK(model.spec().controller_knots.empty());
  CHECK(model.grid().data() == grid);
}

TEST_CASE("studio: undo depth is bounded", "[studio]") {
  StudioOptions o = test_options();
  o.undo_depth = 2;
  StudioModel model(small_spec("clean-union"), o);
  for (int i = 0; i < 3; ++i) REQUIRE(model.add_knot(0.5 + 0.5 * i, 0.3));
  CHECK(model.undo());
  CHECK(model.undo());
  CHECK(!model.undo());
  CHECK(model.spec().controller_knots.size() == 3);  // the preset's two plus the first add
  // By memory: two drags of ~30 changed slices (4 KiB each) do not fit in 0.1 MiB.
  o.undo_depth = 100;
  o.undo_memory_mib = 0.1;
  StudioModel bounded(small_spec("contact"), o);
  bounded.set_d(0.5);
  for (double x : {0.7, 0.72}) {
    REQUIRE(bounded.begin_drag({1, 1}));
    REQUIRE(bounded.drag_to({x, 0.7}));
    bounded.end_drag();
  }
  CHECK(bounded.undo());
  CHECK(!bounded.undo());
  o.undo_memory_mib = 0;
  CHECK_THROWS_AS(StudioModel(small_spec("contact"), o), InputError);
}

TEST_CASE("studio: new document and rename", "[studio]") {
  StudioModel model(small_spec("contact"), test_options());
  REQUIRE(model.rename("mine"));
  CHECK(model.spec().name == "mine");
  CHECK(model.modified());
  REQUIRE(model.undo());
  CHECK(model.spec().name == small_spec("contact").name);
  CHECK_THROWS_AS(model.new_document(OperatorSpec{}), InputError);  // no curves
  CHECK(model.spec().curves.size() == 2);
  model.new_document(small_spec("bulge"));
  CHECK(model.spec() == small_spec("bulge"));
  CHECK(model.document_path().empty());
  CHECK(!model.can_undo());
  check_grid_is_generated(model);
}

TEST_CASE("studio: save, open, export and recent files", "[studio]") {
  const auto dir = temp_dir("files");
  StudioOptions o = test_options();
  o.recent_files_path = (dir / "config" / "recent.json").string();
  StudioModel model(small_spec("contact"), o);
  REQUIRE(model.add_knot(1.0, 0.25));
  CHECK(model.modified());
  const std::string spec_path = (dir / "edited.json").string();
  model.save_spec(spec_path);
  CHECK(!model.modified());
  CHECK(load_spec(spec_path) == model.spec());
  int calls = 0;
  const std::string npy = (dir / "edited.npy").string();
  model.export_grid(npy, [&](int done, int total) {
    ++calls;
    CHECK(done <= total);
  });
  CHECK(calls > 0);
  const StoredOperator stored = load_operator(npy);
  CHECK(stored.spec == model.spec());
  CHECK(stored.grid.data() == model.grid().data());
  // Open replaces the document; a bad file leaves it as it was.
  StudioModel other(small_spec("bulge"), o);
  other.open(spec_path);
  CHECK(other.spec() == model.spec());
  CHECK(other.document_path() == spec_path);
  CHECK(!other.can_undo());
  CHECK_THROWS_AS(other.open((dir / "missing.json").string()), InputError);
  CHECK(other.spec() == model.spec());
  // open_file: the same model as open() on another document, without that first document.
  const std::unique_ptr<StudioModel> opened = StudioModel::open_file(spec_path, o);
  CHECK(opened->spec() == model.spec());
  CHECK(opened->document_path() == spec_path);
  CHECK(!opened->modified());
  CHECK_THROWS_AS(StudioModel::open_file((dir / "missing.json").string(), o), InputError);
  const RecentFiles reread((dir / "config" / "recent.json").string());
  REQUIRE(!reread.files().empty());
  CHECK(std::filesystem::equivalent(reread.files().front(), spec_path));
  std::filesystem::remove_all(dir);
}

namespace {

// One random edit at a random slice: a drag of a few moves, a point added or deleted, a
// keyframe, a knot, an undo or a redo (some are refused; the invariants hold either way).
void random_edit(StudioModel& model, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-0.04, 0.04);
  model.set_slice(int(rng() % unsigned(model.spec().slices)));
  const auto& curves = model.spec().curves;
  const int c = int(rng() % curves.size());
  const int n = int(curves[std::size_t(c)].keyframes[0].points.size());
  switch (rng() % 8) {
    case 0:
    case 1: {
      const CurvePoint p{c, int(rng() % unsigned(n))};
      const Point2 q = model.control_points(c)[std::size_t(p.point)];
      REQUIRE(model.begin_drag(p));
      for (int m = 1; m <= 3; ++m) model.drag_to({q[0] + m * u(rng), q[1] + m * u(rng)});
      model.end_drag();
      break;
    }
    case 2:
      model.add_point(c, int(rng() % unsigned(n - 1)), 0.3);
      break;
    case 3:
      model.delete_point({c, int(rng() % unsigned(n))});
      break;
    case 4:
      model.add_keyframe(c);
      break;
    case 5:
      model.add_knot(0.2 + 2.7 * std::abs(u(rng)) / 0.04, 0.5);
      break;
    case 6:
      model.undo();
      break;
    default:
      model.redo();
      break;
  }
}

}  // namespace

TEST_CASE("studio: random edits keep the solved grid equal to generate(spec)", "[studio]") {
  for (unsigned seed = 1; seed <= 6; ++seed) {
    INFO("seed " << seed);
    std::mt19937 rng(seed);
    StudioOptions o = test_options();
    o.background_thread = seed <= 4;  // and without: every queued slice waits for undo/redo/wait
    StudioModel model(small_spec(seed % 2 ? "contact" : "bulge"), o);
    model.wait_until_solved();
    const OperatorSpec first = model.spec();
    const std::vector<float> first_grid = model.grid().data();
    for (int step = 0; step < 8; ++step) {
      random_edit(model, rng);
      check_displayed_is_current(model);
    }
    check_grid_is_generated(model);
    // Undo everything, then redo everything: both ends bit for bit.
    const OperatorSpec last = model.spec();
    const std::vector<float> last_grid = model.grid().data();
    int steps = 0;
    while (model.undo()) ++steps;
    model.wait_until_solved();
    CHECK(model.spec() == first);
    CHECK(model.grid().data() == first_grid);
    for (int i = 0; i < steps; ++i) REQUIRE(model.redo());
    model.wait_until_solved();
    CHECK(model.spec() == last);
    CHECK(model.grid().data() == last_grid);
  }
}

TEST_CASE("studio: live checks of the displayed slice mark where the iso-line leaves the profile",
          "[studio]") {
  StudioModel model(small_spec("contact"), test_options());
  model.set_d(0.5);
  const LiveCheck& good = model.live_check();
  CHECK(good.current);
  CHECK(good.report.slice == model.slice());
  CHECK(!good.failure);
  CHECK(good.stray_crossings.empty());
  CHECK(good.unmatched_profile.empty());
  // The boundary pulled off the f2 axis: the 0.5 iso-line must still reach (0, 0.5) (eq. 1), away
  // from the profile the designer drew.
  REQUIRE(model.begin_drag({0, 0}));
  REQUIRE(model.drag_to({0.3, 0.5}));
  model.end_drag();
  const LiveCheck& bad = model.live_check();
  REQUIRE(bad.failure);
  CHECK(bad.failure->slice == model.slice());
  CHECK(!bad.stray_crossings.empty());
  for (const Point2& p : bad.stray_crossings) CHECK(p[0] < 0.3);  // between the axis and the profile
}

TEST_CASE("studio: a drag out of the edit band re-centres the band on the new profile", "[studio]") {
  StudioModel model(small_spec("contact"), test_options());
  model.set_d(1.0);
  REQUIRE(model.begin_drag({1, 1}));
  REQUIRE(model.drag_to({0.15, 0.9}));  // far from every slice's contact line: > 3 cells
  CHECK(!model.last_solve_was_schur());
  check_displayed_is_current(model);
  model.end_drag();
  CHECK(model.recentring());
  check_grid_is_generated(model);
  CHECK(!model.recentring());
  REQUIRE(model.begin_drag({1, 1}));
  REQUIRE(model.drag_to({0.16, 0.9}));
  CHECK(model.last_solve_was_schur());
  model.end_drag();
  check_displayed_is_current(model);
  check_grid_is_generated(model);
  REQUIRE(model.undo());
  REQUIRE(model.undo());
  CHECK(model.spec() == small_spec("contact"));
  check_grid_is_generated(model);
}

TEST_CASE("studio: at the real resolution (128²) drags are Schur solves and the grid is generated",
          "[studio][slow]") {
  OperatorSpec spec = preset_spec("bulge", 128);
  spec.slices = 16;
  StudioModel model(spec, test_options());
  model.set_d(0.6);
  REQUIRE(model.begin_drag({1, 1}));
  const Point2 q = model.control_points(1)[1];
  for (int i = 1; i <= 3; ++i) {
    REQUIRE(model.drag_to({q[0] + 0.003 * i, q[1]}));
    CHECK(model.last_solve_was_schur());
  }
  model.end_drag();
  check_displayed_is_current(model);
  check_grid_is_generated(model);
  REQUIRE(model.undo());
  model.wait_until_solved();
  CHECK(model.spec() == spec);
}

TEST_CASE("studio: recent files are most recent first, bounded, and survive a broken file", "[studio]") {
  const auto dir = temp_dir("recent");
  const std::string path = (dir / "isokit" / "recent.json").string();
  {
    RecentFiles recent(path, 3);
    for (const char* f : {"a.json", "b.json", "c.json", "a.json", "d.json"}) recent.add((dir / f).string());
    CHECK(recent.last_error().empty());
    REQUIRE(recent.files().size() == 3);
    CHECK(std::filesystem::path(recent.files()[0]).filename() == "d.json");
    CHECK(std::filesystem::path(recent.files()[1]).filename() == "a.json");
    recent.remove(recent.files()[1]);
  }
  CHECK(RecentFiles(path, 3).files().size() == 2);
  CHECK(RecentFiles(path, 1).files().size() == 1);
  { std::ofstream(path) << "{ not json"; }
  CHECK(RecentFiles(path).files().empty());
  CHECK(RecentFiles("").files().empty());
  std::filesystem::remove_all(dir);
}

TEST_CASE("studio: the smallest grids (resolution 8, the edit band covers everything) work", "[studio]") {
  for (int res : {8, 9, 12}) {
    OperatorSpec spec = preset_spec("contact", res);
    spec.slices = res;
    INFO("resolution " << res);
    StudioModel model(spec, test_options());
    check_grid_is_generated(model);
    model.set_d(0.5);
    const CurvePoint end = contact_end(model);
    const Point2 start = model.control_points(end.curve)[std::size_t(end.point)];
    REQUIRE(model.begin_drag(end));
    REQUIRE(model.drag_to({start[0] + 0.02, start[1]}));
    check_displayed_is_current(model);
    model.end_drag();
    check_grid_is_generated(model);
  }
}

TEST_CASE("studio: the background pauses during a drag and resumes after it", "[studio]") {
  StudioModel model(small_spec("contact"), test_options());
  model.wait_until_solved();
  model.set_d(0.5);
  const CurvePoint end = contact_end(model);
  const Point2 start = model.control_points(end.curve)[std::size_t(end.point)];
  REQUIRE(model.begin_drag(end));
  for (int i = 1; i <= 3; ++i) REQUIRE(model.drag_to({start[0] + 0.01 * i, start[1]}));
  const int queued = model.progress().total;
  REQUIRE(queued > 10);
  // Paused before the first slice of the job: nothing is published however long we wait.
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  model.poll();
  CHECK(model.progress().done == 0);
  CHECK(!model.fully_solved());
  model.end_drag();  // resumes
  const auto t0 = std::chrono::steady_clock::now();
  while (!model.fully_solved() && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60)) {
    model.poll();
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  CHECK(model.fully_solved());
  check_grid_is_generated(model);
  // wait_until_solved() during a drag does not hang: it lets the background run meanwhile.
  REQUIRE(model.begin_drag(end));
  REQUIRE(model.drag_to({start[0] + 0.04, start[1] + 0.01}));
  model.wait_until_solved();
  CHECK(model.fully_solved());
  CHECK(model.dragging());
  model.end_drag();
  check_grid_is_generated(model);
}

TEST_CASE("studio: a knot drag is one undo step", "[studio]") {
  StudioModel model(small_spec("contact"), test_options());
  model.wait_until_solved();
  const std::vector<float> grid = model.grid().data();
  const auto knots = model.controller_knots();
  REQUIRE(knots.size() >= 3);
  const int i = 1;
  const double a0 = knots[i].alpha, d0 = knots[i].d;
  const double lo = knots[i - 1].alpha, hi = knots[i + 1].alpha;
  CHECK(!model.drag_knot_to(a0, 0.5));  // no drag in progress
  CHECK(!model.begin_knot_drag(int(knots.size())));
  REQUIRE(model.begin_knot_drag(i));
  CHECK(model.dragging_knot());
  CHECK(!model.dragging());
  for (int s = 1; s <= 10; ++s) {
    const double a = a0 + (hi - a0) * 0.04 * s, d = std::clamp(d0 + 0.02 * s, 0.0, 1.0);
    REQUIRE(model.drag_knot_to(a, d));
    CHECK(model.controller_knots()[i].alpha == Approx(a));
    CHECK(model.controller_knots()[i].d == Approx(d));
  }
  const auto moved = model.controller_knots();
  CHECK(!model.drag_knot_to(hi + 0.01, 0.5));  // would pass the neighbour: refused, stays
  CHECK(!model.drag_knot_to(lo - 0.01, 0.5));
  CHECK(model.controller_knots()[i].alpha == moved[i].alpha);
  model.end_drag();
  CHECK(!model.dragging_knot());
  CHECK(model.grid().data() == grid);  // the controller is not part of the grid
  REQUIRE(model.can_undo());
  REQUIRE(model.undo());
  CHECK(!model.can_undo());  // ten moves, one step
  CHECK(model.spec().controller_knots.empty());
  CHECK(model.controller_knots()[i].alpha == a0);
  REQUIRE(model.redo());
  CHECK(model.controller_knots()[i].alpha == moved[i].alpha);
  // A drag that moved nothing leaves no step; a point drag ends a knot drag.
  REQUIRE(model.begin_knot_drag(i));
  REQUIRE(model.begin_drag(contact_end(model)));
  CHECK(!model.dragging_knot());
  model.end_drag();
  REQUIRE(model.undo());
  CHECK(!model.can_undo());
}

TEST_CASE("studio: revision() changes exactly when the spec or the grid changes", "[studio]") {
  StudioModel model(small_spec("contact"), test_options());
  model.wait_until_solved();
  long r = model.revision();
  auto changed = [&] {
    const long now = model.revision();
    const bool c = now != r;
    CHECK(now >= r);
    r = now;
    return c;
  };
  // Queries, selection, idle polls, refused edits and showing a solved slice change nothing.
  model.poll();
  (void)model.pick({0.5, 0.5}, 0.05);
  model.select(CurvePoint{0, 1});
  model.set_slice(5);
  (void)model.live_check();
  CHECK(!model.add_knot(4.0, 0.5));
  CHECK(!model.delete_curve(0));
  CHECK(!changed());
  const long shown = model.slice_revision(5);
  // An edit of the controller changes the spec only.
  REQUIRE(model.add_knot(1.0, 0.3));
  CHECK(changed());
  CHECK(model.slice_revision(5) == shown);
  REQUIRE(model.rename("renamed"));
  CHECK(changed());
  // A drag step: the displayed slice is re-solved now (its slice revision moves too).
  const CurvePoint end = contact_end(model);
  const Point2 start = model.control_points(end.curve)[std::size_t(end.point)];
  REQUIRE(model.begin_drag(end));
  CHECK(!changed());
  REQUIRE(model.drag_to({start[0] + 0.01, start[1]}));
  CHECK(changed());
  CHECK(model.slice_revision(5) > shown);
  model.end_drag();
  // Background slices published by poll(): each poll that publishes changes it.
  while (!model.fully_solved()) {
    const int before = model.progress().done;
    model.poll();
    const bool published = model.fully_solved() || model.progress().done != before;
    CHECK(changed() == published);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  model.poll();
  CHECK(!changed());
  REQUIRE(model.undo());
  CHECK(changed());
  model.wait_until_solved();
  changed();
  REQUIRE(model.redo());
  CHECK(changed());
  model.new_document(small_spec("bulge"));
  CHECK(changed());
}

TEST_CASE("studio: pick prefers the nearest point, then the selected curve, then boundary curves",
          "[studio]") {
  StudioModel model(small_spec("contact"), test_options());
  model.set_d(0.0);
  // At d = 0 the contact line has length 0: both its points lie on the boundary corner.
  const Point2 corner = model.control_points(0)[1];
  const auto contact = model.control_points(1);
  REQUIRE(contact.size() == 2);
  REQUIRE(std::hypot(contact[1][0] - corner[0], contact[1][1] - corner[1]) < 1e-9);
  CHECK(model.pick(corner, 0.05) == std::optional<CurvePoint>(CurvePoint{0, 1}));
  CHECK(model.pick({corner[0] + 0.01, corner[1] - 0.01}, 0.05) ==
        std::optional<CurvePoint>(CurvePoint{0, 1}));
  // The selected curve wins a tie (so the contact end can be dragged out of the corner) ...
  model.select(CurvePoint{1, 1});
  CHECK(model.pick(corner, 0.05) == std::optional<CurvePoint>(CurvePoint{1, 1}));
  model.select(CurvePoint{1, 0});
  CHECK(model.pick(corner, 0.05) == std::optional<CurvePoint>(CurvePoint{1, 0}));
  // ... but never against a nearer point.
  const Point2 other = model.control_points(0)[0];
  CHECK(model.pick({other[0] + 0.001, other[1]}, 0.05) == std::optional<CurvePoint>(CurvePoint{0, 0}));
  CHECK(!model.pick({corner[0] + 0.2, corner[1] + 0.2}, 0.05));
  // Away from d = 0 the contact end is its own point and the nearest one is picked.
  model.select(std::nullopt);
  model.set_d(1.0);
  const Point2 end = model.control_points(1)[1];
  CHECK(model.pick(end, 0.02) == std::optional<CurvePoint>(CurvePoint{1, 1}));
}
