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

namespace isokit::viewer {

struct ViewerGuiOptions {
  std::string rig;                     ///< a rig file or `procedural:NAME`
  std::string clip;                    ///< a clip to play at start ("" = edit the rest pose)
  std::string setup;                   ///< a setup file ("" = the defaults)
  std::string method{"tracking2014"};  ///< lbs | dqs | implicit2013 | tracking2014
  int width{1280}, height{800};        ///< window size in pixels
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
