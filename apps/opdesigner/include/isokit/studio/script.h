// SPDX-License-Identifier: MIT
/// \file
/// Scripts for the design studio's headless mode (`isokit-opdesigner gui --script FILE`): a JSON
/// list of input events replayed through the real window, one event per frame, so tests and
/// benchmarks drive the same widgets a user does. Events (each an object with "type"):
/// - `{"type": "move", "to": T, "frames": N}`: move the mouse to target T, in N equal steps
///   (one per frame; default 1), the button state unchanged (a drag when pressed). Targets:
///   `{"px": [x, y]}` window pixels, `{"op": [f1, f2]}` a point of the operator plot,
///   `{"point": [curve, index]}` a control point at the displayed d (where the model has it),
///   `{"knot": i}` a controller knot, `{"ctrl": [alpha, d]}` a point of the controller plot
///   (radians), `{"preview": [x, y]}` a point of the composition preview.
/// - `{"type": "press"}` / `{"type": "release"}`: left mouse button (`"button": 1` right).
/// - `{"type": "key", "key": "Z", "ctrl": true, "shift": false}`: a key press and release.
/// - `{"type": "frames", "n": N}`: render N frames without input.
/// - `{"type": "wait_solved", "max_frames": N}`: render frames until every slice is solved.
/// - `{"type": "screenshot", "name": "NAME"}`: save the window as DIR/NAME.png (--screenshot-dir).
/// - `{"type": "set", "d": D, "angle": A}`: set the displayed d and/or the preview's bend angle
///   (degrees) as the sliders would.
/// - `{"type": "mark", "name": "NAME"}`: record the model state under NAME in the exit report.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "isokit/plot/figure.h"

namespace isokit::studio {

enum class TargetKind { kPixel, kOperator, kControlPoint, kKnot, kController, kPreview };

struct ScriptTarget {
  TargetKind kind{TargetKind::kPixel};
  plot::Point2 at{};  ///< kPixel, kOperator, kController, kPreview
  int curve{0};       ///< kControlPoint
  int index{0};       ///< kControlPoint: point; kKnot: knot
};

enum class EventKind { kMove, kPress, kRelease, kKey, kFrames, kWaitSolved, kScreenshot, kSet, kMark };

struct ScriptEvent {
  EventKind kind{EventKind::kFrames};
  ScriptTarget target;  ///< kMove
  int frames{1};        ///< kMove: steps; kFrames: count; kWaitSolved: limit
  int button{0};        ///< kPress, kRelease
  std::string key;      ///< kKey: a letter, digit or "Delete", "Escape", "Enter"
  bool ctrl{false}, shift{false};
  std::string name;             ///< kScreenshot, kMark
  std::optional<double> d;      ///< kSet
  std::optional<double> angle;  ///< kSet, degrees
};

/// Parses a script. \throw isokit::InputError naming `source`, the event number and the field.
std::vector<ScriptEvent> parse_script(const std::string& json_text, const std::string& source);
/// Reads and parses a script file. \throw isokit::InputError naming the file.
std::vector<ScriptEvent> load_script(const std::string& path);

}  // namespace isokit::studio
