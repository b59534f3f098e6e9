// SPDX-License-Identifier: MIT
/// \file
/// The operator design studio's model (`isokit-opdesigner gui`): the document (an OperatorSpec
/// and its generated grid), the displayed slice, the selection, undo/redo and a background
/// solver. No drawing: the ImGui layer reads the queries and calls the edits, and the unit tests
/// drive the same calls (2014 §4.2: operators are designed by drawing profile curves).
///
/// Threads: every member is called from one thread (the GUI thread). One background thread
/// re-solves the slices an edit changed, into its own buffer; `poll()` (call it once per frame)
/// publishes the finished slices into the grid. Nothing the queries return changes between two
/// calls on the GUI thread.
///
/// Solving: an edit compares every slice's control points (`control_points(slice_d)` of every
/// curve, with its kind and type) before and after; the changed slices are queued. The displayed
/// slice, if changed, is re-solved synchronously (`solve_edited`, Schur scheme inside
/// `StudioOptions::edit_band_cells`), so it is current when the edit returns; the others are
/// solved in the background. `fully_solved()` then `grid()` equals `generate()` of `spec()` up to
/// rounding (≤ 1e-5). Save of the spec does not need the grid; export, undo and redo wait for
/// the background first.
///
/// Edit band: the generators precompute a band of `edit_band_cells` around the profile they
/// were built for; a slice whose edited profile leaves it costs a numeric factorisation (~10x
/// slower). When an edit step (a whole drag) left the band, both generators are rebuilt around
/// the edited profile in the background (seconds at 128², `recentring()`), then adopted.
///
/// Keyframes: control points are keyframed over d and interpolated linearly (ProfileCurve).
/// Point edits act at the displayed d: on the keyframe at that slice's d when one lies within
/// half a slice, else on a new keyframe inserted at the slice's d (with the interpolated points)
/// — so a drag at d bends the profile between the neighbouring keyframes, not everywhere.
///
/// Invalid edits: every edit builds the edited spec and validates it (operators::validate). A
/// dragged point is first clamped into [0, 1 - 1e-6]²; if the spec is still invalid (a
/// self-intersection, a point on an axis away from (0, .5)/(.5, 0)) the edit is refused: the
/// model is unchanged and the EditResult carries validate's message (during a drag the point
/// stays at its last valid position).
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "isokit/operators/biharmonic.h"
#include "isokit/operators/checks.h"
#include "isokit/operators/grid_operator.h"
#include "isokit/operators/spec.h"
#include "isokit/studio/recent_files.h"

