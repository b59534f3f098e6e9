// SPDX-License-Identifier: MIT
// The viewer's window and frame loop (GLFW + OpenGL 3.3 core + Dear ImGui), its script player and
// report. A script is a JSON object {"events": [...]}, one event per frame:
// - {"type": "move", "to": T, "frames": N}: the mouse to T in N steps (a drag while pressed);
//   T = {"px": [x, y]}, {"joint": NAME} (its dot in the view), {"slider": "x"|"y"|"z"|"frame",
//   "value": V} (the point of that slider for V: degrees, or a frame).
// - {"type": "press"} / {"type": "release"}: a mouse button ("button": 0 left, 1 right, 2 middle).
// - {"type": "wheel", "delta": D}; {"type": "frames", "n": N}; {"type": "wait_baked", "max_frames": N}.
// - {"type": "set", "method": M, "compare": M | "none", "overlay": O, "clip": C, "frame": F,
//   "open": PATH}: as the combos, the timeline and the open field would.
// - {"type": "screenshot", "name": NAME}: the window as SCREENSHOT_DIR/NAME.png, its state and pixel
//   counts in the report.
#define GLFW_INCLUDE_NONE
#include <GL/gl.h>
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "isokit/core/atomic_file.h"
#include "isokit/core/error.h"
#include "isokit/skinning/pipeline.h"
#include "isokit/viewer/gui.h"
#include "viewer_gui.h"

namespace isokit::viewer {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

/// The window's model options: baking in the background, an edit shown after `edit_slice_ms`.
ViewerOptions model_options(const ViewerGuiOptions& o) {
  ViewerOptions vo;
  vo.background = true;
  vo.edit_slice_ms = o.edit_slice_ms;
  return vo;
}

skinning::Image read_framebuffer(GLFWwindow* w) {
  skinning::Image img;
  img.rgba = gui_kit::read_framebuffer(w, img.width, img.height);
  return img;
}

/// Pixels of `img` inside `box` (x0, y0, x1, y1) within `tol` of colour `rgb` per channel.
long count_colour(const skinning::Image& img, const ImVec4& box, const std::uint8_t* rgb, int tol) {
  long n = 0;
  for (int y = std::max(0, int(box.y)); y < std::min(img.height, int(box.w)); ++y)
    for (int x = std::max(0, int(box.x)); x < std::min(img.width, int(box.z)); ++x) {
      const std::uint8_t* p =
          img.rgba.data() + 4 * (std::size_t(y) * std::size_t(img.width) + std::size_t(x));
      if (std::abs(p[0] - rgb[0]) <= tol && std::abs(p[1] - rgb[1]) <= tol && std::abs(p[2] - rgb[2]) <= tol)
        ++n;
    }
  return n;
}

/// The script: events, the one being played, and the mouse.
class Player {
 public:
  explicit Player(const std::string& path);
  bool done() const { return next_ >= events_.size(); }
  /// Feeds this frame's input to ImGui (before NewFrame); applies "set" events to the model.
  void apply_input(ImGuiIO& io, const gui::Layout& layout, ViewerModel& model, gui::Panels& panels);
  /// After the frame is drawn: the screenshot to take, if the event was one.
  const json* finish_frame(const ViewerModel& model);
  const std::vector<int>& drag_frames() const { return drag_frames_; }
  std::vector<std::string> failures;

