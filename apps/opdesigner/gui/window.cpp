// SPDX-License-Identifier: MIT
// The studio's window and frame loop: GLFW + OpenGL 3.3 core + Dear ImGui, the script player,
// screenshots (glReadPixels -> PNG) and the exit report.
#define GLFW_INCLUDE_NONE
#include <GL/gl.h>
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "isokit/core/atomic_file.h"
#include "isokit/core/error.h"
#include "kit/gl_window.h"
#include "studio_gui.h"

namespace isokit::studio {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

std::unique_ptr<StudioModel> open_model(const GuiOptions& o) {
  StudioOptions so;
  if (o.recent_files != "default") so.recent_files_path = o.recent_files;
  if (!o.spec_path.empty() && o.resolution <= 0) return StudioModel::open_file(o.spec_path, so);
  operators::OperatorSpec spec =
      o.spec_path.empty() ? operators::preset_spec(o.preset, 128) : operators::load_spec(o.spec_path);
  if (o.resolution > 0) spec.resolution = spec.slices = o.resolution;
  return std::make_unique<StudioModel>(spec, so);
}

plot::RgbaImage read_framebuffer(GLFWwindow* w) {
  plot::RgbaImage img;
  img.pixels = gui_kit::read_framebuffer(w, img.width, img.height);
  return img;
}

/// The model state the tests check: control points (operator and screen coordinates), history,
/// solving, the displayed slice and its check.
json snapshot(StudioModel& model, const gui::Layout& layout, int frame) {
  json points = json::array();
  for (int c = 0; c < int(model.spec().curves.size()); ++c) {
    const auto pts = model.control_points(c);
    for (int i = 0; i < int(pts.size()); ++i) {
      const plot::Point2 px = layout.op.to_screen(pts[i]);
      points.push_back({{"curve", c}, {"index", i}, {"op", {pts[i][0], pts[i][1]}}, {"px", {px[0], px[1]}}});
    }
  }
  const LiveCheck& check = model.live_check();
  json knots = json::array();
  for (const auto& k : model.controller_knots()) knots.push_back({k.alpha, k.d});
  json marks = json::array();
  for (const auto* set : {&check.stray_crossings, &check.unmatched_profile})
    for (const auto& q : *set) {
      const plot::Point2 px = layout.op.to_screen(q);
      marks.push_back({px[0], px[1]});
    }
  return {{"frame", frame},
          {"d", model.d()},
          {"slice", model.slice()},
          {"fully_solved", model.fully_solved()},
          {"can_undo", model.can_undo()},
          {"can_redo", model.can_redo()},
          {"modified", model.modified()},
          {"points", points},
          {"check", check.failure ? json(check.failure->message()) : json(nullptr)},
          {"check_marks_px", marks},
          {"knots", knots},
          {"plot", {layout.op.left, layout.op.top, layout.op.width, layout.op.height}}};
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * double(v.size() - 1) + 0.5))];
}

/// Frames from a drag input to the first redraw of the re-solved slice, the input frame counting
/// as one (1 = redrawn in the frame that received the input).
std::vector<int> latencies(const std::vector<int>& inputs, const std::vector<int>& uploads) {
  std::vector<int> out;
  for (const int f : inputs) {
    const auto it = std::lower_bound(uploads.begin(), uploads.end(), f);
    if (it != uploads.end()) out.push_back(*it - f + 1);
  }
  return out;
}

json timing_summary(const std::vector<double>& frame_ms, const gui::FrameStats& stats,
                    const std::vector<int>& drag_frames, double wall_s) {
  const std::vector<int> lat = latencies(drag_frames, stats.upload_frames);
  const std::vector<double> lat_d(lat.begin(), lat.end());
  return {{"frames", stats.frame},
          {"wall_s", wall_s},
          {"fps", wall_s > 0 ? stats.frame / wall_s : 0.0},
          {"frame_ms",
           {{"median", percentile(frame_ms, 0.5)},
            {"p10", percentile(frame_ms, 0.1)},
            {"p90", percentile(frame_ms, 0.9)}}},
          {"solve_ms",
           {{"count", stats.solve_ms.size()},
            {"median", percentile(stats.solve_ms, 0.5)},
            {"p10", percentile(stats.solve_ms, 0.1)},
            {"p90", percentile(stats.solve_ms, 0.9)},
            {"all", stats.solve_ms}}},
          {"latency_frames",
           {{"count", lat.size()},
            {"median", percentile(lat_d, 0.5)},
            {"max", lat.empty() ? 0 : *std::max_element(lat.begin(), lat.end())}}},
          {"frame_ms_all", frame_ms}};
}

