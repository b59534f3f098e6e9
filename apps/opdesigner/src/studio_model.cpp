// SPDX-License-Identifier: MIT
#include "isokit/studio/model.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <deque>
#include <future>
#include <limits>
#include <map>
#include <utility>

#include "isokit/core/error.h"
#include "isokit/operators/io.h"
#include "isokit/operators/profile.h"
#include "studio/background_solver.h"
#include "studio/edits.h"

namespace isokit::studio {

using operators::GridOperator;
using Clock = std::chrono::steady_clock;

namespace {

/// A dragged point stays this far inside the square's far edges, where g = 1 (2014 eq. 1).
constexpr double kEdgeMargin = 1e-6;

/// One slice's values before and after an undo step (`before_valid`: false when the slice was
/// still queued when the step began, so its old values must be re-solved on undo).
struct SliceSave {
  std::vector<float> before, after;
  bool before_valid{true};
};

/// One undo step: the specs around it and the slices it changed.
struct Step {
  OperatorSpec before, after;
  std::map<int, SliceSave> slices;
};

operators::BiharmonicOptions generator_options(const StudioOptions& o) {
  operators::BiharmonicOptions g;
  g.backend = o.backend;
  g.edit_band_cells = o.edit_band_cells;
  g.tasks = 1;
  return g;
}

EditResult refused(const std::string& why) {
  return EditResult{false, why};
}

}  // namespace

struct StudioModel::Impl {
  Impl(OperatorSpec s, const StudioOptions& o, long first_revision = 0);

  // ---- state read by the GUI thread only
  StudioOptions options;
  OperatorSpec spec;
  GridOperator grid;
  std::vector<char> solved;      // slice k holds generate(spec)'s values (up to rounding)
  std::vector<long> changed_at;  // generation of the last edit that changed slice k
  long generation{0};
  long revision{0};                  // bumped by every change of spec or grid (StudioModel::revision)
  std::vector<long> slice_rev;       // revision at which slice k's values last changed
  int pending{0}, pending_total{0};  // unsolved slices, and their number at the last post
  int slice{0};
  std::optional<CurvePoint> selection;
  std::unique_ptr<operators::BiharmonicOperatorGenerator> generator;  // GUI thread's
  // Edit band re-centring: a generator being built around a newer profile, and whether a solve
  // left the band since the last rebuild started.
  std::future<std::unique_ptr<operators::BiharmonicOperatorGenerator>> rebuilt;
  bool left_band{false};
  std::unique_ptr<detail::BackgroundSolver> background;
  double last_ms{0};
  bool last_schur{false};
  std::optional<LiveCheck> check;
  // drag in progress: a point (`dragging`) or a controller knot (`knot_dragging`)
  bool dragging{false}, knot_dragging{false}, moved{false};
  CurvePoint drag_point;
  int drag_knot{0};
  OperatorSpec drag_start;
  Step drag_step;
  // history
  std::deque<Step> undo;
  std::vector<Step> redo;
  std::string background_error;

  double slice_d(int k) const { return grid.slice_d(k); }
  double half_slice() const { return 0.5 / std::max(1, spec.slices - 1); }
  float* values(int k) { return grid.data().data() + static_cast<std::size_t>(k) * grid.nf() * grid.nf(); }

