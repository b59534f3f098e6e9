// SPDX-License-Identifier: MIT
// Internal to the viewer's window: the panels (ImGui widgets over the model), the 3D view drawn by
// the software rasterizer, and where things are on screen for the script player.
#pragma once

#include <imgui.h>

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "isokit/skinning/render.h"
#include "isokit/viewer/model.h"
#include "kit/gl_window.h"

namespace isokit::viewer::gui {

// Colours the gui test looks for on screenshots (RGB).
constexpr std::uint8_t kJointRgb[3] = {40, 90, 255};
constexpr std::uint8_t kSelectedRgb[3] = {255, 150, 0};
constexpr float kOverlayRgb[3] = {0.95f, 0.1f, 0.1f};  // flagged faces / vertices, linear RGB

enum class Overlay { kNone, kOverlap, kFolds, kIntersecting, kInverted, kContacts, kMask, kDqsDistance };
const char* to_string(Overlay o);

/// Orbit camera over the rig's rest box: yaw and pitch (radians), zoom (> 0, 1 = the box fills
/// the view) and pan (fractions of the box diagonal along the view's right and up).
struct ViewState {
  double yaw{1.2}, pitch{0.2}, zoom{1}, pan_x{0}, pan_y{0};
  skinning::RenderOptions options(const Eigen::AlignedBox3d& box, int width, int height) const;
};

/// Where the widgets are (set while drawing, read by the script player).
struct Layout {
  ImVec2 view_min{0, 0}, view_max{0, 0};  ///< the 3D view's image on screen
  std::map<std::string, ImVec4> sliders;  ///< "x", "y", "z", "frame": rect (x0, y0, x1, y1)
  std::vector<ImVec2> joints;             ///< each joint's screen position
};

/// A GL texture holding an RGBA image.
using Texture = gui_kit::Texture;

/// The viewer's widgets over a model; draw() builds one ImGui frame.
class Panels {
 public:
  /// `skin_wait_ms`: ViewerGuiOptions::skin_wait_ms.
  Panels(ViewerModel& model, double skin_wait_ms);
  void draw(int width, int height);
  const Layout& layout() const { return layout_; }
  Overlay overlay() const { return overlay_; }
  void set_overlay(Overlay o) { overlay_ = o, dirty_ = true; }
  /// Frames whose view image was re-rendered (the model's frame changed), for the report.
  const std::vector<int>& renders() const { return renders_; }
  int frame() const { return frame_; }
  const std::string& message() const { return message_; }
  void set_message(std::string m) { message_ = std::move(m); }
  /// The file the user asked to open this frame (the window loads it, then replaces the model).
  std::optional<std::string> take_open_request();
  void request_open(std::string path) { open_request_ = std::move(path); }

 private:
  void draw_side_panel();
  void draw_joint_panel();
  void draw_clip_panel();
  void draw_method_panel();
  void draw_stats_panel();
  void draw_view(const ImVec2& at, const ImVec2& size);
  void render_view(int width, int height);
  void draw_joints(ImDrawList* dl, const ImVec2& at, const skinning::Camera& camera);
  void handle_view_input(const ImVec2& at, const ImVec2& size);

  ViewerModel& model_;
  double skin_wait_ms_;
  ViewState view_;
  Overlay overlay_{Overlay::kNone};
  Layout layout_;
  Texture texture_, texture_beside_;
  skinning::Camera camera_;
  float pixel_scale_{1.f};  ///< screen pixels per rendered pixel
  Eigen::AlignedBox3d box_;
  long rendered_id_{-1};
  int rendered_w_{0}, rendered_h_{0};
  bool dirty_{true};
  bool playing_{false};
  int frame_{0};
  std::vector<int> renders_;
  std::string message_;
  char pose_path_[512] = "pose.json";
  char bake_path_[512] = "clip.glb";
  char open_path_[512] = "";
  std::optional<std::string> open_request_;
};

}  // namespace isokit::viewer::gui
