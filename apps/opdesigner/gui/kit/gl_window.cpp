// SPDX-License-Identifier: MIT
#include "gl_window.h"

#define GLFW_INCLUDE_NONE
#include <GL/gl.h>
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include <algorithm>
#include <cstdio>

#include "isokit/core/error.h"

namespace isokit::gui_kit {

GlfwSession::GlfwSession(const std::string& app) {
  glfwSetErrorCallback([](int code, const char* text) { std::fprintf(stderr, "glfw %d: %s\n", code, text); });
  require(glfwInit() == GLFW_TRUE, app, "cannot initialise GLFW (no display?)",
          "run it on a desktop, or headless under xvfb-run -a");
}

GlfwSession::~GlfwSession() {
  glfwTerminate();
}

ImGuiSession::ImGuiSession(GLFWwindow* w) {
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(w, true);
  ImGui_ImplOpenGL3_Init("#version 330 core");
}

ImGuiSession::~ImGuiSession() {
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
}

GLFWwindow* open_window(const std::string& app, const std::string& title, int width, int height,
                        bool scripted, bool vsync) {
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_RESIZABLE, scripted ? GLFW_FALSE : GLFW_TRUE);
  GLFWwindow* w = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  require(w != nullptr, app, "cannot open an OpenGL 3.3 window",
          "check the display and the GL driver (headless: xvfb-run with Mesa's libgl1-mesa-dri)");
  glfwMakeContextCurrent(w);
  glfwSwapInterval(vsync && !scripted ? 1 : 0);
  return w;
}

std::vector<std::uint8_t> read_framebuffer(GLFWwindow* w, int& width, int& height) {
  glfwGetFramebufferSize(w, &width, &height);
  const std::size_t row = 4 * static_cast<std::size_t>(width);
  std::vector<std::uint8_t> raw(row * static_cast<std::size_t>(height)), out(raw.size());
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, raw.data());
  for (int y = 0; y < height; ++y)  // GL rows are bottom to top
    std::copy_n(raw.data() + row * static_cast<std::size_t>(height - 1 - y), row,
                out.data() + row * static_cast<std::size_t>(y));
  for (std::size_t i = 3; i < out.size(); i += 4) out[i] = 255;
  return out;
}

Texture::~Texture() {
  if (name_ != 0) glDeleteTextures(1, &name_);
}

void Texture::upload(int width, int height, const std::uint8_t* rgba) {
  if (name_ == 0) glGenTextures(1, &name_);
  glBindTexture(GL_TEXTURE_2D, name_);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, width, height, 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
}

ImTextureID Texture::id() const {
  return reinterpret_cast<ImTextureID>(static_cast<std::uintptr_t>(name_));
}

}  // namespace isokit::gui_kit
