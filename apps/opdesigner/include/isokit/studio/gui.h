// SPDX-License-Identifier: MIT
/// \file
/// The operator design studio's window (`isokit-opdesigner gui [SPEC]`): GLFW + OpenGL 3.3 +
/// Dear ImGui over the studio model (isokit/studio/model.h). The slice of the operator at the
/// displayed d is drawn as a colour map with iso-lines every 0.1 (0.5 thick) and the profile
/// curves (2014 Fig. 5/6) with control points to drag, add and delete; a d slider; the controller
/// d(α) as an editable curve; a live composition of two capsules at a joint; the checks of the
/// displayed slice with the offending region marked; undo/redo; open/save/export.
///
/// Headless use (tests, benchmarks): `script_path` replays input events (isokit/studio/script.h)
/// through the real widgets, screenshots go to `screenshot_dir`, and a JSON report (the model
/// state at marks and screenshots, frame and solve timings, input-to-redraw latency) is written
/// to `report_path` at exit.
#pragma once

#include <string>

namespace isokit::studio {

struct GuiOptions {
  /// Spec file to open; "" starts from the preset `preset`.
  std::string spec_path;
  /// Preset used without a spec (operators::preset_spec_names()). Default "contact".
  std::string preset{"contact"};
  /// Overrides the spec's resolution and slice count when > 0 (tests use small grids). Default 0.
  int resolution{0};
  /// Window size in pixels. Default 1280 x 800.
  int width{1280}, height{800};
  /// Script of input events; "" = interactive.
  std::string script_path;
  /// Folder for screenshots of the script. Default ".".
  std::string screenshot_dir{"."};
  /// JSON report written at exit; "" = none (a script defaults it to screenshot_dir/studio-report.json).
  std::string report_path;
  /// Synchronise with the display's refresh (interactive default); scripts run unsynchronised.
  bool vsync{true};
  /// Recent-files list; nullopt-like "" keeps it in memory (scripts), "default" = the user's file.
  std::string recent_files{"default"};
};

/// Opens the window and runs until it is closed or the script ends. Returns the process exit code:
/// 0, or 2 when a script's event failed (the report says which). \throw isokit::InputError for a
/// bad spec or script, or when no window can be created (no display: run under xvfb-run).
int run_gui(const GuiOptions& options);

}  // namespace isokit::studio
