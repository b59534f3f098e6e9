// SPDX-License-Identifier: MIT
#include "fuzz_util.h"

#include <unistd.h>
#include <filesystem>
#include <fstream>

namespace isokit::fuzz {

const std::string& scratch_dir() {
  static const std::string dir = [] {
    const auto p = std::filesystem::temp_directory_path() / ("isokit-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(p);
    return p.string();
  }();
  return dir;
}

std::string write_input(const std::uint8_t* data, std::size_t size, const std::string& name) {
  const std::string path = scratch_dir() + "/" + name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

}  // namespace isokit::fuzz
