// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "isokit/core/atomic_file.h"
#include "isokit/core/error.h"

using namespace isokit;
namespace fs = std::filesystem;

namespace {

/// An empty scratch folder per test case.
fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("isokit_test_atomic_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string read_all(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> folder_entries(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  return names;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no InputError";
}

}  // namespace

TEST_CASE("atomic files: written, replaced, byte for byte", "[core][atomic_file]") {
  const fs::path dir = scratch("write");
  const std::string path = (dir / "out.json").string();
  write_text_file_atomically(path, "first\n");
  CHECK(read_all(path) == "first\n");
  write_text_file_atomically(path, "second, longer\r\n");
  CHECK(read_all(path) == "second, longer\r\n");
  const std::string binary("a\0b\xff\n", 5);
  write_bytes_atomically(path, binary.data(), binary.size());
  CHECK(read_all(path) == binary);
  write_stream_atomically(path, [](std::ostream& out) { out << "part 1, " << 2; });
  CHECK(read_all(path) == "part 1, 2");
  write_file_atomically(path,
                        [](const std::string& tmp) { std::ofstream(tmp, std::ios::binary) << "by name"; });
  CHECK(read_all(path) == "by name");
  CHECK(folder_entries(dir) == std::vector<std::string>{"out.json"});
}

TEST_CASE("atomic files: the temporary file is hidden, beside the target, with its extension",
          "[core][atomic_file]") {
  const fs::path dir = scratch("name");
  std::vector<fs::path> seen;
  for (int i = 0; i < 2; ++i)
    write_file_atomically((dir / "mesh.off").string(), [&](const std::string& tmp) {
      seen.emplace_back(tmp);
      std::ofstream(tmp) << "OFF\n0 0 0\n";
    });
  REQUIRE(seen.size() == 2);
  for (const fs::path& tmp : seen) {
    CHECK(tmp.parent_path() == dir);
    CHECK(tmp.filename().string().rfind(".mesh.tmp-", 0) == 0);
    CHECK(tmp.extension() == ".off");
  }
  CHECK(seen[0] != seen[1]);  // unique per call
  // A bare file name goes to the current folder.
  const fs::path cwd = fs::current_path();
  fs::current_path(dir);
  write_text_file_atomically("bare.txt", "x");
  fs::current_path(cwd);
  CHECK(read_all(dir / "bare.txt") == "x");
}

TEST_CASE("atomic files: no partial file on failure", "[core][atomic_file]") {
  const fs::path dir = scratch("failure");
  const std::string path = (dir / "out.glb").string();
  write_text_file_atomically(path, "old contents");

  SECTION("a writer that throws after writing half") {
    CHECK_THROWS_WITH(write_stream_atomically(path,
                                              [](std::ostream& out) {
                                                out << "half of the new";
                                                out.flush();
                                                throw std::runtime_error("writer failed");
                                              }),
                      "writer failed");
  }
  SECTION("a file-name writer that throws after writing half") {
    CHECK_THROWS_AS(write_file_atomically(path,
                                          [](const std::string& tmp) {
                                            std::ofstream(tmp) << "half";
                                            require(false, "encoder", "failed", "retry");
                                          }),
                    InputError);
  }
  SECTION("a file-name writer that writes nothing") {
    CHECK_THAT(error_of([&] { write_file_atomically(path, [](const std::string&) {}); }),
               Catch::Contains(path) && Catch::Contains("no file was written"));
  }
  SECTION("the rename fails (the target became a folder)") {
    const std::string message = error_of([&] {
      write_text_file_atomically((dir / "late").string(), "x");
      write_file_atomically((dir / "late").string(), [&](const std::string& tmp) {
        std::ofstream(tmp) << "new";
        fs::remove(dir / "late");
        fs::create_directories(dir / "late" / "child");
      });
    });
    CHECK_THAT(message, Catch::Contains("late") && Catch::Contains("cannot rename"));
    fs::remove_all(dir / "late");
  }
  // The existing file is unchanged and no temporary file is left.
  CHECK(read_all(path) == "old contents");
  CHECK(folder_entries(dir) == std::vector<std::string>{"out.glb"});
}

TEST_CASE("atomic files: bad targets give one line naming the path", "[core][atomic_file]") {
  const fs::path dir = scratch("errors");
  auto one_line_naming = [](const std::string& message, const std::string& path) {
    CHECK_THAT(message, Catch::Contains(path));
    CHECK(message.find('\n') == std::string::npos);
  };
  const std::string missing = (dir / "no-such-folder" / "out.png").string();
  const std::string message = error_of([&] { write_text_file_atomically(missing, "x"); });
  one_line_naming(message, missing);
  CHECK_THAT(message, Catch::Contains("does not exist"));
  CHECK_FALSE(fs::exists(dir / "no-such-folder"));

  one_line_naming(error_of([&] { write_text_file_atomically(dir.string(), "x"); }), dir.string());
  one_line_naming(error_of([&] { write_text_file_atomically((dir / "").string(), "x"); }), dir.string());

  // A folder nobody can create files in (also as root): /proc on Linux.
  if (fs::is_directory("/proc")) {
    const std::string unwritable = "/proc/isokit-test.json";
    const std::string m = error_of([&] { write_text_file_atomically(unwritable, "x"); });
    one_line_naming(m, unwritable);
    CHECK_THAT(m, Catch::Contains("cannot create a temporary file"));
  }
  CHECK(folder_entries(dir).empty());
}

TEST_CASE("make_output_folder creates a missing folder and its parents, or names what is in the way",
          "[core][unit]") {
  const fs::path dir = scratch("output_folder");
  const fs::path nested = dir / "a" / "b";
  make_output_folder(nested.string(), "--screenshot-dir");
  CHECK(fs::is_directory(nested));
  make_output_folder(nested.string(), "--screenshot-dir");  // already there: fine
  write_text_file_atomically((dir / "file").string(), "x");
  const std::string e = error_of([&] { make_output_folder((dir / "file").string(), "--screenshot-dir"); });
  CHECK(e.find("--screenshot-dir") != std::string::npos);
  CHECK(e.find("file") != std::string::npos);
  CHECK(e.find('\n') == std::string::npos);
}
