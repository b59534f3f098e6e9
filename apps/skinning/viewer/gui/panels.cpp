// SPDX-License-Identifier: MIT
// The viewer's widgets: the side panel (joints, pose edits, clips, methods, overlays, statistics)
// and the 3D view (software-rendered image, joints drawn over it, orbit / zoom / pan, picking).
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "isokit/core/error.h"
#include "viewer_gui.h"

namespace isokit::viewer::gui {

const char* to_string(Overlay o) {
  switch (o) {
    case Overlay::kNone:
      return "none";
    case Overlay::kOverlap:
      return "interpenetration";
    case Overlay::kFolds:
      return "folds";
    case Overlay::kIntersecting:
      return "self-intersections";
    case Overlay::kInverted:
      return "inverted triangles";
    case Overlay::kContacts:
      return "contacts";
    case Overlay::kMask:
      return "relaxation mask";
    case Overlay::kDqsDistance:
      return "distance to DQS";
  }
  return "?";
}

skinning::RenderOptions ViewState::options(const Eigen::AlignedBox3d& box, int width, int height) const {
  skinning::RenderOptions o;
  o.width = std::max(width, 16);
  o.height = std::max(height, 16);
  o.supersample = 1;
  o.view_direction =
      Eigen::Vector3d(-std::sin(yaw) * std::cos(pitch), -std::sin(pitch), -std::cos(yaw) * std::cos(pitch));
  o.up = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d forward = o.view_direction.normalized();
  const Eigen::Vector3d right = forward.cross(o.up).normalized(), up = right.cross(forward);
  const double diag = box.diagonal().norm();
  const Eigen::Vector3d centre = box.center() + diag * (pan_x * right + pan_y * up);
  const Eigen::Vector3d half = 0.5 * box.sizes() / std::max(zoom, 1e-3);
  o.frame = Eigen::AlignedBox3d(centre - half, centre + half);
  o.background = Eigen::Vector3f(0.93f, 0.94f, 0.96f);
  return o;
}

Panels::Panels(ViewerModel& model, double skin_wait_ms) : model_(model), skin_wait_ms_(skin_wait_ms) {
  for (Eigen::Index v = 0; v < model_.rig().rest.rows(); ++v)
    box_.extend(model_.rig().rest.row(v).cast<double>().transpose());
  for (const Eigen::Vector3d& p : model_.joint_positions()) box_.extend(p);
}

void Panels::draw(int width, int height) {
  ++frame_;
  if (model_.poll(skin_wait_ms_)) dirty_ = true;
  if (playing_ && !model_.clip().empty()) {
    model_.set_frame(model_.frame() + 1 < model_.frame_count() ? model_.frame() + 1 : 0);
  }
  const float side = 340.f;
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2(side, float(height)));
  ImGui::Begin("isokit", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  draw_side_panel();
  ImGui::End();
  draw_view(ImVec2(side, 0), ImVec2(float(width) - side, float(height)));
}

void Panels::draw_side_panel() {
  draw_method_panel();
  ImGui::Separator();
  draw_joint_panel();
  ImGui::Separator();
  draw_clip_panel();
  ImGui::Separator();
  draw_stats_panel();
  if (!message_.empty()) ImGui::TextWrapped("%s", message_.c_str());
}

std::optional<std::string> Panels::take_open_request() {
  std::optional<std::string> r;
  r.swap(open_request_);
  return r;
}

void Panels::draw_method_panel() {
  ImGui::InputText("##open", open_path_, sizeof(open_path_));
  ImGui::SameLine();
  if (ImGui::Button("open") && open_path_[0] != '\0') open_request_ = std::string(open_path_);
  const std::vector<Method> methods = skinning::all_methods();
  int m = int(std::find(methods.begin(), methods.end(), model_.method()) - methods.begin());
  std::vector<const char*> names;
  for (Method x : methods) names.push_back(skinning::to_string(x));
  if (ImGui::Combo("method", &m, names.data(), int(names.size()))) model_.set_method(methods[std::size_t(m)]);
  int c = model_.compare()
              ? 1 + int(std::find(methods.begin(), methods.end(), *model_.compare()) - methods.begin())
              : 0;
  std::vector<const char*> cnames{"none"};
  cnames.insert(cnames.end(), names.begin(), names.end());
  if (ImGui::Combo("beside", &c, cnames.data(), int(cnames.size())))
    model_.set_compare(c == 0 ? std::nullopt : std::optional<Method>(methods[std::size_t(c - 1)]));
  int o = int(overlay_);
  const char* overlays[] = {
      "none",     "interpenetration", "folds",          "self-intersections", "inverted triangles",
      "contacts", "relaxation mask",  "distance to DQS"};
  if (ImGui::Combo("overlay", &o, overlays, 8)) set_overlay(Overlay(o));
  if (ImGui::Button("reset view")) view_ = ViewState{}, dirty_ = true;
  ImGui::TextDisabled("view: right-drag turns, middle-drag pans, wheel zooms");
}

void Panels::draw_joint_panel() {
  const skinning::Rig& rig = model_.rig();
  ImGui::Text("joints (%zu): click one in the view or here", rig.joints.size());
  ImGui::BeginChild("joints", ImVec2(0, 150), true);
  for (std::size_t j = 0; j < rig.joints.size(); ++j)
    if (ImGui::Selectable(rig.joints[j].name.c_str(), model_.selected_joint() == int(j)))
      model_.select_joint(int(j));
  ImGui::EndChild();
  layout_.sliders.clear();
  const int j = model_.selected_joint();
  if (j >= 0) {
    std::array<double, 3> a = model_.joint_angles(j);
    const char* axes[3] = {"x", "y", "z"};
    for (int k = 0; k < 3; ++k) {
      float v = float(a[std::size_t(k)]);
      const bool changed = ImGui::SliderFloat(axes[k], &v, -180.f, 180.f, "%.1f deg");
      if (ImGui::IsItemActivated()) model_.begin_drag();
      if (changed) {
        a[std::size_t(k)] = v;
        model_.set_joint_angles(j, a);
      }
      if (ImGui::IsItemDeactivated()) model_.end_drag();
      const ImVec2 lo = ImGui::GetItemRectMin(), hi = ImGui::GetItemRectMax();
      layout_.sliders[axes[k]] = ImVec4(lo.x, lo.y, hi.x, hi.y);
    }
  }
  if (ImGui::Button("undo") && model_.can_undo()) model_.undo();
  ImGui::SameLine();
  if (ImGui::Button("redo") && model_.can_redo()) model_.redo();
  ImGui::SameLine();
  if (ImGui::Button("rest pose")) model_.reset_pose();
  ImGui::InputText("##pose", pose_path_, sizeof(pose_path_));
  ImGui::SameLine();
  if (ImGui::Button("save pose")) {
    try {
      model_.save_pose_script(pose_path_);
      message_ = std::string("saved ") + pose_path_;
    } catch (const std::exception& e) {
      message_ = e.what();
    }
  }
}

void Panels::draw_clip_panel() {
  const std::vector<std::string> clips = model_.clips();
  if (clips.empty()) {
    ImGui::TextUnformatted("no clip");
    return;
  }
  int c = int(std::find(clips.begin(), clips.end(), model_.clip()) - clips.begin());
  std::vector<const char*> names{"(edit the pose)"};
  for (const std::string& s : clips) names.push_back(s.c_str());
  int sel = model_.clip().empty() ? 0 : c + 1;
  if (ImGui::Combo("clip", &sel, names.data(), int(names.size()))) {
    if (sel == 0)
      model_.stop_clip();
    else
      model_.play_clip(clips[std::size_t(sel - 1)]);
  }
  if (!model_.clip().empty()) {
    ImGui::Checkbox("play", &playing_);
    int f = model_.frame();
    if (ImGui::SliderInt("frame", &f, 0, model_.frame_count() - 1)) model_.set_frame(f);
    const ImVec2 lo = ImGui::GetItemRectMin(), hi = ImGui::GetItemRectMax();
    layout_.sliders["frame"] = ImVec4(lo.x, lo.y, hi.x, hi.y);
    ImGui::InputText("##bake", bake_path_, sizeof(bake_path_));
    ImGui::SameLine();
    if (ImGui::Button("bake clip")) {
      try {
        model_.export_clip(bake_path_);
        message_ = std::string("wrote ") + bake_path_ + " (" + skinning::to_string(model_.method()) + ")";
      } catch (const std::exception& e) {
        message_ = e.what();
      }
    }
  }
}

void Panels::draw_stats_panel() {
  const skinning::FrameStats& s = model_.stats();
  ImGui::Text("%s: %.1f ms per frame", skinning::to_string(model_.method()), s.ms);
  ImGui::Text("tracker calls %d (at the cap %d), iterations %d", s.tracker_calls, s.capped_calls,
              s.iterations);
  const skinning::FrameMetrics& m = s.metrics;
  if (!model_.metrics_shown()) {
    ImGui::TextDisabled("(metrics: measured when the pose rests)");
  } else {
    ImGui::Text("new interpenetration %.4f %% of the volume", 100 * m.self_overlap_new);
    ImGui::Text("  of the skin alone %.4f %%", 100 * m.skin_overlap_new);
    ImGui::Text("folded triangles %d (new %d)", m.folded_triangles, m.folded_new);
    ImGui::Text("self-intersections %d (new %d)", m.self_intersections, m.self_intersections_new);
    ImGui::Text("inverted triangles %d (new %d)", m.inverted_triangles, m.new_inverted_triangles);
    ImGui::Text("edge distortion max %.3f, mean %.4f", m.edge_distortion_max, m.edge_distortion_mean);
  }
  ImGui::Text("frames baked %ld%s", model_.frames_baked(), model_.pending() ? " (baking...)" : "");
  ImGui::Text("%.0f fps", double(ImGui::GetIO().Framerate));
}

}  // namespace isokit::viewer::gui
