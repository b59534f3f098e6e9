// SPDX-License-Identifier: MIT
#include "isokit/studio/recent_files.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "isokit/core/atomic_file.h"

namespace isokit::studio {

namespace fs = std::filesystem;

std::string default_recent_files_path() {
  const char* xdg = std::getenv("XDG_CONFIG_HOME");
  if (xdg && *xdg) return (fs::path(xdg) / "isokit" / "recent.json").string();
  const char* home = std::getenv("HOME");
  if (home && *home) return (fs::path(home) / ".config" / "isokit" / "recent.json").string();
  return "";
}

namespace {

std::vector<std::string> read_list(const std::string& path) {
  std::ifstream in(path);
  if (!in) return {};
  std::stringstream text;
  text << in.rdbuf();
  const nlohmann::json j = nlohmann::json::parse(text.str(), nullptr, false);
  std::vector<std::string> out;
  if (!j.is_object() || !j.contains("recent") || !j["recent"].is_array()) return out;
  for (const auto& item : j["recent"])
    if (item.is_string()) out.push_back(item.get<std::string>());
  return out;
}

}  // namespace

RecentFiles::RecentFiles(std::string path, int capacity)
    : path_(std::move(path)), capacity_(std::max(1, capacity)) {
  if (path_.empty()) return;
  files_ = read_list(path_);
  if (int(files_.size()) > capacity_) files_.resize(static_cast<std::size_t>(capacity_));
}

void RecentFiles::add(const std::string& file) {
  std::error_code ec;
  const fs::path absolute = fs::absolute(file, ec);
  const std::string name = ec ? file : absolute.lexically_normal().string();
  files_.erase(std::remove(files_.begin(), files_.end(), name), files_.end());
  files_.insert(files_.begin(), name);
  if (int(files_.size()) > capacity_) files_.resize(static_cast<std::size_t>(capacity_));
  store();
}

void RecentFiles::remove(const std::string& file) {
  files_.erase(std::remove(files_.begin(), files_.end(), file), files_.end());
  store();
}

void RecentFiles::store() {
  last_error_.clear();
  if (path_.empty()) return;
  try {
    std::error_code ec;
    fs::create_directories(fs::path(path_).parent_path(), ec);
    write_text_file_atomically(path_, nlohmann::json{{"recent", files_}}.dump(2) + "\n");
  } catch (const std::exception& e) {
    last_error_ = e.what();
  }
}

}  // namespace isokit::studio