json drag_summary(const std::vector<double>& frame_ms, const std::vector<int>& drag_frames) {
  std::vector<double> ms;
  for (const int f : drag_frames)
    if (f >= 0 && f < int(frame_ms.size())) ms.push_back(frame_ms[f]);
  const double median = percentile(ms, 0.5);
  return {{"frames", ms.size()},
          {"frame_ms_median", median},
          {"frame_ms_p90", percentile(ms, 0.9)},
          {"fps", median > 0 ? 1000.0 / median : 0.0}};
}

/// Runs the script's screenshot or mark after the frame is rendered.
void take(const ScriptEvent& e, GLFWwindow* w, StudioModel& model, const gui::Layout& layout, int frame,
          const GuiOptions& o, json& shots, json& marks) {
  json state = snapshot(model, layout, frame);
  state["name"] = e.name;
  if (e.kind == EventKind::kScreenshot) {
    const std::string file = o.screenshot_dir + "/" + e.name + ".png";
    plot::write_png(file, read_framebuffer(w));
    state["file"] = file;
    shots.push_back(state);
  } else {
    marks.push_back(state);
  }
}

}  // namespace
int run_gui(const GuiOptions& o) {
  std::vector<ScriptEvent> events;
  if (!o.script_path.empty()) events = load_script(o.script_path);
  if (!o.script_path.empty())  // the screenshots' folder exists before anything runs
    make_output_folder(o.screenshot_dir.empty() ? "." : o.screenshot_dir,
                       "isokit-opdesigner gui --screenshot-dir");
  gui_kit::GlfwSession glfw("the design studio");  // first: without a display, fail before solving anything
  std::unique_ptr<StudioModel> model = open_model(o);
  GLFWwindow* window = gui_kit::open_window("the design studio", "isokit operator studio", o.width, o.height,
                                            !o.script_path.empty(), o.vsync);
  gui_kit::ImGuiSession imgui(window);
  gui::Panels panels(*model, o);
  std::optional<gui::ScriptPlayer> player;
  if (!o.script_path.empty()) player.emplace(std::move(events), window);
  gui::FrameStats stats;
  std::vector<double> frame_ms, ui_ms;
  json shots = json::array(), marks = json::array();
  const auto start = Clock::now();
  while (!glfwWindowShouldClose(window) && !(player && player->done())) {
    const auto t0 = Clock::now();
    glfwPollEvents();
    model->poll();
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    if (player) player->apply_input(ImGui::GetIO(), panels.layout(), *model, panels, stats.frame);
    ImGui::NewFrame();
    const auto t_ui = Clock::now();
    panels.draw(stats);
    ImGui::Render();
    ui_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t_ui).count());
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(window, &fw, &fh);
    glViewport(0, 0, fw, fh);
    glClearColor(0.06f, 0.06f, 0.07f, 1.f);
    glClear(GL_COLOR_BUFFER_BIT);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    if (player)
      if (const auto e = player->finish_frame(*model))
        take(*e, window, *model, panels.layout(), stats.frame, o, shots, marks);
    glfwSwapBuffers(window);
    frame_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    ++stats.frame;
  }
  const double wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  std::string report_path = o.report_path;
  if (report_path.empty() && player) report_path = o.screenshot_dir + "/studio-report.json";
  if (!report_path.empty()) {
    const std::vector<int> drags = player ? player->drag_input_frames() : std::vector<int>{};
    json report = {{"timing", timing_summary(frame_ms, stats, drags, wall_s)},
                   {"drag", drag_summary(frame_ms, drags)},
                   {"drag_ui", drag_summary(ui_ms, drags)},
                   {"handle_rgb", {gui::kHandleRgb[0], gui::kHandleRgb[1], gui::kHandleRgb[2]}},
                   {"check_rgb", {gui::kCheckRgb[0], gui::kCheckRgb[1], gui::kCheckRgb[2]}},
                   {"screenshots", shots},
                   {"marks", marks},
                   {"final", snapshot(*model, panels.layout(), stats.frame)},
                   {"messages", panels.messages()},
                   {"script_failures", player ? player->failures() : std::vector<std::string>{}},
                   {"resolution", model->spec().resolution},
                   {"gl_renderer", reinterpret_cast<const char*>(glGetString(GL_RENDERER))},
                   {"window", {o.width, o.height}}};
    write_text_file_atomically(report_path, report.dump(1) + "\n");
  }
  glfwDestroyWindow(window);
  if (player)
    for (const auto& f : player->failures())
      std::fprintf(stderr, "isokit-opdesigner gui: script: %s\n", f.c_str());
  return player && !player->failures().empty() ? 2 : 0;
}

}  // namespace isokit::studio
