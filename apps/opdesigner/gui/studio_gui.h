// SPDX-License-Identifier: MIT
// Internal to isokit_studio_gui: the panels (ImGui widgets over the model) and the script player
// (input events into ImGui's IO), shared by window.cpp, panels.cpp and replay.cpp.
#pragma once

#include <imgui.h>

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "isokit/opdesigner/designer.h"
#include "isokit/studio/gui.h"
#include "isokit/studio/model.h"
#include "isokit/studio/script.h"
#include "isokit/studio/view.h"
#include "kit/gl_window.h"

struct GLFWwindow;

namespace isokit::studio::gui {

// Colours of the drawn items (RGBA); the gui test looks for the handle colour on screenshots.
constexpr std::uint8_t kHandleRgb[3] = {255, 40, 200};
constexpr std::uint8_t kSelectedRgb[3] = {255, 150, 0};
/// Margin in pixels between an editable plot and its input area (handles on the plot's edges).
constexpr float kPlotPad = 10.f;
constexpr std::uint8_t kCheckRgb[3] = {255, 30, 30};  // marks of a failed check

/// Where the plots are on screen (set while drawing, read by the script player).
struct Layout {
  PlotMapping op;          ///< the operator slice, (f1, f2) ∈ [0, 1]²
  PlotMapping controller;  ///< the controller, α ∈ [0, π] x d ∈ [0, 1]
  PlotMapping preview;     ///< the composition preview, [-1.6, 1.6]²
};

/// Per-frame measurements (frame counter, upload of a re-solved slice, solve times).
struct FrameStats {
  int frame{0};
  int last_upload_frame{-1};       ///< frame whose slice texture was last rebuilt
  std::vector<double> solve_ms;    ///< model.last_solve_ms() after each accepted drag_to
  std::vector<int> upload_frames;  ///< frames in which the slice texture was rebuilt
};

/// A GL texture holding an RGBA image.
class Texture : public gui_kit::Texture {
 public:
  using gui_kit::Texture::upload;
  void upload(const plot::RgbaImage& image) { upload(image.width, image.height, image.pixels.data()); }
};

/// The studio's widgets over a model; draw() builds one ImGui frame.
class Panels {
 public:
  Panels(StudioModel& model, GuiOptions options);
  void draw(FrameStats& stats);
  const Layout& layout() const { return layout_; }
  void set_d(double d) { model_.set_d(d); }
  void set_angle(double degrees) { angle_deg_ = degrees; }
  /// Messages of refused edits and failed file actions, oldest first (for the report).
  const std::vector<std::string>& messages() const { return messages_; }

 private:
  void draw_operator_plot(FrameStats& stats);
  void handle_operator_input(FrameStats& stats);
  void draw_slice_layers(ImDrawList* dl, FrameStats& stats);
  void draw_curves(ImDrawList* dl);
  void draw_check_marks(ImDrawList* dl);
  void draw_side_panel();
  void draw_curve_panel();
  void draw_file_panel();
  void draw_history_and_progress();
  void draw_check_panel();
  void draw_controller_plot();
  void draw_preview();
  void handle_shortcuts();
  void run_pending_actions();
  void report(const EditResult& r);
  void report(const std::string& message);

  StudioModel& model_;
  GuiOptions options_;
  Layout layout_;
  Texture slice_tex_, preview_tex_;
  std::pair<int, long> shown_slice_{-1, -1};  // slice and slice_revision behind slice_tex_
  std::vector<IsoLineSet> slice_iso_;
  opdesigner::ComposedField preview_;
  std::vector<IsoLineSet> preview_iso_;
  std::pair<long, double> preview_key_{-1, -1};  // revision and angle behind preview_
  double angle_deg_{120};
  std::string path_field_;
  std::string export_field_;
  enum class Pending { kNone, kUndo, kRedo, kSave, kExport };
  Pending pending_{Pending::kNone};
  std::vector<std::string> messages_;
  std::string status_;
};

/// Replays script events into ImGui's IO, one event per frame (moves may span frames).
class ScriptPlayer {
 public:
  ScriptPlayer(std::vector<ScriptEvent> events, GLFWwindow* window);
  /// Before ImGui::NewFrame: applies the current event's input to `io`.
  void apply_input(ImGuiIO& io, const Layout& layout, StudioModel& model, Panels& panels, int frame);
  /// After the frame is rendered: the screenshot/mark to take now (if any), then advances.
  std::optional<ScriptEvent> finish_frame(StudioModel& model);
  bool done() const { return next_ >= events_.size() && !key_release_ && !release_frame_; }
  /// Frames in which a move with the button held was delivered (for the latency).
  const std::vector<int>& drag_input_frames() const { return drag_frames_; }
  /// Events that did not do what they asked (e.g. wait_solved ran out of frames).
  const std::vector<std::string>& failures() const { return failures_; }

 private:
  plot::Point2 resolve(const ScriptTarget& t, const Layout& layout, StudioModel& model) const;
  std::vector<ScriptEvent> events_;
  GLFWwindow* window_;
  std::size_t next_{0};
  int step_{0};  // frames spent on the current event
  plot::Point2 mouse_{-1, -1}, move_from_{}, move_to_{};
  bool down_[3]{false, false, false};
  std::optional<int> key_release_;  // GLFW key to release next frame
  bool release_frame_{false};       // this frame only releases a key
  bool ctrl_{false}, shift_{false};
  std::vector<int> drag_frames_;
  std::vector<std::string> failures_;
};

}  // namespace isokit::studio::gui
