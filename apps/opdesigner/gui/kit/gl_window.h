// SPDX-License-Identifier: MIT
// What the design studio's and the skinning viewer's windows share (isokit_gui_kit): the GLFW
// and Dear ImGui sessions, an OpenGL 3.3 core window, RGBA textures, and the framebuffer read
// back for screenshots. Build tree only.
#pragma once

#include <imgui.h>

#include <cstdint>
#include <string>
#include <vector>

struct GLFWwindow;

namespace isokit::gui_kit {

/// glfwInit / glfwTerminate. \throw InputError naming `app` without a display.
struct GlfwSession {
  explicit GlfwSession(const std::string& app);
  ~GlfwSession();
  GlfwSession(const GlfwSession&) = delete;
  GlfwSession& operator=(const GlfwSession&) = delete;
};

/// Dear ImGui on `window` (GLFW and OpenGL 3 backends, dark style, no ini file).
struct ImGuiSession {
  explicit ImGuiSession(GLFWwindow* window);
  ~ImGuiSession();
  ImGuiSession(const ImGuiSession&) = delete;
  ImGuiSession& operator=(const ImGuiSession&) = delete;
};

/// An OpenGL 3.3 core window, current; `scripted`: not resizable, no vsync.
/// \throw InputError naming `app` when it cannot be opened.
GLFWwindow* open_window(const std::string& app, const std::string& title, int width, int height,
                        bool scripted, bool vsync);

/// The back buffer as RGBA rows top to bottom (alpha 255); `width`, `height` receive its size.
std::vector<std::uint8_t> read_framebuffer(GLFWwindow* window, int& width, int& height);

/// A GL texture holding an RGBA image.
class Texture {
 public:
  Texture() = default;
  ~Texture();
  Texture(const Texture&) = delete;
  Texture& operator=(const Texture&) = delete;
  void upload(int width, int height, const std::uint8_t* rgba);
  ImTextureID id() const;

 private:
  unsigned int name_{0};
};

}  // namespace isokit::gui_kit