  void solve_now(int k);
  void begin_step();
  void wrote_slice(int k) { slice_rev[static_cast<std::size_t>(k)] = ++revision; }
  void mark_changed(const std::vector<int>& slices);
  void post_pending();
  void apply(OperatorSpec next, Step& step);
  void push(Step step);
  void trim_history();
  void poll();
  void wait(const ProgressFn& progress);
  void swap_slices(Step& step, bool to_before);
  void recentre_band();
  void adopt_rebuilt(bool block);
  LiveCheck compute_check();
};

StudioModel::Impl::Impl(OperatorSpec s, const StudioOptions& o, long first_revision)
    : options(o), spec(std::move(s)), revision(first_revision) {
  require(options.undo_depth >= 1, "undo_depth", "must be at least 1", "keep one undo step or more");
  require(options.undo_memory_mib > 0, "undo_memory_mib", "must be positive", "give the memory in MiB");
  operators::validate(spec, "studio");
  generator = std::make_unique<operators::BiharmonicOperatorGenerator>(spec, generator_options(options));
  grid = GridOperator(
      spec.slices, spec.resolution,
      std::vector<float>(static_cast<std::size_t>(spec.slices) * spec.resolution * spec.resolution));
  solved.assign(static_cast<std::size_t>(spec.slices), 0);
  changed_at.assign(static_cast<std::size_t>(spec.slices), 0);
  slice_rev.assign(static_cast<std::size_t>(spec.slices), 0);
  pending = spec.slices;
  if (options.background_thread)
    background = std::make_unique<detail::BackgroundSolver>(spec, generator_options(options));
  solve_now(0);
  post_pending();
}

// Starts an edit step made of several moves (a drag): they apply to `drag_start`.
void StudioModel::Impl::begin_step() {
  moved = false;
  drag_start = spec;
  drag_step = Step{};
  drag_step.before = spec;
}

// Solves slice k of the current spec on this thread.
void StudioModel::Impl::solve_now(int k) {
  const auto start = Clock::now();
  const std::vector<float> v = generator->solve_edited(slice_d(k), spec);
  last_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  last_schur = generator->last_edit_was_schur();
  left_band |= !last_schur;
  std::memcpy(values(k), v.data(), v.size() * sizeof(float));
  wrote_slice(k);
  if (!solved[static_cast<std::size_t>(k)]) --pending;
  solved[static_cast<std::size_t>(k)] = 1;
  if (k == slice) check.reset();
}

void StudioModel::Impl::mark_changed(const std::vector<int>& slices) {
  ++generation;
  for (const int k : slices) {
    changed_at[static_cast<std::size_t>(k)] = generation;
    if (solved[static_cast<std::size_t>(k)]) ++pending;
    solved[static_cast<std::size_t>(k)] = 0;
    if (k == slice) check.reset();
  }
}

// Hands every unsolved slice to the background, nearest to the displayed slice first.
void StudioModel::Impl::post_pending() {
  std::vector<int> unsolved;
  for (int k = 0; k < spec.slices; ++k)
    if (!solved[static_cast<std::size_t>(k)]) unsolved.push_back(k);
  std::stable_sort(unsolved.begin(), unsolved.end(),
                   [&](int a, int b) { return std::abs(a - slice) < std::abs(b - slice); });
  pending_total = int(unsolved.size());
  if (background && !unsolved.empty()) background->post(generation, spec, std::move(unsolved));
}

// Makes `next` (validated) the spec: records the changed slices' old values in `step`, solves
// the displayed slice now and queues the others.
void StudioModel::Impl::apply(OperatorSpec next, Step& step) {
  poll();
  const std::vector<int> changed = detail::changed_slices(spec, next);
  for (const int k : changed)
    if (step.slices.count(k) == 0) {
      SliceSave& save = step.slices[k];
      save.before.assign(values(k), values(k) + static_cast<std::size_t>(grid.nf()) * grid.nf());
      save.before_valid = solved[static_cast<std::size_t>(k)] != 0;
    }
  if (!(next == spec)) ++revision;
  spec = std::move(next);
  check.reset();
  mark_changed(changed);
  if (!solved[static_cast<std::size_t>(slice)]) solve_now(slice);
  post_pending();
}

void StudioModel::Impl::push(Step step) {
  undo.push_back(std::move(step));
  redo.clear();
  trim_history();
}

// Drops the oldest undo steps beyond undo_depth or undo_memory_mib (keeping the newest).
void StudioModel::Impl::trim_history() {
  auto bytes = [](const Step& step) {
    double total = 0;
    for (const auto& entry : step.slices)
      total += double(entry.second.before.size() + entry.second.after.size()) * sizeof(float);
    return total;
  };
  double total = 0;
  for (const Step& step : undo) total += bytes(step);
  for (const Step& step : redo) total += bytes(step);
  const double limit = options.undo_memory_mib * 1024.0 * 1024.0;
  while (undo.size() > 1 && (int(undo.size()) > options.undo_depth || total > limit)) {
    total -= bytes(undo.front());
    undo.pop_front();
  }
}

// Publishes background results still valid: the slice is unsolved and no edit changed it after
// the result's job was posted.
void StudioModel::Impl::poll() {
  adopt_rebuilt(false);
  if (!background) return;
  for (auto& r : background->take()) {
    const auto k = static_cast<std::size_t>(r.slice);
    if (solved[k] || r.generation < changed_at[k]) continue;
    std::memcpy(values(r.slice), r.values.data(), r.values.size() * sizeof(float));
    wrote_slice(r.slice);
    solved[k] = 1;
    --pending;
  }
  background_error = background->error();
}

void StudioModel::Impl::wait(const ProgressFn& progress) {
  if (background) background->set_paused(false);  // paused by a drag: waiting needs it
  for (poll(); pending > 0; poll()) {
    if (progress) progress(pending_total - pending, pending_total);
    if (!background || background->idle()) {  // no thread, or its job failed: solve here (throws)
      solve_now(int(std::find(solved.begin(), solved.end(), 0) - solved.begin()));
      continue;
    }
    background->wait(std::chrono::milliseconds(20));
  }
  if (progress) progress(pending_total, pending_total);
  if (background) background->set_paused(dragging);
}

// After an edit step: when a solve of the step left the edit band, builds generators around the
// current profile (GUI one on another thread, adopted by poll(); the background's before its
// next slice), so the next drags near it are Schur solves again (docs/performance.md).
void StudioModel::Impl::recentre_band() {
  if (!left_band || rebuilt.valid()) return;
  left_band = false;
  const operators::BiharmonicOptions o = generator_options(options);
  rebuilt = std::async(std::launch::async, [s = spec, o] {
    return std::make_unique<operators::BiharmonicOperatorGenerator>(s, o);
  });
  if (background) background->rebase(spec);
}

// Takes the rebuilt generator when it is ready (or waits for it with `block`), then starts the
// next rebuild if a solve left the band meanwhile.
void StudioModel::Impl::adopt_rebuilt(bool block) {
  if (!rebuilt.valid()) return;
  if (!block && rebuilt.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
  generator = rebuilt.get();
  recentre_band();
}

// Undo (`to_before`) or redo of `step` on a fully solved grid: exchanges the slices' values.
void StudioModel::Impl::swap_slices(Step& step, bool to_before) {
  const std::size_t n = static_cast<std::size_t>(grid.nf()) * grid.nf();
  std::vector<int> requeue, all;
  for (auto& [k, save] : step.slices) {
    std::vector<float>& keep = to_before ? save.after : save.before;
    const std::vector<float>& restore = to_before ? save.before : save.after;
    keep.assign(values(k), values(k) + n);
    all.push_back(k);
    if (to_before && !save.before_valid) {
      requeue.push_back(k);
    } else {
      std::memcpy(values(k), restore.data(), n * sizeof(float));
    }
    if (!to_before) save.before_valid = true;
  }
  spec = to_before ? step.before : step.after;
  check.reset();
  ++generation;
  ++revision;
  for (const int k : all) {
    changed_at[static_cast<std::size_t>(k)] = generation;
    slice_rev[static_cast<std::size_t>(k)] = revision;
  }
  for (const int k : requeue) {
    solved[static_cast<std::size_t>(k)] = 0;
    ++pending;
  }
  if (!solved[static_cast<std::size_t>(slice)]) solve_now(slice);
  post_pending();
}

LiveCheck StudioModel::Impl::compute_check() {
  LiveCheck out;
  out.report = operators::inspect_slice(spec, grid, slice);
  out.failure = operators::judge_slice(out.report);
  out.current = solved[static_cast<std::size_t>(slice)] != 0;
  const double h = out.report.cell;
  const operators::SliceProfile profile(spec, slice_d(slice));
  const std::vector<Point2> iso = operators::iso_crossings(grid, slice, 0.5);
  for (const Point2& p : iso)
    if (profile.distance(p) > h) out.stray_crossings.push_back(p);
  for (const Point2& q : profile.samples(0.5 * h, true)) {
    double best = std::numeric_limits<double>::infinity();
    for (const Point2& p : iso) best = std::min(best, std::hypot(p[0] - q[0], p[1] - q[1]));
    if (best > h) out.unmatched_profile.push_back(q);
  }
  return out;
}

// ---- StudioModel: construction and files

StudioModel::StudioModel(OperatorSpec spec, StudioOptions options)
    : impl_(std::make_unique<Impl>(std::move(spec), options)),
      recent_(options.recent_files_path.value_or(default_recent_files_path()), options.recent_capacity),
      saved_spec_(impl_->spec) {}

StudioModel::~StudioModel() = default;

void StudioModel::new_document(OperatorSpec spec) {
  // The revision keeps increasing across documents (a GUI keyed on it must redraw).
  auto fresh = std::make_unique<Impl>(std::move(spec), impl_->options, impl_->revision + 1);
  impl_ = std::move(fresh);
  document_path_.clear();
  saved_spec_ = impl_->spec;
}

std::unique_ptr<StudioModel> StudioModel::open_file(const std::string& path, StudioOptions options) {
  auto model = std::make_unique<StudioModel>(operators::load_spec(path), std::move(options));
  model->document_path_ = path;
  model->recent_.add(path);
  return model;
}

void StudioModel::open(const std::string& path) {
  new_document(operators::load_spec(path));
  document_path_ = path;
  recent_.add(path);
}

void StudioModel::save_spec(const std::string& path) {
  operators::save_spec(impl_->spec, path);
  document_path_ = path;
  saved_spec_ = impl_->spec;
  recent_.add(path);
}

void StudioModel::export_grid(const std::string& npy_path, const ProgressFn& progress) {
  end_drag();
  impl_->wait(progress);
  operators::save_operator(npy_path, impl_->spec, impl_->grid);
}

const std::string& StudioModel::document_path() const {
  return document_path_;
}
bool StudioModel::modified() const {
  return !(impl_->spec == saved_spec_);
}
RecentFiles& StudioModel::recent_files() {
  return recent_;
}

// ---- view

const OperatorSpec& StudioModel::spec() const {
  return impl_->spec;
}
const GridOperator& StudioModel::grid() const {
  return impl_->grid;
}
bool StudioModel::slice_solved(int k) const {
  return k >= 0 && k < impl_->spec.slices && impl_->solved[static_cast<std::size_t>(k)] != 0;
}
int StudioModel::slice() const {
  return impl_->slice;
}
double StudioModel::d() const {
  return impl_->slice_d(impl_->slice);
}

void StudioModel::set_slice(int k) {
  k = std::clamp(k, 0, impl_->spec.slices - 1);
  if (k == impl_->slice) return;
  end_drag();
  impl_->slice = k;
  impl_->check.reset();
  impl_->poll();
  if (!impl_->solved[static_cast<std::size_t>(k)]) impl_->solve_now(k);
}

void StudioModel::set_d(double d) {
  if (!std::isfinite(d)) return;
  set_slice(int(std::lround(std::clamp(d, 0.0, 1.0) * (impl_->spec.slices - 1))));
}

const float* StudioModel::slice_values() const {
  return impl_->grid.slice(impl_->slice);
}

std::vector<Point2> StudioModel::control_points(int c) const {
  if (c < 0 || c >= int(impl_->spec.curves.size())) return {};
  return impl_->spec.curves[static_cast<std::size_t>(c)].control_points(d());
}

std::vector<Point2> StudioModel::polyline(int c) const {
  if (c < 0 || c >= int(impl_->spec.curves.size())) return {};
  return impl_->spec.curves[static_cast<std::size_t>(c)].polyline(d());
}

std::vector<ControllerKnot> StudioModel::controller_knots() const {
  return detail::effective_knots(impl_->spec);
}

const LiveCheck& StudioModel::live_check() {
  if (!impl_->check) impl_->check = impl_->compute_check();
  return *impl_->check;
}

double StudioModel::last_solve_ms() const {
  return impl_->last_ms;
}
bool StudioModel::last_solve_was_schur() const {
  return impl_->last_schur;
}

// ---- selection

std::optional<CurvePoint> StudioModel::pick(const Point2& p, double radius) const {
  return detail::nearest_point(impl_->spec, d(), p, radius, impl_->selection);
}

std::optional<SegmentPick> StudioModel::pick_segment(const Point2& p, double radius) const {
  return detail::nearest_segment(impl_->spec, d(), p, radius);
}

const std::optional<CurvePoint>& StudioModel::selection() const {
  return impl_->selection;
}

void StudioModel::select(std::optional<CurvePoint> point) {
  const auto& curves = impl_->spec.curves;
  if (point &&
      (point->curve < 0 || point->curve >= int(curves.size()) || point->point < 0 ||
       point->point >= int(curves[static_cast<std::size_t>(point->curve)].keyframes[0].points.size())))
    point.reset();
  impl_->selection = point;
}

// ---- edits

EditResult StudioModel::commit(const std::function<OperatorSpec(const OperatorSpec&)>& edit) {
  end_drag();
  OperatorSpec next;
  try {
    next = edit(impl_->spec);
    operators::validate(next, "edit");
  } catch (const InputError& e) {
    return refused(e.what());
  }
  Step step;
  step.before = impl_->spec;
  impl_->apply(std::move(next), step);
  step.after = impl_->spec;
  impl_->push(std::move(step));
  impl_->recentre_band();
  select(impl_->selection);
  return {};
}

EditResult StudioModel::begin_drag(const CurvePoint& point) {
  end_drag();
  select(point);
  if (!impl_->selection)
    return refused("no control point " + std::to_string(point.point) + " on curve " +
                   std::to_string(point.curve));
  Impl& m = *impl_;
  m.begin_step();
  m.dragging = true;
  m.drag_point = point;
  if (m.background) m.background->set_paused(true);  // the drag's solves get the cores
  return {};
}

EditResult StudioModel::drag_to(const Point2& p) {
  Impl& m = *impl_;
  if (!m.dragging) return refused("no drag in progress; call begin_drag first");
  if (!std::isfinite(p[0]) || !std::isfinite(p[1])) return refused("the drag position is not finite");
  const Point2 to{std::clamp(p[0], 0.0, 1.0 - kEdgeMargin), std::clamp(p[1], 0.0, 1.0 - kEdgeMargin)};
  OperatorSpec next;
  try {
    next = detail::move_point(m.drag_start, m.drag_point, d(), m.half_slice(), to);
    operators::validate(next, "drag");
  } catch (const InputError& e) {
    return refused(e.what());
  }
  m.apply(std::move(next), m.drag_step);
  m.moved = true;
  return {};
}

void StudioModel::end_drag() {
  Impl& m = *impl_;
  if (!m.dragging && !m.knot_dragging) return;
  if (m.dragging && m.background) m.background->set_paused(false);
  m.dragging = m.knot_dragging = false;
  if (!m.moved) return;
  m.drag_step.after = m.spec;
  m.push(std::move(m.drag_step));
  m.recentre_band();
}

bool StudioModel::dragging() const {
  return impl_->dragging;
}

EditResult StudioModel::begin_knot_drag(int i) {
  end_drag();
  if (i < 0 || i >= int(controller_knots().size()))
    return refused("no controller knot " + std::to_string(i) + " (the controller has " +
                   std::to_string(controller_knots().size()) + ")");
  Impl& m = *impl_;
  m.begin_step();
  m.knot_dragging = true;
  m.drag_knot = i;
  return {};
}

EditResult StudioModel::drag_knot_to(double alpha, double d) {
  Impl& m = *impl_;
  if (!m.knot_dragging) return refused("no knot drag in progress; call begin_knot_drag first");
  OperatorSpec next;
  try {
    next = detail::set_knot(m.drag_start, m.drag_knot, alpha, d);
    operators::validate(next, "knot drag");
  } catch (const InputError& e) {
    return refused(e.what());
  }
  m.apply(std::move(next), m.drag_step);
  m.moved = true;
  return {};
}

bool StudioModel::dragging_knot() const {
  return impl_->knot_dragging;
}

EditResult StudioModel::add_point(int curve, int segment, double t) {
  const EditResult r =
      commit([&](const OperatorSpec& s) { return detail::insert_point(s, curve, segment, t); });
  if (r) select(CurvePoint{curve, segment + 1});
  return r;
}

EditResult StudioModel::delete_point(const CurvePoint& point) {
  return commit([&](const OperatorSpec& s) { return detail::remove_point(s, point); });
}

EditResult StudioModel::add_keyframe(int c) {
  const double at = d(), tolerance = impl_->half_slice();
  return commit([&](const OperatorSpec& s) { return detail::insert_keyframe(s, c, at, tolerance); });
}

EditResult StudioModel::delete_keyframe(int c, int k) {
  return commit([&](const OperatorSpec& s) { return detail::remove_keyframe(s, c, k); });
}

EditResult StudioModel::add_knot(double alpha, double d) {
  return commit([&](const OperatorSpec& s) { return detail::insert_knot(s, alpha, d); });
}

EditResult StudioModel::move_knot(int i, double alpha, double d) {
  return commit([&](const OperatorSpec& s) { return detail::set_knot(s, i, alpha, d); });
}

EditResult StudioModel::delete_knot(int i) {
  return commit([&](const OperatorSpec& s) { return detail::remove_knot(s, i); });
}

EditResult StudioModel::rename(const std::string& name) {
  return commit([&](const OperatorSpec& s) {
    OperatorSpec next = s;
    next.name = name;
    return next;
  });
}

EditResult StudioModel::add_curve(CurveKind kind, CurveType type, std::vector<Point2> points) {
  return commit([&](const OperatorSpec& s) { return detail::append_curve(s, kind, type, points); });
}

EditResult StudioModel::delete_curve(int c) {
  return commit([&](const OperatorSpec& s) { return detail::remove_curve(s, c); });
}

// ---- history

bool StudioModel::can_undo() const {
  return !impl_->undo.empty();
}
bool StudioModel::can_redo() const {
  return !impl_->redo.empty();
}

bool StudioModel::undo(const ProgressFn& progress) {
  end_drag();
  Impl& m = *impl_;
  if (m.undo.empty()) return false;
  m.wait(progress);
  Step step = std::move(m.undo.back());
  m.undo.pop_back();
  m.swap_slices(step, true);
  m.recentre_band();
  m.redo.push_back(std::move(step));
  m.trim_history();
  select(m.selection);
  return true;
}

bool StudioModel::redo(const ProgressFn& progress) {
  end_drag();
  Impl& m = *impl_;
  if (m.redo.empty()) return false;
  m.wait(progress);
  Step step = std::move(m.redo.back());
  m.redo.pop_back();
  m.swap_slices(step, false);
  m.recentre_band();
  m.undo.push_back(std::move(step));
  select(m.selection);
  return true;
}

// ---- background

void StudioModel::poll() {
  impl_->poll();
}

SolveProgress StudioModel::progress() const {
  if (impl_->pending == 0) return {};
  return SolveProgress{impl_->pending_total - impl_->pending, impl_->pending_total};
}

long StudioModel::revision() const {
  return impl_->revision;
}
long StudioModel::slice_revision(int k) const {
  if (k < 0 || k >= impl_->spec.slices) return 0;
  return impl_->slice_rev[static_cast<std::size_t>(k)];
}

bool StudioModel::fully_solved() const {
  return impl_->pending == 0;
}
void StudioModel::wait_until_solved(const ProgressFn& progress) {
  impl_->wait(progress);
  impl_->adopt_rebuilt(true);
}
bool StudioModel::recentring() const {
  return impl_->rebuilt.valid();
}
const std::string& StudioModel::background_error() const {
  return impl_->background_error;
}

}  // namespace isokit::studio
