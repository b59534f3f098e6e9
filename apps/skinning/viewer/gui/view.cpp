// SPDX-License-Identifier: MIT
// The viewer's 3D view: the shown frame rendered by the software rasterizer into a texture (with
// the overlay's colours), the joints drawn over it, orbit / zoom / pan and joint picking.
#include <algorithm>
#include <cmath>

#include "viewer_gui.h"

namespace isokit::viewer::gui {

namespace {

/// Per-face (interpenetration, folds, intersecting, inverted) or per-vertex (contacts, mask, distance to DQS)
/// colours of `overlay`; the other set stays empty.
void overlay_colours(Overlay overlay, const Overlays& o, std::size_t nv, std::size_t nt,
                     skinning::RenderOptions& options) {
  const Eigen::Vector3f base = options.base_color, hot(kOverlayRgb[0], kOverlayRgb[1], kOverlayRgb[2]);
  auto faces = [&](const std::vector<std::uint8_t>& flag) {
    options.face_colors.resize(Eigen::Index(nt), 3);
    for (std::size_t f = 0; f < nt; ++f)
      options.face_colors.row(Eigen::Index(f)) = (flag[f] ? hot : base).transpose();
  };
  auto vertices = [&](auto&& weight) {
    options.vertex_colors.resize(Eigen::Index(nv), 3);
    for (std::size_t v = 0; v < nv; ++v) {
      const float w = std::clamp(weight(v), 0.f, 1.f);
      options.vertex_colors.row(Eigen::Index(v)) = (base * (1.f - w) + hot * w).transpose();
    }
  };
  switch (overlay) {
    case Overlay::kNone:
      break;
    case Overlay::kOverlap:
      faces(o.overlap);
      break;
    case Overlay::kFolds:
      faces(o.folded);
      break;
    case Overlay::kIntersecting:
      faces(o.intersecting);
      break;
    case Overlay::kInverted:
      faces(o.inverted);
      break;
    case Overlay::kContacts:
      vertices([&](std::size_t v) { return o.contact[v] ? 1.f : 0.f; });
      break;
    case Overlay::kMask:
      vertices([&](std::size_t v) { return 1.f - o.mask[v]; });
      break;
    case Overlay::kDqsDistance: {
      const float top = std::max(1e-12f, *std::max_element(o.dqs_distance.begin(), o.dqs_distance.end()));
      vertices([&](std::size_t v) { return o.dqs_distance[v] / top; });
      break;
    }
  }
}

}  // namespace

void Panels::render_view(int width, int height) {
  const skinning::Rig& rig = model_.rig();
  skinning::RenderOptions o = view_.options(box_, width, height);
  if (overlay_ != Overlay::kNone)
    overlay_colours(overlay_, model_.overlays(), std::size_t(rig.rest.rows()),
                    std::size_t(rig.triangles.rows()), o);
  camera_ = skinning::frame_camera(o, o.frame);
  const skinning::Image main_view = skinning::render_mesh(model_.positions(), rig.triangles, o);
  texture_.upload(main_view.width, main_view.height, main_view.rgba.data());
  if (const track::Positions* beside = model_.compare_positions()) {
    o.face_colors.resize(0, 3);
    o.vertex_colors.resize(0, 3);
    const skinning::Image beside_view = skinning::render_mesh(*beside, rig.triangles, o);
    texture_beside_.upload(beside_view.width, beside_view.height, beside_view.rgba.data());
  }
  rendered_id_ = model_.shown_id();
  rendered_w_ = width, rendered_h_ = height;
  renders_.push_back(frame_);
  dirty_ = false;
}

void Panels::draw_view(const ImVec2& at, const ImVec2& size) {
  ImGui::SetNextWindowPos(at);
  ImGui::SetNextWindowSize(size);
  ImGui::PushStyleVar(ImGuiStyleVar_WindowPadding, ImVec2(0, 0));
  ImGui::Begin(
      "view", nullptr,
      ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoBringToFrontOnFocus);
  const bool beside = model_.compare().has_value();
  const int w = int(size.x) / (beside ? 2 : 1), h = int(size.y);
  // During a slider drag the view is rendered at half resolution: the software rasterizer then
  // leaves the cores to the tracker (the skin shown lags less), and the full view follows the drag.
  const int div = model_.dragging() ? 2 : 1;
  if (dirty_ || rendered_id_ != model_.shown_id() || w / div != rendered_w_ || h / div != rendered_h_)
    render_view(w / div, h / div);
  pixel_scale_ = float(w) / float(std::max(rendered_w_, 1));
  ImGui::Image(texture_.id(), ImVec2(float(w), float(h)));
  layout_.view_min = at;
  layout_.view_max = ImVec2(at.x + float(w), at.y + float(h));
  handle_view_input(at, ImVec2(float(w), float(h)));
  if (beside) {
    ImGui::SameLine(0, 0);
    ImGui::Image(texture_beside_.id(), ImVec2(float(w), float(h)));
  }
  ImDrawList* dl = ImGui::GetWindowDrawList();
  draw_joints(dl, at, camera_);
  dl->AddText(ImVec2(at.x + 8, at.y + 6), IM_COL32(20, 20, 20, 255), skinning::to_string(model_.method()));
  if (beside)
    dl->AddText(ImVec2(at.x + float(w) + 8, at.y + 6), IM_COL32(20, 20, 20, 255),
                skinning::to_string(*model_.compare()));
  ImGui::End();
  ImGui::PopStyleVar();
}

void Panels::draw_joints(ImDrawList* dl, const ImVec2& at, const skinning::Camera& camera) {
  const std::vector<Eigen::Vector3d> p = model_.joint_positions();
  layout_.joints.assign(p.size(), ImVec2(-1e6f, -1e6f));
  for (std::size_t j = 0; j < p.size(); ++j) {
    const Eigen::Vector3d s = camera.project(p[j]);
    if (s.z() > 0)
      layout_.joints[j] = ImVec2(at.x + pixel_scale_ * float(s.x()), at.y + pixel_scale_ * float(s.y()));
  }
  const skinning::Rig& rig = model_.rig();
  const ImU32 bone = IM_COL32(kJointRgb[0], kJointRgb[1], kJointRgb[2], 200);
  for (std::size_t j = 0; j < p.size(); ++j)
    if (rig.joints[j].parent >= 0)
      dl->AddLine(layout_.joints[std::size_t(rig.joints[j].parent)], layout_.joints[j], bone, 2.f);
  for (std::size_t j = 0; j < p.size(); ++j) {
    const bool selected = int(j) == model_.selected_joint();
    const ImU32 c = selected ? IM_COL32(kSelectedRgb[0], kSelectedRgb[1], kSelectedRgb[2], 255)
                             : IM_COL32(kJointRgb[0], kJointRgb[1], kJointRgb[2], 255);
    dl->AddCircleFilled(layout_.joints[j], selected ? 7.f : 4.f, c);
  }
}

void Panels::handle_view_input(const ImVec2& at, const ImVec2& size) {
  const ImGuiIO& io = ImGui::GetIO();
  const ImVec2 m = io.MousePos;
  const bool inside = m.x >= at.x && m.y >= at.y && m.x < at.x + size.x && m.y < at.y + size.y;
  if (!inside || !ImGui::IsWindowHovered()) return;
  if (ImGui::IsMouseClicked(ImGuiMouseButton_Left)) {
    int best = -1;
    float best_d2 = 12.f * 12.f;
    for (std::size_t j = 0; j < layout_.joints.size(); ++j) {
      const float dx = layout_.joints[j].x - m.x, dy = layout_.joints[j].y - m.y;
      if (dx * dx + dy * dy < best_d2) best = int(j), best_d2 = dx * dx + dy * dy;
    }
    if (best >= 0) model_.select_joint(best);
  }
  if (ImGui::IsMouseDragging(ImGuiMouseButton_Right)) {
    view_.yaw -= 0.01 * double(io.MouseDelta.x);
    view_.pitch = std::clamp(view_.pitch + 0.01 * double(io.MouseDelta.y), -1.5, 1.5);
    dirty_ = true;
  }
  if (ImGui::IsMouseDragging(ImGuiMouseButton_Middle)) {
    view_.pan_x -= double(io.MouseDelta.x) / double(size.x) / view_.zoom;
    view_.pan_y += double(io.MouseDelta.y) / double(size.y) / view_.zoom;
    dirty_ = true;
  }
  if (io.MouseWheel != 0.f) {
    view_.zoom = std::clamp(view_.zoom * std::pow(1.15, double(io.MouseWheel)), 0.2, 20.0);
    dirty_ = true;
  }
}

}  // namespace isokit::viewer::gui