 private:
  ImVec2 target(const json& t, const gui::Layout& layout, const ViewerModel& model);
  std::vector<json> events_;
  std::size_t next_{0};
  int step_{0}, frame_{0};
  ImVec2 mouse_{10, 10}, from_{10, 10};
  bool pressed_{false};
  int button_{0};
  std::vector<int> drag_frames_;
};

Player::Player(const std::string& path) {
  std::ifstream in(path);
  require(bool(in), path, "cannot be read", "check the script path");
  std::stringstream ss;
  ss << in.rdbuf();
  json j;
  try {
    j = json::parse(ss.str());
  } catch (const json::exception& e) {
    throw InputError(path + ": not valid JSON (" + e.what() + "); fix the script");
  }
  require(j.is_object() && j.contains("events") && j["events"].is_array(), path, "needs an \"events\" list",
          "see apps/skinning/viewer/gui/window.cpp for the events");
  for (std::size_t k = 0; k < j["events"].size(); ++k) {
    const json& e = j["events"][k];
    const std::string where = path + ": events[" + std::to_string(k) + "]";
    require(e.is_object() && e.contains("type") && e["type"].is_string(), where, "has no \"type\"",
            "give each event a type");
    const std::string type = e["type"].get<std::string>();
    static const char* const kTypes[] = {"move",   "press",      "release", "wheel",
                                         "frames", "wait_baked", "set",     "screenshot"};
    require(std::find(std::begin(kTypes), std::end(kTypes), type) != std::end(kTypes), where,
            "unknown type '" + type + "'",
            "use move, press, release, wheel, frames, wait_baked, set or screenshot");
    if (type == "move") {
      const json* t = e.contains("to") ? &e["to"] : nullptr;
      const bool px = t && t->is_object() && t->contains("px") && (*t)["px"].is_array() &&
                      (*t)["px"].size() == 2 && (*t)["px"][0].is_number() && (*t)["px"][1].is_number();
      const bool joint = t && t->is_object() && t->contains("joint") && (*t)["joint"].is_string();
      const bool slider = t && t->is_object() && t->contains("slider") && (*t)["slider"].is_string() &&
                          (!t->contains("value") || (*t)["value"].is_number());
      require(px || joint || slider, where + ".to", "is not a target",
              R"(give {"px": [x, y]}, {"joint": NAME} or {"slider": "x", "value": V})");
    }
    require(!e.contains("delta") || e["delta"].is_number(), where + ".delta", "must be a number",
            "fix the script");
    for (const char* key : {"frames", "n", "max_frames", "button", "frame"})
      require(!e.contains(key) || e[key].is_number_integer(), where + "." + key, "must be an integer",
              "fix the script");
    for (const char* key : {"method", "compare", "overlay", "clip", "open", "name"})
      require(!e.contains(key) || e[key].is_string(), where + "." + key, "must be a string",
              "fix the script");
    events_.push_back(e);
  }
}

ImVec2 Player::target(const json& t, const gui::Layout& layout, const ViewerModel& model) {
  if (t.contains("px")) return ImVec2(t["px"][0].get<float>(), t["px"][1].get<float>());
  if (t.contains("joint")) {
    const int j = model.rig().joint_index(t["joint"].get<std::string>());
    if (j >= 0 && std::size_t(j) < layout.joints.size()) return layout.joints[std::size_t(j)];
    failures.push_back("no joint '" + t["joint"].get<std::string>() + "' in the view");
    return mouse_;
  }
  const std::string s = t.value("slider", "");
  const auto it = layout.sliders.find(s);
  if (it == layout.sliders.end()) {
    failures.push_back("no slider '" + s + "' on screen");
    return mouse_;
  }
  const ImVec4 r = it->second;
  const double v = t.value("value", 0.0);
  const double u = s == "frame" ? v / std::max(1, model.frame_count() - 1) : (v + 180.0) / 360.0;
  // The slider's value area is the item's width minus the label (about 15 px for one letter).
  const float x0 = r.x + 6.f, x1 = r.z - 6.f - (s == "frame" ? 45.f : 15.f);
  return ImVec2(x0 + float(std::clamp(u, 0.0, 1.0)) * (x1 - x0), 0.5f * (r.y + r.w));
}

void Player::apply_input(ImGuiIO& io, const gui::Layout& layout, ViewerModel& model, gui::Panels& panels) {
  ++frame_;
  if (done()) return;
  const json& e = events_[next_];
  const std::string type = e["type"].get<std::string>();
  if (type == "move") {
    const int n = std::max(1, e.value("frames", 1));
    if (step_ == 0) from_ = mouse_;
    ++step_;
    const ImVec2 to = target(e["to"], layout, model);
    const float t = float(step_) / float(n);
    mouse_ = ImVec2(from_.x + t * (to.x - from_.x), from_.y + t * (to.y - from_.y));
    if (pressed_) drag_frames_.push_back(frame_);
  } else if (type == "press" || type == "release") {
    pressed_ = type == "press";
    button_ = std::clamp(e.value("button", 0), 0, 2);
  } else if (type == "wheel") {
    io.MouseWheel += e.value("delta", 0.f);
  } else if (type == "set") {
    if (e.contains("method")) model.set_method(skinning::method_from_string(e["method"].get<std::string>()));
    if (e.contains("compare")) {
      const std::string c = e["compare"].get<std::string>();
      model.set_compare(c == "none" ? std::nullopt : std::optional<Method>(skinning::method_from_string(c)));
    }
    if (e.contains("overlay"))
      for (int o = 0; o <= int(gui::Overlay::kDqsDistance); ++o)
        if (e["overlay"].get<std::string>() == gui::to_string(gui::Overlay(o)))
          panels.set_overlay(gui::Overlay(o));
    if (e.contains("clip")) model.play_clip(e["clip"].get<std::string>());
    if (e.contains("frame")) model.set_frame(e["frame"].get<int>());
    if (e.contains("open")) panels.request_open(e["open"].get<std::string>());
  }
  io.MousePos = mouse_;
  // The GLFW backend sets the buttons from the real mouse each frame: the script's state wins.
  for (int b = 0; b < 3; ++b) io.MouseDown[b] = pressed_ && b == button_;
}

const json* Player::finish_frame(const ViewerModel& model) {
  if (done()) return nullptr;
  const json& e = events_[next_];
  const std::string type = e["type"].get<std::string>();
  bool finished = true;
  if (type == "move") finished = step_ >= std::max(1, e.value("frames", 1));
  if (type == "frames") finished = ++step_ >= e.value("n", 1);
  if (type == "wait_baked") finished = !model.pending() || ++step_ >= e.value("max_frames", 600);
  if (!finished) return nullptr;
  step_ = 0;
  ++next_;
  return type == "screenshot" ? &e : nullptr;
}

/// The state the gui test checks, with pixel counts of the shot.
json shot_state(const json& e, const skinning::Image& img, ViewerModel& model, const gui::Panels& panels,
                const std::string& file) {
  const gui::Layout& l = panels.layout();
  const ImVec4 view(l.view_min.x, l.view_min.y, l.view_max.x, l.view_max.y);
  const std::uint8_t red[3] = {std::uint8_t(255 * 0.97f), 30, 30};
  const int j = model.selected_joint();
  json angles = j >= 0 ? json(model.joint_angles(j)) : json(nullptr);
  const track::Positions& p = model.positions();
  return {{"name", e.value("name", "")},
          {"file", file},
          {"selected", j >= 0 ? json(model.rig().joints[std::size_t(j)].name) : json(nullptr)},
          {"angles", angles},
          {"method", skinning::to_string(model.method())},
          {"overlay", gui::to_string(panels.overlay())},
          {"clip", model.clip()},
          {"frame", model.frame()},
          {"pending", model.pending()},
          {"message", panels.message()},
          {"joints", model.rig().joints.size()},
          {"positions_sum", double(p.cast<double>().sum())},
          {"selected_pixels", count_colour(img, view, gui::kSelectedRgb, 20)},
          {"joint_pixels", count_colour(img, view, gui::kJointRgb, 20)},
          {"overlay_pixels", count_colour(img, view, red, 60)},
          // Triangles the folds overlay flags (folds hide inside creases: pixels cannot show them).
          {"folded_triangles", std::count(model.overlays().folded.begin(), model.overlays().folded.end(), 1)},
          {"view", {view.x, view.y, view.z, view.w}}};
}

/// A model of the rig at `path` with the setup at `setup_path` ("" = the defaults): read and fitted,
/// with the stages reported to `progress`. \throw InputError naming the file.
std::unique_ptr<ViewerModel> open_model(const std::string& path, const std::string& setup_path, Method method,
                                        const ViewerOptions& vo, const skinning::Progress& progress) {
  const skinning::SkinSetup setup =
      setup_path.empty() ? skinning::SkinSetup{} : skinning::load_setup(setup_path);
  auto sk = std::make_shared<skinning::Skinner>(skinning::open_rig(path, 30, progress, nullptr, setup.mask),
                                                setup, progress);
  return std::make_unique<ViewerModel>(sk, method, vo);
}

/// A rig opened from the window: read and fitted on its own thread, with its progress and its
/// error for the window to show.
class Opener {
 public:
  Opener(std::string path, std::string setup_path, Method method, ViewerOptions vo)
      : path_(std::move(path)), thread_([this, setup_path, method, vo] { run(setup_path, method, vo); }) {}
  ~Opener() { thread_.join(); }
  bool done() const { return done_; }
  std::string progress() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return stage_;
  }
  /// The finished model, or the one-line error (after done()).
  std::unique_ptr<ViewerModel>& model() { return model_; }
  const std::string& error() const { return error_; }
  const std::string& path() const { return path_; }

