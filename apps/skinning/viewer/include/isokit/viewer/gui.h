// SPDX-License-Identifier: MIT
/// \file
/// The skinning viewer's window (`isokit-skin view`, docs/skinning.md "The viewer"): GLFW +
/// OpenGL 3.3 + Dear ImGui over a ViewerModel baking in the background. The view is drawn by
/// the software rasterizer (`render_mesh`) into a texture; the joints are drawn over it and
/// picked by a click. A script (`script_path`) replays input events through the real widgets,
/// one event per frame, takes screenshots and writes a report (the `gui` test, the drag
/// benchmark).
#pragma once

#include <string>

#include "isokit/viewer/model.h"

namespace isokit::viewer {

struct ViewerGuiOptions {
  std::string rig;    ///< a rig file or `procedural:NAME`
  std::string clip;   ///< a clip to play at start ("" = edit the rest pose)
  std::string setup;  ///< a setup file ("" = the defaults)
  /// lbs | dqs | ddm | cor | implicit2013 | tracking2014 (default: skinning::kDefaultMethod)
  std::string method{skinning::to_string(skinning::kDefaultMethod)};
  int width{1280}, height{800};  ///< window size in pixels
  /// ViewerOptions::edit_slice_ms: an edit's skin shown after this many ms of its solve (0 = whole).
  double edit_slice_ms{ViewerOptions{}.edit_slice_ms};
  /// Each drawn frame waits up to this long for the skin of the last edit when it is not shown
  /// yet (ms; default 5; 0 = never wait): a few ms of the frame for a skin closer to the sliders
  /// (ViewerModel::poll(double)).
  double skin_wait_ms{5.0};
  /// Headless mode: a JSON script of input events (gui.cpp's file comment); the window closes
  /// after its last event and writes `report_path` (default `screenshot_dir/viewer-report.json`).
  std::string script_path;
  std::string screenshot_dir{"."};
  std::string report_path;
};

/// Opens the window and runs until it is closed (or the script ends). Returns the exit code.
/// \throw InputError for a rig, setup or script that cannot be used, or no display.
int run_viewer(const ViewerGuiOptions& options);

}  // namespace isokit::viewer
