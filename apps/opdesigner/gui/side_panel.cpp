// SPDX-License-Identifier: MIT
// The studio's side panel: d, solve progress, history, files, checks, the controller d(α) and
// the live composition of two capsules (opdesigner::compose_field, shared with `compose`).
#include <imgui.h>
// imgui_stdlib.h needs imgui.h first.
#include <imgui_stdlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "isokit/core/math.h"
#include "isokit/operators/controller.h"
#include "studio_gui.h"

namespace isokit::studio::gui {
namespace {

ImVec2 to_im(const plot::Point2& p) {
  return ImVec2(float(p[0]), float(p[1]));
}

std::string fmt(const char* f, double v) {
  char b[96];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

}  // namespace

void Panels::draw_side_panel() {
  ImGui::Text("%s%s", model_.spec().name.c_str(), model_.modified() ? " (modified)" : "");
  ImGui::TextDisabled("%s", model_.document_path().empty() ? "new document" : model_.document_path().c_str());
  float d = float(model_.d());
  if (ImGui::SliderFloat("d", &d, 0.f, 1.f, "%.3f")) model_.set_d(d);
  ImGui::Text("slice %d of %d, %dx%d; re-solve %.2f ms (%s)", model_.slice(), model_.spec().slices,
              model_.spec().resolution, model_.spec().resolution, model_.last_solve_ms(),
              model_.last_solve_was_schur() ? "schur" : "refactor");
  draw_history_and_progress();
  ImGui::Separator();
  draw_curve_panel();
  ImGui::Separator();
  draw_file_panel();
  ImGui::Separator();
  draw_check_panel();
  ImGui::Separator();
  draw_controller_plot();
  ImGui::Separator();
  draw_preview();
  if (!status_.empty()) ImGui::TextWrapped("%s", status_.c_str());
}

void Panels::draw_history_and_progress() {
  ImGui::BeginDisabled(!model_.can_undo());
  if (ImGui::Button("Undo (Ctrl+Z)")) pending_ = Pending::kUndo;
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::BeginDisabled(!model_.can_redo());
  if (ImGui::Button("Redo (Ctrl+Y)")) pending_ = Pending::kRedo;
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::BeginDisabled(!model_.selection());
  if (ImGui::Button("Delete point") && model_.selection()) report(model_.delete_point(*model_.selection()));
  ImGui::EndDisabled();
  const SolveProgress p = model_.progress();
  if (!model_.fully_solved() && p.total > 0) {
    const std::string label = "solving " + std::to_string(p.done) + "/" + std::to_string(p.total) +
                              " slices" + (pending_ != Pending::kNone ? " (then the queued action)" : "");
    ImGui::ProgressBar(float(p.done) / float(p.total), ImVec2(-1, 0), label.c_str());
  } else {
    ImGui::ProgressBar(1.f, ImVec2(-1, 0), "all slices solved");
  }
  if (!model_.background_error().empty())
    ImGui::TextColored(ImVec4(1, 0.3f, 0.3f, 1), "background: %s", model_.background_error().c_str());
}

/// Per curve: its kind and keyframes (click one to show its d, x to delete it), a keyframe at the
/// displayed d, deleting the curve; and a new contact line.
void Panels::draw_curve_panel() {
  const auto& curves = model_.spec().curves;
  for (int c = 0; c < int(curves.size()); ++c) {
    ImGui::PushID(c);
    ImGui::Text("%d %s:", c, curves[c].kind == CurveKind::kContact ? "contact" : "boundary");
    for (int k = 0; k < int(curves[c].keyframes.size()); ++k) {
      const double kd = curves[c].keyframes[k].d;
      ImGui::SameLine();
      ImGui::PushID(k);
      if (ImGui::SmallButton(fmt("d=%.2f", kd).c_str())) model_.set_d(kd);
      ImGui::SameLine(0, 1);
      if (ImGui::SmallButton("x")) report(model_.delete_keyframe(c, k));
      ImGui::PopID();
    }
    ImGui::SameLine();
    if (ImGui::SmallButton("+ keyframe at d")) report(model_.add_keyframe(c));
    ImGui::SameLine();
    if (ImGui::SmallButton("delete curve")) report(model_.delete_curve(c));
    ImGui::PopID();
  }
  if (ImGui::SmallButton("+ contact line")) {
    report(model_.add_curve(CurveKind::kContact, CurveType::kPolyline, {{0.5, 0.5}, {0.6, 0.6}}));
  }
}

void Panels::draw_file_panel() {
  ImGui::InputText("spec", &path_field_);
  if (ImGui::Button("Open")) {
    try {
      model_.open(path_field_);
      status_ = "opened " + path_field_;
    } catch (const std::exception& e) {
      report(e.what());
    }
  }
  ImGui::SameLine();
  if (ImGui::Button("Save")) pending_ = Pending::kSave;
  ImGui::SameLine();
  if (ImGui::BeginCombo("##recent", "recent files", ImGuiComboFlags_NoPreview)) {
    for (const auto& f : model_.recent_files().files())
      if (ImGui::Selectable(f.c_str())) path_field_ = f;
    ImGui::EndCombo();
  }
  ImGui::InputText("grid .npy", &export_field_);
  if (ImGui::Button("Export grid (.npy + .json)")) pending_ = Pending::kExport;
}

void Panels::draw_check_panel() {
  const LiveCheck& check = model_.live_check();
  if (check.failure) {
    ImGui::TextColored(ImVec4(1, 0.35f, 0.35f, 1), "check failed (red marks): %s",
                       check.failure->check.c_str());
    ImGui::TextWrapped("%s; %s", check.failure->detail.c_str(), check.failure->fix.c_str());
  } else {
    ImGui::TextColored(ImVec4(0.4f, 1, 0.4f, 1), "checks ok%s", check.current ? "" : " (slice not current)");
  }
  const auto& r = check.report;
  ImGui::TextDisabled("bc %.1e  iso->profile %.2f cells  profile->iso %.2f cells  contact %.3f",
                      r.boundary_error, r.cell > 0 ? r.iso_to_profile / r.cell : 0.0,
                      r.cell > 0 ? r.profile_to_iso / r.cell : 0.0, r.contact_length);
}

void Panels::draw_controller_plot() {
  ImGui::Text("controller d(alpha): drag knots, click to add, right-click to delete");
  const float w = ImGui::GetContentRegionAvail().x, h = 130.f;
  const ImVec2 o = ImGui::GetCursorScreenPos();
  layout_.controller =
      PlotMapping{o.x + kPlotPad, o.y + kPlotPad, w - 2 * kPlotPad, h - 2 * kPlotPad, 0, 0, kPi, 1};
  const PlotMapping& m = layout_.controller;
  ImGui::InvisibleButton("controller", ImVec2(w, h),
                         ImGuiButtonFlags_MouseButtonLeft | ImGuiButtonFlags_MouseButtonRight);
  const std::vector<ControllerKnot> knots = model_.controller_knots();
  const ImVec2 mp = ImGui::GetIO().MousePos;
  const plot::Point2 p = m.to_domain({mp.x, mp.y});
  auto nearest = [&]() -> std::optional<int> {
    for (int i = 0; i < int(knots.size()); ++i) {
      const plot::Point2 s = m.to_screen({knots[i].alpha, knots[i].d});
      if (std::hypot(s[0] - mp.x, s[1] - mp.y) < 9.0) return i;
    }
    return std::nullopt;
  };
  if (ImGui::IsItemActivated() && ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
    if (const auto i = nearest())
      report(model_.begin_knot_drag(*i));  // the whole drag is one undo step
    else
      report(model_.add_knot(std::clamp(p[0], 0.0, kPi), std::clamp(p[1], 0.0, 1.0)));
  }
  if (model_.dragging_knot() && ImGui::IsItemActive() &&
      (ImGui::GetIO().MouseDelta.x != 0 || ImGui::GetIO().MouseDelta.y != 0))
    report(model_.drag_knot_to(std::clamp(p[0], 0.0, kPi), std::clamp(p[1], 0.0, 1.0)));
  if (model_.dragging_knot() && !ImGui::IsItemActive()) model_.end_drag();
  if (ImGui::IsItemHovered() && ImGui::IsMouseClicked(ImGuiMouseButton_Right))
    if (const auto i = nearest()) report(model_.delete_knot(*i));
  ImDrawList* dl = ImGui::GetWindowDrawList();
  dl->AddRectFilled(o, ImVec2(o.x + w, o.y + h), IM_COL32(30, 30, 40, 255));
  for (int q = 1; q < 4; ++q) {
    const float x = float(m.to_screen({q * kPi / 4, 0})[0]);
    dl->AddLine(ImVec2(x, o.y), ImVec2(x, o.y + h), IM_COL32(80, 80, 90, 255));
  }
  const std::vector<ControllerKnot> now = model_.controller_knots();
  const operators::Controller curve(now);
  std::vector<ImVec2> line;
  for (int s = 0; s <= 128; ++s)
    line.push_back(to_im(m.to_screen({kPi * s / 128, curve.eval(kPi * s / 128)})));
  dl->AddPolyline(line.data(), int(line.size()), IM_COL32(240, 200, 60, 255), ImDrawFlags_None, 2.f);
  for (const auto& k : now) {
    dl->AddCircleFilled(to_im(m.to_screen({k.alpha, k.d})), 6.5f, IM_COL32(0, 0, 0, 255), 12);
    dl->AddCircleFilled(to_im(m.to_screen({k.alpha, k.d})), 5.f, IM_COL32(240, 200, 60, 255), 12);
  }
  dl->AddText(ImVec2(o.x + 4, o.y + 2), IM_COL32(200, 200, 200, 255), "d=1");
  dl->AddText(ImVec2(o.x + w - 70, o.y + h - 16), IM_COL32(200, 200, 200, 255), "alpha=pi");
}

void Panels::draw_preview() {
  float angle = float(angle_deg_);
  if (ImGui::SliderFloat("bend (deg)", &angle, 0.f, 180.f, "%.0f")) angle_deg_ = angle;
  // Recomposed when the document (spec or grid: model_.revision()) or the angle changed.
  const std::pair<long, double> key{model_.revision(), angle_deg_};
  if (key != preview_key_) {
    opdesigner::ComposeOptions o;
    o.angle_deg = angle_deg_;
    o.samples = 141;
    const operators::Controller controller(model_.controller_knots());
    preview_ = opdesigner::compose_field(model_.grid(), controller.table(), o);
    preview_tex_.upload(colour_image(preview_.grid));
    preview_iso_ = decile_iso_lines(preview_.grid);
    preview_key_ = key;
  }
  const float size =
      std::max(80.f, std::min(ImGui::GetContentRegionAvail().x, ImGui::GetContentRegionAvail().y - 30.f));
  const ImVec2 o = ImGui::GetCursorScreenPos();
  layout_.preview = PlotMapping{o.x, o.y, size, size, -1.6, -1.6, 1.6, 1.6};
  ImGui::Dummy(ImVec2(size, size));
  ImDrawList* dl = ImGui::GetWindowDrawList();
  dl->AddImage(preview_tex_.id(), o, ImVec2(o.x + size, o.y + size));
  const PlotMapping& m = layout_.preview;
  for (const auto& set : preview_iso_) {
    const bool surface = std::abs(set.level - 0.5f) < 1e-3f;
    for (const auto& s : set.segments)
      dl->AddLine(to_im(m.to_screen(s[0])), to_im(m.to_screen(s[1])),
                  surface ? IM_COL32(255, 255, 255, 255) : IM_COL32(25, 25, 25, 160), surface ? 2.f : 1.f);
  }
  for (const auto& s : preview_.contact)
    dl->AddLine(to_im(m.to_screen(s[0])), to_im(m.to_screen(s[1])), IM_COL32(30, 220, 60, 255), 3.f);
  const auto& b = preview_.bones;
  dl->AddLine(to_im(m.to_screen(b[0])), to_im(m.to_screen(b[1])), IM_COL32(230, 60, 160, 200), 1.5f);
  dl->AddLine(to_im(m.to_screen(b[1])), to_im(m.to_screen(b[2])), IM_COL32(230, 60, 160, 200), 1.5f);
  ImGui::Text("contact length %.3f (green), max d %.2f", preview_.stats.contact_length, preview_.stats.max_d);
}

}  // namespace isokit::studio::gui
