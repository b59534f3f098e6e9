// SPDX-License-Identifier: MIT
// The studio's widgets: the operator slice with its curves (2014 Fig. 5/6), the side panel (d,
// progress, history, files, checks), the controller curve and the composition preview.
#include <GL/gl.h>

#include <algorithm>
#include <cmath>

#include "isokit/core/error.h"
#include "isokit/core/math.h"
#include "isokit/operators/controller.h"
#include "isokit/operators/spec.h"
#include "studio_gui.h"

namespace isokit::studio::gui {
namespace {

constexpr float kHandleRadius = 6.f;
constexpr double kPickPixels = 9.0;

ImU32 rgb(const std::uint8_t (&c)[3], std::uint8_t a = 255) {
  return IM_COL32(c[0], c[1], c[2], a);
}

ImVec2 to_im(const plot::Point2& p) {
  return ImVec2(float(p[0]), float(p[1]));
}

plot::Point2 mouse_pixel() {
  const ImVec2 m = ImGui::GetIO().MousePos;
  return {double(m.x), double(m.y)};
}

void draw_iso_sets(ImDrawList* dl, const PlotMapping& map, const std::vector<IsoLineSet>& sets) {
  for (const auto& set : sets) {
    const bool surface = std::abs(set.level - 0.5f) < 1e-3f;
    const ImU32 col = surface ? IM_COL32(255, 255, 255, 255) : IM_COL32(25, 25, 25, 200);
    for (const auto& s : set.segments)
      dl->AddLine(to_im(map.to_screen(s[0])), to_im(map.to_screen(s[1])), col, surface ? 2.5f : 1.0f);
  }
}

void draw_handle(ImDrawList* dl, const ImVec2& at, bool selected) {
  dl->AddCircleFilled(at, kHandleRadius + 1.5f, IM_COL32(0, 0, 0, 255), 16);
  dl->AddCircleFilled(at, kHandleRadius, rgb(selected ? kSelectedRgb : kHandleRgb), 16);
}

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

}  // namespace

// ---- Panels ----

Panels::Panels(StudioModel& model, GuiOptions options) : model_(model), options_(std::move(options)) {
  path_field_ = model_.document_path().empty() ? "operator.json" : model_.document_path();
  export_field_ = "operator.npy";
}

void Panels::report(const EditResult& r) {
  if (!r) report(r.message);
}

void Panels::report(const std::string& message) {
  status_ = message;
  messages_.push_back(message);
}

// The full-window panel has no background of its own: the frame's glClear paints it, which saves
// a blended full-screen layer (software GL is fill-bound).
void Panels::draw(FrameStats& stats) {
  const ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(io.DisplaySize);
  ImGui::Begin("isokit operator studio", nullptr,
               ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoSavedSettings |
                   ImGuiWindowFlags_NoBringToFrontOnFocus | ImGuiWindowFlags_NoBackground);
  handle_shortcuts();
  run_pending_actions();
  const float side = std::clamp(io.DisplaySize.x * 0.38f, 320.f, 520.f);
  ImGui::BeginChild("plot", ImVec2(io.DisplaySize.x - side - 24.f, 0), false, ImGuiWindowFlags_NoScrollbar);
  draw_operator_plot(stats);
  ImGui::EndChild();
  ImGui::SameLine();
  ImGui::BeginChild("side", ImVec2(0, 0), false);
  draw_side_panel();
  ImGui::EndChild();
  ImGui::End();
}

void Panels::handle_shortcuts() {
  const ImGuiIO& io = ImGui::GetIO();
  if (io.WantTextInput) return;
  const bool z = ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Z), false);
  const bool y = ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Y), false);
  if (io.KeyCtrl && z && !io.KeyShift) pending_ = Pending::kUndo;
  if (io.KeyCtrl && (y || (z && io.KeyShift))) pending_ = Pending::kRedo;
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Delete), false) && model_.selection())
    report(model_.delete_point(*model_.selection()));
}

void Panels::run_pending_actions() {
  if (pending_ == Pending::kNone || !model_.fully_solved()) return;
  const Pending action = pending_;
  pending_ = Pending::kNone;
  try {
    if (action == Pending::kUndo && !model_.undo()) report("nothing to undo");
    if (action == Pending::kRedo && !model_.redo()) report("nothing to redo");
    if (action == Pending::kSave) {
      model_.save_spec(path_field_);
      status_ = "saved " + path_field_;
    }
    if (action == Pending::kExport) {
      model_.export_grid(export_field_);
      status_ = "exported " + export_field_ + " and its .json";
    }
  } catch (const std::exception& e) {
    report(e.what());
  }
}

// ---- The operator slice ----

void Panels::draw_operator_plot(FrameStats& stats) {
  const ImVec2 avail = ImGui::GetContentRegionAvail();
  const float size = std::max(64.f, std::min(avail.x, avail.y) - 8.f - 2 * kPlotPad);
  const ImVec2 corner = ImGui::GetCursorScreenPos();
  const ImVec2 origin(corner.x + kPlotPad, corner.y + kPlotPad);
  layout_.op = PlotMapping{origin.x, origin.y, size, size, 0, 0, 1, 1};
  // The button reaches kPlotPad beyond the plot, so handles on its edges can be grabbed.
  ImGui::InvisibleButton("operator", ImVec2(size + 2 * kPlotPad, size + 2 * kPlotPad),
                         ImGuiButtonFlags_MouseButtonLeft | ImGuiButtonFlags_MouseButtonRight);
  handle_operator_input(stats);
  ImDrawList* dl = ImGui::GetWindowDrawList();
  draw_slice_layers(dl, stats);
  draw_check_marks(dl);
  draw_curves(dl);
  dl->AddText(ImVec2(origin.x + 6, origin.y + size - 18), IM_COL32(255, 255, 255, 255),
              ("f1 ->   g(f1, f2; d = " + fmt("%.3f", model_.d()) + ")").c_str());
}

