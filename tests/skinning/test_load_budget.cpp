// SPDX-License-Identifier: MIT
// The memory budget of a load (isokit/core/load_budget.h, docs/fuzzing.md): each load runs in a
// process of its own (isokit_load_probe, or isokit-skin info), whose peak resident memory is read
// with wait4, on the fuzz targets' seeds, the fuzzers' findings and inputs crafted to declare far
// more than they hold.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>
#include <catch2/catch.hpp>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "isokit/core/load_budget.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

struct Run {
  int exit_code{-1};
  double peak_mib{0};
  double seconds{0};
  std::string output;
};

/// Runs `args` (args[0] the executable) with stdout and stderr in a file; its peak resident
/// memory from wait4 (Linux: the process and the children it waited for).
Run run(const std::vector<std::string>& args, const fs::path& log) {
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  Run r;
  int status = 0;
  rusage usage{};
  REQUIRE(wait4(pid, &status, 0, &usage) == pid);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.peak_mib = static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
  std::ifstream in(log);
  std::stringstream s;
  s << in.rdbuf();
  r.output = s.str();
  return r;
}

struct Scratch {
  explicit Scratch(const std::string& name)
      : path(fs::temp_directory_path() / ("isokit-load-budget-" + name + "-" + std::to_string(getpid()))) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  fs::path path;
};

double mib(std::uint64_t bytes) {
  return static_cast<double>(bytes) / (1024.0 * 1024.0);
}

void write(const fs::path& p, const std::string& text) {
  std::ofstream(p, std::ios::binary) << text;
}

/// A .gltf whose one mesh has `primitives` primitives, all reading the same POSITION accessor of
/// `vertices` floats in big.bin: the decoded data grows with the primitives, the file barely does.
void shared_accessor_gltf(const fs::path& dir, int vertices, int primitives) {
  std::vector<float> pos(static_cast<std::size_t>(vertices) * 3);
  for (std::size_t i = 0; i < pos.size(); ++i) pos[i] = static_cast<float>(i % 97) * 0.01f;
  std::ofstream(dir / "big.bin", std::ios::binary)
      .write(reinterpret_cast<const char*>(pos.data()), static_cast<std::streamsize>(pos.size() * 4));
  json doc;
  doc["asset"]["version"] = "2.0";
  doc["buffers"] = json::array({{{"uri", "big.bin"}, {"byteLength", pos.size() * 4}}});
  doc["bufferViews"] = json::array({{{"buffer", 0}, {"byteLength", pos.size() * 4}}});
  doc["accessors"] = json::array({{{"bufferView", 0},
                                   {"componentType", 5126},
                                   {"count", vertices},
                                   {"type", "VEC3"},
                                   {"min", {0, 0, 0}},
                                   {"max", {1, 1, 1}}}});
  json prims = json::array();
  for (int p = 0; p < primitives; ++p) prims.push_back({{"attributes", {{"POSITION", 0}}}});
  doc["meshes"] = json::array({{{"primitives", prims}}});
  doc["nodes"] = json::array({{{"mesh", 0}}});
  doc["scenes"] = json::array({{{"nodes", {0}}}});
  write(dir / "shared.gltf", doc.dump());
}

/// The seed .gltf with its node hierarchy made a chain of nodes that each list the next one twice:
/// a tree of 2^depth nodes if it were copied per path.
void shared_children_gltf(const fs::path& seed, const fs::path& out, int depth) {
  std::ifstream in(seed);
  json doc = json::parse(in);
  const auto first = static_cast<int>(doc["nodes"].size());
  for (int k = 0; k < depth; ++k) {
    json node = {{"name", "chain" + std::to_string(k)}};
    if (k + 1 < depth) node["children"] = {first + k + 1, first + k + 1};
    doc["nodes"].push_back(node);
  }
  doc["scenes"][0]["nodes"].push_back(first);
  write(out, doc.dump());
}

/// The seed .gltf with an accessor without a buffer view declaring `count` MAT4 elements as the
/// inverse bind matrices.
void unbacked_gltf(const fs::path& seed, const fs::path& out, std::uint64_t count) {
  std::ifstream in(seed);
  json doc = json::parse(in);
  doc["accessors"].push_back({{"componentType", 5126}, {"count", count}, {"type", "MAT4"}});
  doc["skins"][0]["inverseBindMatrices"] = doc["accessors"].size() - 1;
  write(out, doc.dump());
}

struct Input {
  std::string kind;
  fs::path file;
  std::uint64_t input_bytes;  ///< the file and what it references
};

}  // namespace