 private:
  void run(const std::string& setup_path, Method method, const ViewerOptions& vo) {
    try {
      model_ =
          open_model(path_, setup_path, method, vo, [this](const std::string& stage, int done, int total) {
            std::lock_guard<std::mutex> lock(mutex_);
            stage_ = stage + " " + std::to_string(done) + " / " + std::to_string(total);
          });
    } catch (const std::exception& e) {
      error_ = e.what();
    }
    done_ = true;
  }
  std::string path_;
  mutable std::mutex mutex_;
  std::string stage_{"reading"};
  std::unique_ptr<ViewerModel> model_;
  std::string error_;
  std::atomic<bool> done_{false};
  std::thread thread_;
};

/// While a rig is being opened: a small window with the stage and its progress.
void draw_opening(const Opener& opener) {
  ImGui::SetNextWindowPos(ImVec2(360, 20));
  ImGui::Begin("opening", nullptr, ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoCollapse);
  ImGui::Text("opening %s", opener.path().c_str());
  ImGui::Text("%s", opener.progress().c_str());
  ImGui::End();
}

/// The script's report: the screenshots, the drag's redraw rate and the lag of the skin shown.
json report_of(const Player& player, const json& shots, const std::vector<double>& frame_ms,
               const std::vector<long>& requested, const std::vector<long>& shown, const json& bakes,
               const gui::Panels& panels) {
  std::vector<int> lag;  // per drag frame: frames since the request now shown was made
  std::vector<double> drag_ms;
  for (const int f : player.drag_frames()) {
    const std::size_t k = std::size_t(std::min<int>(f, int(shown.size())) - 1);
    std::size_t g = 0;
    while (g < k && requested[g] < shown[k]) ++g;
    lag.push_back(int(k - g));
    if (k < frame_ms.size()) drag_ms.push_back(frame_ms[k]);
  }
  std::sort(drag_ms.begin(), drag_ms.end());
  const double median = drag_ms.empty() ? 0.0 : drag_ms[drag_ms.size() / 2];
  std::vector<double> bake_ms;
  for (const json& b : bakes) bake_ms.push_back(b[0].get<double>());
  std::sort(bake_ms.begin(), bake_ms.end());
  return {{"screenshots", shots},
          {"script_failures", player.failures},
          {"drag",
           {{"frames", drag_ms.size()},
            {"frame_ms_median", median},
            {"fps", median > 0 ? 1000.0 / median : 0.0},
            {"lag_frames_max", lag.empty() ? 0 : *std::max_element(lag.begin(), lag.end())},
            {"lag_frames", lag},
            {"bake_ms_median", bake_ms.empty() ? 0.0 : bake_ms[bake_ms.size() / 2]},
            {"bakes", bakes}}},
          {"frames", frame_ms.size()},
          {"message", panels.message()},
          {"gl_renderer", reinterpret_cast<const char*>(glGetString(GL_RENDERER))}};
}