namespace isokit::studio {

using operators::ControllerKnot;
using operators::CurveKind;
using operators::CurveType;
using operators::OperatorSpec;
using operators::Point2;

struct StudioOptions {
  /// Edit band of the generators, in cells (BiharmonicOptions::edit_band_cells): drags that stay
  /// this close to the opened profile are re-solved with the Schur scheme. Default 3.
  int edit_band_cells{3};
  /// Sparse backend of the generators. Default kAuto.
  operators::SparseBackend backend{operators::SparseBackend::kAuto};
  /// Undo steps kept (oldest dropped first), ≥ 1. Default 100.
  int undo_depth{100};
  /// Memory of the slice values kept for undo/redo (a step keeps the slices it changed, up to
  /// 2 x 64 KiB each at 128²): the oldest steps are dropped beyond it, the last one always kept.
  /// Default 1024 MiB.
  double undo_memory_mib{1024};
  /// Solve queued slices on a background thread. false: no thread; queued slices are solved on
  /// the calling thread by wait_until_solved (and export, undo, redo) — deterministic, for tests
  /// and scripts. Default true.
  bool background_thread{true};
  /// Recent-files list: nullopt = default_recent_files_path(); "" = in memory only (tests).
  std::optional<std::string> recent_files_path;
  /// Recent files kept. Default 10.
  int recent_capacity{10};
};

/// A control point: curve index into spec().curves and point index within that curve.
struct CurvePoint {
  int curve{-1};
  int point{-1};
  bool operator==(const CurvePoint& o) const { return curve == o.curve && point == o.point; }
};

/// A point on a curve's control polygon at the displayed d: between points `segment` and
/// `segment + 1` at parameter `t` ∈ [0, 1].
struct SegmentPick {
  int curve{-1};
  int segment{-1};
  double t{0};
  Point2 at{};
};

/// What an edit did: ok, or refused with the reason (validate's message, or why the edit does
/// not apply). A refused edit changes nothing.
struct EditResult {
  bool ok{true};
  std::string message;
  explicit operator bool() const { return ok; }
};

/// Background re-solve: `done` of `total` slices since the last edit (0/0 when idle).
struct SolveProgress {
  int done{0};
  int total{0};
};

/// Checks of the displayed slice (operators::inspect_slice / judge_slice) and where they fail.
struct LiveCheck {
  operators::SliceReport report;
  std::optional<operators::CheckFailure> failure;
  /// 0.5 crossings (on grid edges) more than one cell from the profile: stray iso-lines.
  std::vector<Point2> stray_crossings;
  /// Boundary-profile samples more than one cell from every 0.5 crossing: the profile the
  /// operator does not reproduce.
  std::vector<Point2> unmatched_profile;
  /// False while the displayed slice is not solved for the current spec (never after an edit).
  bool current{true};
};

/// (done, total) slices; called on the calling (GUI) thread while waiting.
using ProgressFn = std::function<void(int done, int total)>;

class StudioModel {
 public:
  /// Validates `spec`, builds the generators and solves the first slice (d = 0) now, the others
  /// in the background. \throw isokit::InputError for an invalid spec.
  explicit StudioModel(OperatorSpec spec, StudioOptions options = {});
  ~StudioModel();
  StudioModel(const StudioModel&) = delete;
  StudioModel& operator=(const StudioModel&) = delete;

  // ---- Files (a path field is the GUI's file dialog).
  /// Replaces the document by the spec at `path` (history cleared, slice 0 displayed) and adds it
  /// to the recent files. \throw isokit::InputError (load_spec's message); the model is unchanged.
  void open(const std::string& path);
  /// Replaces the document by `spec` (e.g. a preset: "New"), with no document path and an empty
  /// history. \throw isokit::InputError for an invalid spec; the model is unchanged.
  void new_document(OperatorSpec spec);
  /// Writes the spec atomically (operators::save_spec), makes `path` the document path and adds
  /// it to the recent files. \throw isokit::InputError naming the file.
  void save_spec(const std::string& path);
  /// Waits for the background, then writes the grid and its spec (operators::save_operator).
  /// \throw isokit::InputError naming the file.
  void export_grid(const std::string& npy_path, const ProgressFn& progress = {});
  /// The last opened or saved spec file ("" for a new document).
  const std::string& document_path() const;
  /// True when the spec differs from the one last opened or saved.
  bool modified() const;
  RecentFiles& recent_files();

  // ---- View.
  const OperatorSpec& spec() const;
  /// The grid: `spec().slices` slices of `resolution²`. A slice not yet re-solved
  /// (`!slice_solved(k)`) holds its values before the edit.
  const operators::GridOperator& grid() const;
  bool slice_solved(int k) const;
  /// The displayed slice and its d (`k / (slices - 1)`).
  int slice() const;
  double d() const;
  /// Shows slice `k` (clamped to the grid); solves it now if it is still queued. Ends a drag in
  /// progress (edits act at the displayed d).
  void set_slice(int k);
  /// Shows the slice nearest to `d` (clamped to [0, 1]).
  void set_d(double d);
  /// The displayed slice: `resolution²` values, `[i1 * nf + i2] = g(i1 h, i2 h)`; always solved
  /// for the current spec.
  const float* slice_values() const;
  /// Control points and polyline of curve `c` at the displayed d.
  std::vector<Point2> control_points(int c) const;
  std::vector<Point2> polyline(int c) const;
  /// The controller's knots: spec().controller_knots, or the preset's when those are empty.
  std::vector<ControllerKnot> controller_knots() const;
  /// Checks of the displayed slice (cached until the slice or the spec changes).
  const LiveCheck& live_check();
  /// Milliseconds and scheme of the last synchronous slice solve.
  double last_solve_ms() const;
  bool last_solve_was_schur() const;