TEST_CASE("load budget: no load of a seed, a finding or a crafted input takes more than its budget",
          "[skinning][io][fuzz]") {
  Scratch dir("inputs");
  const fs::path log = dir.path / "probe.log";
  REQUIRE(run({ISOKIT_LOAD_PROBE, "seeds", (dir.path / "seeds").string()}, log).exit_code == 0);
  const fs::path seeds = dir.path / "seeds";
  std::vector<Input> inputs;
  auto add = [&](const std::string& kind, const fs::path& f, std::uint64_t extra = 0) {
    inputs.push_back({kind, f, fs::file_size(f) + extra});
  };
  for (const char* target : {"glb", "gltf", "fbx", "dae", "setup", "spec"})
    for (const auto& e : fs::directory_iterator(seeds / target))
      add(std::string(target) == "setup" || std::string(target) == "spec" ? target : "rig", e.path());
  // The npy seed with the spec it belongs to.
  const fs::path op = dir.path / "op";
  fs::create_directories(op);
  fs::copy_file(seeds / "npy" / "op.npy", op / "op.npy");
  json op_spec = json::parse(std::ifstream(seeds / "spec" / "contact.json"));
  op_spec["resolution"] = 8;
  op_spec["slices"] = 8;
  write(op / "op.json", op_spec.dump());
  add("npy", op / "op.npy");
  // The fuzzers' findings.
  const fs::path findings = fs::path(ISOKIT_TEST_SOURCE_DIR) / "data" / "fuzz";
  for (const auto& e : fs::directory_iterator(findings)) {
    const std::string name = e.path().filename().string();
    if (e.is_directory()) continue;
    add(name.rfind("setup", 0) == 0 ? "setup" : name.rfind("spec", 0) == 0 ? "spec" : "rig", e.path());
  }
  // Crafted: one accessor read by 400 primitives, a node chain shared twice per level, an
  // accessor with no data declaring 2^40 elements, a spec and a pose script declaring large sizes.
  shared_accessor_gltf(dir.path, 20000, 400);
  add("rig", dir.path / "shared.gltf", fs::file_size(dir.path / "big.bin"));
  shared_children_gltf(seeds / "gltf" / "tube.gltf", dir.path / "chain.gltf", 40);
  add("rig", dir.path / "chain.gltf");
  unbacked_gltf(seeds / "gltf" / "tube.gltf", dir.path / "unbacked.gltf", std::uint64_t{1} << 40);
  add("rig", dir.path / "unbacked.gltf");
  json spec = json::parse(std::ifstream(seeds / "spec" / "contact.json"));
  spec["resolution"] = 1024;
  spec["slices"] = 1024;
  write(dir.path / "huge.json", spec.dump());
  add("spec", dir.path / "huge.json");
  write(dir.path / "pose.json",
        R"({"keys": [{"frame": 0}, {"frame": 3000, "joints": {"bone1": [["z", 90]]}}]})");
  add("pose", dir.path / "pose.json");

  const Run baseline = run({ISOKIT_LOAD_PROBE, "none"}, log);
  REQUIRE(baseline.exit_code == 0);
  for (const Input& in : inputs) {
    const Run r = run({ISOKIT_LOAD_PROBE, in.kind, in.file.string()}, log);
    const double budget = mib(isokit::load_budget_bytes(in.input_bytes));
    INFO(in.kind << " " << in.file.filename().string() << ": exit " << r.exit_code << ", peak " << r.peak_mib
                 << " MiB (baseline " << baseline.peak_mib << "), budget " << budget << " MiB\n"
                 << r.output);
    CHECK((r.exit_code == 0 || r.exit_code == 2));
    CHECK(r.peak_mib - baseline.peak_mib <= budget);
  }
}

TEST_CASE("load budget: the crafted inputs are refused by name", "[skinning][io][fuzz]") {
  Scratch dir("refused");
  const fs::path log = dir.path / "probe.log";
  REQUIRE(run({ISOKIT_LOAD_PROBE, "seeds", (dir.path / "seeds").string()}, log).exit_code == 0);
  const fs::path tube = dir.path / "seeds" / "gltf" / "tube.gltf";
  shared_children_gltf(tube, dir.path / "chain.gltf", 40);
  Run r = run({ISOKIT_LOAD_PROBE, "rig", (dir.path / "chain.gltf").string()}, log);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Catch::Contains("node 'chain") && Catch::Contains("reached twice"));
  unbacked_gltf(tube, dir.path / "unbacked.gltf", std::uint64_t{1} << 40);
  r = run({ISOKIT_LOAD_PROBE, "rig", (dir.path / "unbacked.gltf").string()}, log);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Catch::Contains("inverseBindMatrices") && Catch::Contains("has no buffer view"));
  shared_accessor_gltf(dir.path, 20000, 400);
  r = run({ISOKIT_LOAD_PROBE, "rig", (dir.path / "shared.gltf").string()}, log);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Catch::Contains("meshes[0] primitive") && Catch::Contains("past the load budget"));
  // One line each.
  CHECK(std::count(r.output.begin(), r.output.end(), '\n') == 1);
}

TEST_CASE("load budget: isokit-skin info on the two fuzz findings, under 100 MB and 1 s",
          "[skinning][io][fuzz]") {
  Scratch dir("info");
  const fs::path findings = fs::path(ISOKIT_TEST_SOURCE_DIR) / "data" / "fuzz";
  // An inverseBindMatrices accessor claiming 333,333,332 MAT4 (42.6 GB as doubles) over 128 bytes:
  // a one-line input error, before anything is allocated.
  Run r = run({ISOKIT_SKIN_EXE, "info", (findings / "gltf-accessor-count-42GB.gltf").string()},
              dir.path / "a.log");
  INFO(r.output);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Catch::Contains("inverseBindMatrices") && Catch::Contains("333333332 elements") &&
                           Catch::Contains("buffer view 5 holds 128 bytes"));
  CHECK(r.peak_mib < 100);
  CHECK(r.seconds < 1);
  // A valid clip 14 hours long: listed, not sampled.
  r = run({ISOKIT_SKIN_EXE, "info", (findings / "glb-clip-1.5M-frames.glb").string()}, dir.path / "b.log");
  INFO(r.output);
  CHECK(r.exit_code == 0);
  CHECK_THAT(r.output, Catch::Contains("1545762 frames"));
  CHECK(r.peak_mib < 100);
  CHECK(r.seconds < 1);
}
