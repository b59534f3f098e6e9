// SPDX-License-Identifier: MIT
// The real rigs a benchmark runs on: every .glb / .gltf / .fbx of ISOKIT_RIGS (default
// ../shared/data/rigs), sorted, then ../shared/data/Fox.glb when they exist (none: an empty list).
#pragma once

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

namespace isokit::bench {

inline std::vector<std::string> real_rig_files() {
  namespace fs = std::filesystem;
  const char* env = std::getenv("ISOKIT_RIGS");
  const fs::path folder = env ? env : "../shared/data/rigs";
  std::error_code ec;
  std::vector<std::string> files;
  if (fs::is_directory(folder, ec))
    for (const auto& e : fs::directory_iterator(folder, ec)) {
      const std::string ext = e.path().extension().string();
      if (ext == ".glb" || ext == ".gltf" || ext == ".fbx") files.push_back(e.path().string());
    }
  std::sort(files.begin(), files.end());
  if (fs::exists("../shared/data/Fox.glb", ec)) files.push_back("../shared/data/Fox.glb");
  return files;
}

}  // namespace isokit::bench
