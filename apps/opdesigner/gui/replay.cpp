// SPDX-License-Identifier: MIT
// The script player: input events into the frame loop. Keys go through the GLFW backend's own
// key callback (the path a real key press takes); the mouse position and buttons are written to
// ImGui's IO after the backend's NewFrame (imgui 1.86 polls GLFW for them, and a synthetic
// button cannot be held through GLFW), so every widget sees exactly what a user's drag gives.
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>

#include <cfloat>

#include "isokit/core/error.h"
#include "studio_gui.h"

namespace isokit::studio::gui {
namespace {

int glfw_key(const std::string& key) {
  if (key.size() == 1 && key[0] >= 'A' && key[0] <= 'Z') return GLFW_KEY_A + (key[0] - 'A');
  if (key.size() == 1 && key[0] >= 'a' && key[0] <= 'z') return GLFW_KEY_A + (key[0] - 'a');
  if (key.size() == 1 && key[0] >= '0' && key[0] <= '9') return GLFW_KEY_0 + (key[0] - '0');
  if (key == "Delete") return GLFW_KEY_DELETE;
  if (key == "Escape") return GLFW_KEY_ESCAPE;
  if (key == "Enter") return GLFW_KEY_ENTER;
  require(false, "script key '" + key + "'", "is not supported", "use A-Z, 0-9, Delete, Escape or Enter");
  return GLFW_KEY_UNKNOWN;
}

}  // namespace

ScriptPlayer::ScriptPlayer(std::vector<ScriptEvent> events, GLFWwindow* window)
    : events_(std::move(events)), window_(window) {
  for (const auto& e : events_)
    if (e.kind == EventKind::kKey) glfw_key(e.key);  // unknown keys fail before the window runs
}

plot::Point2 ScriptPlayer::resolve(const ScriptTarget& t, const Layout& layout, StudioModel& model) const {
  switch (t.kind) {
    case TargetKind::kPixel:
      return t.at;
    case TargetKind::kOperator:
      return layout.op.to_screen(t.at);
    case TargetKind::kController:
      return layout.controller.to_screen(t.at);
    case TargetKind::kPreview:
      return layout.preview.to_screen(t.at);
    case TargetKind::kControlPoint: {
      const int curves = int(model.spec().curves.size());
      require(t.curve >= 0 && t.curve < curves, "script target point [" + std::to_string(t.curve) + ", ...]",
              "names a curve that does not exist", "the spec has " + std::to_string(curves) + " curves");
      const auto pts = model.control_points(t.curve);
      require(t.index >= 0 && t.index < int(pts.size()),
              "script target point index " + std::to_string(t.index), "is out of range",
              "curve " + std::to_string(t.curve) + " has " + std::to_string(pts.size()));
      return layout.op.to_screen(pts[t.index]);
    }
    case TargetKind::kKnot: {
      const auto knots = model.controller_knots();
      require(t.index >= 0 && t.index < int(knots.size()), "script target knot " + std::to_string(t.index),
              "is out of range", "the controller has " + std::to_string(knots.size()) + " knots");
      return layout.controller.to_screen({knots[t.index].alpha, knots[t.index].d});
    }
  }
  return t.at;
}

void ScriptPlayer::apply_input(ImGuiIO& io, const Layout& layout, StudioModel& model, Panels& panels,
                               int frame) {
  if (key_release_) {
    ImGui_ImplGlfw_KeyCallback(window_, *key_release_, 0, GLFW_RELEASE, 0);
    if (ctrl_) ImGui_ImplGlfw_KeyCallback(window_, GLFW_KEY_LEFT_CONTROL, 0, GLFW_RELEASE, 0);
    if (shift_) ImGui_ImplGlfw_KeyCallback(window_, GLFW_KEY_LEFT_SHIFT, 0, GLFW_RELEASE, 0);
    key_release_.reset();
    release_frame_ = true;
  } else if (next_ < events_.size()) {
    const ScriptEvent& e = events_[next_];
    switch (e.kind) {
      case EventKind::kMove: {
        if (step_ == 0) {
          move_to_ = resolve(e.target, layout, model);
          move_from_ = mouse_[0] < 0 ? move_to_ : mouse_;
        }
        const double t = double(step_ + 1) / e.frames;
        mouse_ = {move_from_[0] + t * (move_to_[0] - move_from_[0]),
                  move_from_[1] + t * (move_to_[1] - move_from_[1])};
        if (down_[0]) drag_frames_.push_back(frame);
        break;
      }
      case EventKind::kPress:
      case EventKind::kRelease:
        down_[e.button] = e.kind == EventKind::kPress;
        break;
      case EventKind::kKey: {
        const int mods = (e.ctrl ? GLFW_MOD_CONTROL : 0) | (e.shift ? GLFW_MOD_SHIFT : 0);
        ctrl_ = e.ctrl;
        shift_ = e.shift;
        if (e.ctrl) ImGui_ImplGlfw_KeyCallback(window_, GLFW_KEY_LEFT_CONTROL, 0, GLFW_PRESS, mods);
        if (e.shift) ImGui_ImplGlfw_KeyCallback(window_, GLFW_KEY_LEFT_SHIFT, 0, GLFW_PRESS, mods);
        key_release_ = glfw_key(e.key);
        ImGui_ImplGlfw_KeyCallback(window_, *key_release_, 0, GLFW_PRESS, mods);
        break;
      }
      case EventKind::kSet:
        if (e.d) panels.set_d(*e.d);
        if (e.angle) panels.set_angle(*e.angle);
        break;
      default:
        break;
    }
  }
  io.MousePos = mouse_[0] < 0 ? ImVec2(-FLT_MAX, -FLT_MAX) : ImVec2(float(mouse_[0]), float(mouse_[1]));
  for (int b = 0; b < 3; ++b) io.MouseDown[b] = down_[b];
}

std::optional<ScriptEvent> ScriptPlayer::finish_frame(StudioModel& model) {
  if (release_frame_) {
    release_frame_ = false;
    return std::nullopt;
  }
  if (next_ >= events_.size()) return std::nullopt;
  const ScriptEvent e = events_[next_];
  ++step_;
  bool finished = true;
  if (e.kind == EventKind::kMove || e.kind == EventKind::kFrames) finished = step_ >= e.frames;
  if (e.kind == EventKind::kWaitSolved) {
    finished = model.fully_solved() || step_ >= e.frames;
    if (finished && !model.fully_solved())
      failures_.push_back("event " + std::to_string(next_ + 1) + " (wait_solved): not solved after " +
                          std::to_string(e.frames) + " frames");
  }
  if (e.kind == EventKind::kKey) finished = true;  // the release comes next frame
  if (finished) {
    ++next_;
    step_ = 0;
  }
  if (finished && (e.kind == EventKind::kScreenshot || e.kind == EventKind::kMark)) return e;
  return std::nullopt;
}

}  // namespace isokit::studio::gui
