// SPDX-License-Identifier: MIT
#include "isokit/core/atomic_file.h"

#include <atomic>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "isokit/core/error.h"

namespace isokit {
namespace {

namespace fs = std::filesystem;

/// The folder that holds `target` ("." for a bare file name).
fs::path folder_of(const fs::path& target) {
  return target.has_parent_path() ? target.parent_path() : fs::path(".");
}

/// `.<stem>.tmp-<pid>-<counter><extension>` beside the target: hidden, unique within the
/// process (counter) and between processes (pid), with the target's extension.
fs::path temporary_path(const fs::path& target) {
  static std::atomic<unsigned long> counter{0};
  const std::string name = "." + target.stem().string() + ".tmp-" + std::to_string(::getpid()) + "-" +
                           std::to_string(counter.fetch_add(1)) + target.extension().string();
  return folder_of(target) / name;
}

void check_target(const std::string& path) {
  const fs::path target(path);
  const std::string name = target.filename().string();
  require(!name.empty() && name != "." && name != "..", path, "has no file name",
          "give a file path such as out/result.json");
  std::error_code ec;
  const fs::path dir = folder_of(target);
  require(fs::is_directory(dir, ec), path, "the folder '" + dir.string() + "' does not exist",
          "create the folder first or choose another path");
  require(!fs::is_directory(target, ec), path, "is a folder", "give a file path");
}

}  // namespace

void write_file_atomically(const std::string& path, const std::function<void(const std::string&)>& writer) {
  check_target(path);
  const fs::path tmp = temporary_path(fs::path(path));
  try {
    writer(tmp.string());
    std::error_code ec;
    require(fs::is_regular_file(tmp, ec), path, "no file was written", "check that the folder is writable");
    fs::rename(tmp, path, ec);
    require(!ec, path, "cannot rename the temporary file over it (" + ec.message() + ")",
            "check the permissions of the folder and of an existing file");
  } catch (...) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw;
  }
}

void write_stream_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  write_file_atomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    require(out.is_open(), path,
            "cannot create a temporary file in '" + folder_of(fs::path(path)).string() + "'",
            "check that the folder is writable");
    write(out);
    out.flush();
    require(out.good(), path, "write failed", "check the free disk space and the folder's permissions");
    out.close();
    require(!out.fail(), path, "write failed when closing", "check the free disk space");
  });
}

void write_bytes_atomically(const std::string& path, const void* data, std::size_t size) {
  write_stream_atomically(path, [&](std::ostream& out) {
    out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
  });
}

void write_text_file_atomically(const std::string& path, const std::string& contents) {
  write_bytes_atomically(path, contents.data(), contents.size());
}

void make_output_folder(const std::string& dir, const std::string& what) {
  if (dir.empty()) return;
  std::error_code ec;
  fs::create_directories(dir, ec);
  const bool is_dir = fs::is_directory(dir, ec);
  require(is_dir, what + " '" + dir + "'",
          ec ? "cannot be created (" + ec.message() + ")" : "exists and is not a folder",
          "give a folder in a writable place");
}

}  // namespace isokit