  // ---- Selection.
  /// The nearest control point within `radius` of `p` at the displayed d, if any.
  std::optional<CurvePoint> pick(const Point2& p, double radius) const;
  /// The nearest point of a control polygon within `radius` of `p` (for add_point).
  std::optional<SegmentPick> pick_segment(const Point2& p, double radius) const;
  const std::optional<CurvePoint>& selection() const;
  /// Selects a point (or nothing); an invalid point clears the selection.
  void select(std::optional<CurvePoint> point);

  // ---- Edits: each is one undo step (a whole drag is one step) and returns EditResult.
  /// Starts dragging `point` (and selects it); ends a drag in progress first.
  EditResult begin_drag(const CurvePoint& point);
  /// Moves the dragged point to `p` at the displayed d (see the file comment: keyframes,
  /// clamping, refusal); re-solves the displayed slice before returning.
  EditResult drag_to(const Point2& p);
  /// Ends the drag; the step goes on the undo stack if anything moved.
  void end_drag();
  bool dragging() const;
  /// Inserts a point after `segment` at parameter `t` of that segment, in every keyframe (so the
  /// profile at every d keeps its shape for polylines). Selects it.
  EditResult add_point(int curve, int segment, double t = 0.5);
  /// Deletes the point from every keyframe; refused below 2 points (polyline) or 4 (B-spline).
  EditResult delete_point(const CurvePoint& point);
  /// Inserts a keyframe of curve `c` at the displayed d (the interpolated points); refused when
  /// one lies within half a slice.
  EditResult add_keyframe(int c);
  /// Deletes keyframe `k` of curve `c`; refused for a curve's last keyframe.
  EditResult delete_keyframe(int c, int k);
  /// Controller knots (angles in radians, d in [0, 1]); editing a preset controller first copies
  /// its knots into spec().controller_knots. The first (α = 0) and last (α = π) knots keep their
  /// angle: move_knot changes only their d, and they cannot be deleted. add_knot refuses an
  /// angle already used; move_knot refuses to pass a neighbour. The grid does not change.
  EditResult add_knot(double alpha, double d);
  EditResult move_knot(int i, double alpha, double d);
  EditResult delete_knot(int i);
  /// Renames the operator (spec().name). The grid does not change.
  EditResult rename(const std::string& name);
  /// Appends a curve with one keyframe (the same points for every d).
  EditResult add_curve(CurveKind kind, CurveType type, std::vector<Point2> points);
  /// Removes curve `c` (refused when it is the last boundary curve).
  EditResult delete_curve(int c);

  // ---- History (bounded by StudioOptions::undo_depth). Undo and redo end a drag, wait for the
  // background (progress on this thread) and restore the spec and the changed slices bit for bit.
  bool can_undo() const;
  bool can_redo() const;
  bool undo(const ProgressFn& progress = {});
  bool redo(const ProgressFn& progress = {});

  // ---- Background solver.
  /// Publishes the slices the background finished. Call once per frame; cheap when idle.
  void poll();
  SolveProgress progress() const;
  /// True when every slice is solved for the current spec (as of the last poll()).
  bool fully_solved() const;
  /// Polls until fully_solved(), calling `progress` between slices, then waits for a generator
  /// being rebuilt (recentring()). Export, undo and redo wait for the slices only.
  void wait_until_solved(const ProgressFn& progress = {});
  /// True while a generator is being rebuilt around the edited profile (see the file comment);
  /// poll() adopts it, wait_until_solved() waits for it.
  bool recentring() const;
  /// The last background failure ("" if none); its slices stay queued.
  const std::string& background_error() const;

 private:
  struct Impl;
  /// Applies `edit` to the spec as one undo step (refused when it throws or validate fails).
  EditResult commit(const std::function<OperatorSpec(const OperatorSpec&)>& edit);
  std::unique_ptr<Impl> impl_;
  RecentFiles recent_;
  std::string document_path_;
  OperatorSpec saved_spec_;  // as last opened or saved, for modified()
};

}  // namespace isokit::studio
