// SPDX-License-Identifier: MIT
/// \file
/// The real-rig evaluation (`isokit-eval`, `make eval`; docs/skinning-real-rigs.md). For every
/// rig: every clip, and a bend-and-return of its elbows and knees (eval_joints.h), baked with
/// each method in the same run; one row per (rig, animation, method) (eval_rows.h) in
/// `OUT/eval.json` and `OUT/eval.md`, and per rig `OUT/<rig>/<animation>.metrics.json` (the
/// `--metrics` JSON of that bake), `OUT/<rig>/contact_sheet.png` (the bend-and-return: a close-up
/// per bent joint) and `OUT/<rig>/<clip>.png` (close-ups of the two joints that turn most). A rig,
/// animation or method that fails becomes a row with its one-line error and the run goes on; the
/// tables are rewritten after each animation. Progress goes to stderr.
#pragma once

#include <string>
#include <vector>

#include "eval_rows.h"

namespace isokit::eval {

struct EvalOptions {
  std::vector<std::string> rigs;     ///< files or procedural specs
  std::vector<std::string> folders;  ///< every .glb/.gltf/.fbx/.dae of these (sorted)
  std::vector<std::string> only;     ///< keep the rigs whose path contains one of these
  std::vector<std::string> clips;    ///< keep these animations ("bend" = the bend-and-return)
  /// The geometric methods (the bar: dqs, and the best of dqs, ddm, cor) and the implicit ones.
  std::vector<std::string> methods{"dqs", "ddm", "cor", "implicit2013", "tracking2014"};
  int max_frames{0};  ///< first frames of each clip (0 = all; the bend-and-return is not cut)
  int bend_frames{31};
  double bend_degrees{120};
  double fps{30};  ///< clip sampling rate
  bool render{true}, self_intersections{true};
  std::string out{"out/eval"}, commit;
  /// A setup file applied to every rig (isokit-skin's `--setup`; empty = the defaults): for
  /// ablations and the papers' settings, never a per-rig setup.
  std::string setup;
};

/// The rigs a run evaluates: `rigs`, the files of `folders`, filtered by `only`; with neither,
/// `../shared/data/rigs` (when it exists) and `../shared/data/Fox.glb`.
std::vector<std::string> rigs_of(const EvalOptions& options);

/// Runs the evaluation and returns its rows (also written to `options.out`).
/// \throw InputError for an unknown method or when there is no rig at all.
std::vector<Row> run_evaluation(const EvalOptions& options);

}  // namespace isokit::eval