void Panels::handle_operator_input(FrameStats& stats) {
  const PlotMapping& map = layout_.op;
  const plot::Point2 p = map.to_domain(mouse_pixel());
  const double radius = kPickPixels / map.width;
  if (ImGui::IsItemActivated() && ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
    if (const auto hit = model_.pick(p, radius)) {
      report(model_.begin_drag(*hit));
    } else if (const auto seg = model_.pick_segment(p, radius)) {
      report(model_.add_point(seg->curve, seg->segment, seg->t));
    } else {
      model_.select(std::nullopt);
    }
  }
  if (model_.dragging() && ImGui::IsItemActive()) {
    const ImVec2 delta = ImGui::GetIO().MouseDelta;
    if (delta.x != 0.f || delta.y != 0.f) {
      const EditResult r = model_.drag_to(p);
      if (r) stats.solve_ms.push_back(model_.last_solve_ms());
      report(r);
    }
  }
  if (model_.dragging() && !ImGui::IsItemActive()) model_.end_drag();
  if (ImGui::IsItemHovered() && ImGui::IsMouseClicked(ImGuiMouseButton_Right))
    if (const auto hit = model_.pick(p, radius)) report(model_.delete_point(*hit));
}

void Panels::draw_slice_layers(ImDrawList* dl, FrameStats& stats) {
  const int nf = model_.spec().resolution;
  const std::pair<int, long> key{model_.slice(), model_.slice_revision(model_.slice())};
  if (key != shown_slice_) {
    shown_slice_ = key;
    const plot::ScalarGrid grid = slice_grid(model_.slice_values(), nf);
    slice_tex_.upload(colour_image(grid));
    slice_iso_ = decile_iso_lines(grid);
    stats.last_upload_frame = stats.frame;
    stats.upload_frames.push_back(stats.frame);
  }
  const PlotMapping& m = layout_.op;
  // Texel centres sit on the grid nodes: the plot's corners are the corner nodes.
  const float half = 0.5f / float(nf);
  dl->AddImage(slice_tex_.id(), ImVec2(float(m.left), float(m.top)),
               ImVec2(float(m.left + m.width), float(m.top + m.height)), ImVec2(half, half),
               ImVec2(1.f - half, 1.f - half));
  draw_iso_sets(dl, m, slice_iso_);
}

void Panels::draw_curves(ImDrawList* dl) {
  const PlotMapping& m = layout_.op;
  const auto& curves = model_.spec().curves;
  for (int c = 0; c < int(curves.size()); ++c) {
    const bool contact = curves[c].kind == CurveKind::kContact;
    std::vector<ImVec2> line;
    for (const auto& q : model_.polyline(c)) line.push_back(to_im(m.to_screen(q)));
    dl->AddPolyline(line.data(), int(line.size()),
                    contact ? IM_COL32(30, 220, 60, 255) : IM_COL32(230, 60, 160, 255), ImDrawFlags_None,
                    3.f);
    const std::vector<plot::Point2> pts = model_.control_points(c);
    if (curves[c].type == CurveType::kBSpline)
      for (std::size_t i = 0; i + 1 < pts.size(); ++i)
        dl->AddLine(to_im(m.to_screen(pts[i])), to_im(m.to_screen(pts[i + 1])), IM_COL32(220, 220, 220, 160),
                    1.f);
    for (int i = 0; i < int(pts.size()); ++i)
      draw_handle(dl, to_im(m.to_screen(pts[i])),
                  model_.selection() == std::optional<CurvePoint>(CurvePoint{c, i}));
  }
}

void Panels::draw_check_marks(ImDrawList* dl) {
  const LiveCheck& check = model_.live_check();
  if (!check.failure) return;
  const PlotMapping& m = layout_.op;
  const ImU32 red = rgb(kCheckRgb);
  ImVec2 lo(1e9f, 1e9f), hi(-1e9f, -1e9f);
  for (const auto* set : {&check.stray_crossings, &check.unmatched_profile})
    for (const auto& q : *set) {
      const ImVec2 at = to_im(m.to_screen(q));
      dl->AddCircle(at, 5.f, red, 10, 2.5f);
      lo = ImVec2(std::min(lo.x, at.x), std::min(lo.y, at.y));
      hi = ImVec2(std::max(hi.x, at.x), std::max(hi.y, at.y));
    }
  if (lo.x <= hi.x)  // the offending region: the marks' bounding box, padded
    dl->AddRect(ImVec2(lo.x - 12, lo.y - 12), ImVec2(hi.x + 12, hi.y + 12), red, 4.f, ImDrawFlags_None, 2.5f);
  if (check.failure->check.rfind("boundary", 0) == 0)  // the failing edge values: outline the square
    dl->AddRect(ImVec2(float(m.left), float(m.top)), ImVec2(float(m.left + m.width), float(m.top + m.height)),
                red, 0.f, ImDrawFlags_None, 4.f);
}

}  // namespace isokit::studio::gui