/// The model of the rig on the command line (read and fitted before the window opens).
std::unique_ptr<ViewerModel> initial_model(const ViewerGuiOptions& o) {
  auto model = open_model(o.rig, o.setup, skinning::method_from_string(o.method), model_options(o),
                          [](const std::string& stage, int done, int total) {
                            std::fprintf(stderr, "\r  %-24s %d / %d", stage.c_str(), done, total);
                            if (done == total) std::fprintf(stderr, "\n");
                          });
  if (!o.clip.empty()) model->play_clip(o.clip), model->wait_idle();
  return model;
}

}  // namespace

int run_viewer(const ViewerGuiOptions& o) {
  require(o.width >= 320 && o.width <= 8192 && o.height >= 200 && o.height <= 8192, "isokit-skin view --size",
          "must be 320 to 8192 pixels wide (got " + std::to_string(o.width) + ")", "give e.g. --size 1280");
  std::unique_ptr<Player> player;  // a bad script fails before anything is fitted
  if (!o.script_path.empty()) player = std::make_unique<Player>(o.script_path);
  if (player) {  // the script's outputs: their folders exist before anything runs
    make_output_folder(o.screenshot_dir.empty() ? "." : o.screenshot_dir,
                       "isokit-skin view --screenshot-dir");
    const std::string parent = std::filesystem::path(o.report_path).parent_path().string();
    if (!o.report_path.empty() && !parent.empty())
      make_output_folder(parent, "isokit-skin view --report's folder");
  }
  gui_kit::GlfwSession glfw("isokit-skin view");  // without a display, fail before fitting anything
  std::unique_ptr<ViewerModel> model = initial_model(o);
  GLFWwindow* window = gui_kit::open_window("isokit-skin view", "isokit skinning viewer", o.width, o.height,
                                            !o.script_path.empty(), true);
  gui_kit::ImGuiSession imgui(window);
  auto panels = std::make_unique<gui::Panels>(*model, o.skin_wait_ms);
  std::unique_ptr<Opener> opener;
  json shots = json::array();
  std::vector<double> frame_ms;
  std::vector<long> requested, shown;
  json bakes = json::array();  // per new frame shown: [ms, sub-steps, iterations, capped calls]
  while (!glfwWindowShouldClose(window) && !(player && player->done())) {
    const auto t0 = Clock::now();
    glfwPollEvents();
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    if (player) player->apply_input(ImGui::GetIO(), panels->layout(), *model, *panels);
    ImGui::NewFrame();
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(window, &fw, &fh);
    panels->draw(fw, fh);
    if (auto path = panels->take_open_request(); path && !opener)
      opener = std::make_unique<Opener>(*path, o.setup, model->method(), model_options(o));
    if (opener) draw_opening(*opener);
    ImGui::Render();
    glViewport(0, 0, fw, fh);
    glClearColor(0.06f, 0.06f, 0.07f, 1.f);
    glClear(GL_COLOR_BUFFER_BIT);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    if (player)
      if (const json* e = player->finish_frame(*model)) {
        const std::string file = o.screenshot_dir + "/" + e->value("name", "shot") + ".png";
        const skinning::Image img = read_framebuffer(window);
        skinning::write_png(img, file);
        shots.push_back(shot_state(*e, img, *model, *panels, file));
      }
    glfwSwapBuffers(window);
    if (opener && opener->done()) {  // the opened rig replaces the shown one, or its error is shown
      if (opener->model()) {
        panels.reset();
        model = std::move(opener->model());
        panels = std::make_unique<gui::Panels>(*model, o.skin_wait_ms);
      } else {
        panels->set_message(opener->error());  // names the file
      }
      opener.reset();
    }
    if (shown.empty() || model->shown_id() != shown.back()) {
      const skinning::FrameStats& st = model->stats();
      bakes.push_back({st.ms, st.substeps, st.iterations, st.capped_calls});
    }
    requested.push_back(model->request_id());
    shown.push_back(model->shown_id());
    frame_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
  if (player) {
    const std::string path = o.report_path.empty() ? o.screenshot_dir + "/viewer-report.json" : o.report_path;
    write_text_file_atomically(
        path, report_of(*player, shots, frame_ms, requested, shown, bakes, *panels).dump(1) + "\n");
    for (const std::string& f : player->failures)
      std::fprintf(stderr, "isokit-skin view: script: %s\n", f.c_str());
  }
  glfwDestroyWindow(window);
  return player && !player->failures.empty() ? 2 : 0;
}

}  // namespace isokit::viewer
