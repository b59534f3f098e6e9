// SPDX-License-Identifier: MIT
/// \file
/// Value types of the studio model (model.h): its options, picks, edit results, progress and
/// live checks.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "isokit/operators/biharmonic.h"
#include "isokit/operators/checks.h"
#include "isokit/operators/spec.h"

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

}  // namespace isokit::studio
