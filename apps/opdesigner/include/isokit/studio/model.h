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
/// solved in the background; while a point drag is in progress the background thread pauses
/// at its next slice boundary (on 2 cores it would compete with the drag's solves) and resumes
/// when the drag ends (or while `wait_until_solved()` waits). `fully_solved()` then `grid()`
/// equals `generate()` of `spec()` up to rounding (≤ 1e-5). Save of the spec does not need the
/// grid; export, undo and redo wait for the background first.
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

#include <memory>
#include <string>
#include <vector>

#include "isokit/operators/grid_operator.h"
#include "isokit/studio/recent_files.h"
#include "isokit/studio/types.h"

namespace isokit::studio {

class StudioModel {
 public:
  /// Validates `spec`, builds the generators and solves the first slice (d = 0) now, the others
  /// in the background. \throw isokit::InputError for an invalid spec.
  explicit StudioModel(OperatorSpec spec, StudioOptions options = {});
  /// A model of the spec file at `path`, as `open(path)` leaves it (document path, recent file)
  /// without building a throwaway document first. \throw isokit::InputError (load_spec's
  /// message, or an invalid spec).
  static std::unique_ptr<StudioModel> open_file(const std::string& path, StudioOptions options = {});
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
  /// The nearest control point within `radius` of `p` at the displayed d, if any. Points at the
  /// same spot (e.g. at d = 0 the contact line's ends on the boundary corner) go to the
  /// selected point, then its curve, then boundary curves.
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
  /// Ends the drag (of a point or a knot); the step goes on the undo stack if anything moved.
  void end_drag();
  /// True while a point drag (begin_drag) is in progress.
  bool dragging() const;
  /// A drag of controller knot `i` (see move_knot): one undo step for the whole drag, like
  /// begin_drag/drag_to/end_drag. Ends a drag in progress first; refused for a missing knot.
  EditResult begin_knot_drag(int i);
  /// Moves the dragged knot to (`alpha`, `d`) from where it was when the drag began (move_knot's
  /// rules); a refused move leaves it at its last valid position. The grid does not change.
  EditResult drag_knot_to(double alpha, double d);
  /// True while a knot drag is in progress.
  bool dragging_knot() const;
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
  /// A counter increased by every change of the spec or the grid (an accepted edit or drag step,
  /// undo, redo, a slice solved on this thread or published by poll(), a new document) and by
  /// nothing else: redraw what depends on the document when it differs from the value drawn.
  long revision() const;
  /// The revision at which slice `k`'s values last changed (0: never written or no such slice);
  /// a texture of the displayed slice is current while (slice(), slice_revision(slice())) is.
  long slice_revision(int k) const;
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
