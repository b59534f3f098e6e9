// SPDX-License-Identifier: MIT
// The disk cache of grid operators: hits, misses on every change of the key, corrupt entries
// regenerated, unwritable folders, and two writers of one key.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include "isokit/operators/cache.h"
#include "isokit/operators/io.h"

using namespace isokit::operators;
namespace fs = std::filesystem;

namespace {

/// A fresh, empty folder per test case.
fs::path fresh_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("isokit-test-cache-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  return dir;
}

/// A small contact operator (16 x 16 x 8: generated in milliseconds).
OperatorSpec small_spec() {
  OperatorSpec s = preset_spec("contact", 16);
  s.slices = 8;
  return s;
}

/// Temporary files left in `dir` (names with ".tmp").
int temporaries(const fs::path& dir) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(dir))
    n += e.path().filename().string().find(".tmp") != std::string::npos;
  return n;
}

}  // namespace

TEST_CASE("operator cache: a miss stores the grid, the next get hits it", "[unit][cache]") {
  const fs::path dir = fresh_dir("hit");
  const OperatorCache cache(dir.string());
  const OperatorSpec spec = small_spec();
  const CachedGrid first = cache.get(spec);
  CHECK_FALSE(first.hit);
  CHECK(first.warnings.empty());
  REQUIRE(fs::exists(first.path));
  CHECK(fs::exists(spec_path_for(first.path)));
  CHECK(first.path.find(hex_key(operator_cache_key(spec))) != std::string::npos);
  const CachedGrid second = cache.get(spec);
  CHECK(second.hit);
  CHECK(second.path == first.path);
  CHECK(second.grid.data() == first.grid.data());
  // regenerate skips the lookup.
  CHECK_FALSE(cache.get(spec, {}, true).hit);
  CHECK(temporaries(dir) == 0);
  fs::remove_all(dir);
}

TEST_CASE("operator cache: the key changes with the grid, not with the name or controller", "[unit][cache]") {
  const OperatorSpec spec = small_spec();
  const std::uint64_t key = operator_cache_key(spec);
  SECTION("a moved contact-curve point, the resolution, the slices, the slope, the version: new keys") {
    OperatorSpec moved = spec;
    moved.curves.back().keyframes.back().points.back()[0] -= 0.05;
    OperatorSpec finer = preset_spec("contact", 17);
    finer.slices = 8;
    OperatorSpec more = spec;
    more.slices = 9;
    OperatorSpec slope = spec;
    slope.distance_slope = 1.5;
    for (const OperatorSpec& s : {moved, finer, more, slope}) CHECK(operator_cache_key(s) != key);
    CHECK(operator_cache_key(spec, kBiharmonicGeneratorVersion + 1) != key);
    CHECK(operator_cache_key(spec, kBiharmonicGeneratorVersion) == key);
  }
  SECTION("name and controller: same key (they do not change the grid)") {
    OperatorSpec renamed = spec;
    renamed.name = "mine";
    renamed.controller = "bulge";
    renamed.controller_knots = {{0.0, 1.0}, {3.0, 0.0}};
    CHECK(operator_cache_key(renamed) == key);
  }
  SECTION("a changed spec misses and gets its own entry") {
    const fs::path dir = fresh_dir("miss");
    const OperatorCache cache(dir.string());
    const CachedGrid a = cache.get(spec);
    OperatorSpec moved = spec;
    moved.curves.back().keyframes.back().points.back()[0] -= 0.05;
    moved.curves.back().keyframes.back().points.back()[1] -= 0.05;
    const CachedGrid b = cache.get(moved);
    CHECK_FALSE(b.hit);
    CHECK(b.path != a.path);
    CHECK(fs::exists(a.path));
    CHECK(fs::exists(b.path));
    CHECK(b.grid.data() != a.grid.data());
    fs::remove_all(dir);
  }
  CHECK(hex_key(0xab12ull) == "000000000000ab12");
  CHECK(fnv1a64("") == 0xcbf29ce484222325ull);
  CHECK(fnv1a64("a") == 0xaf63dc4c8601ec8cull);  // the published FNV-1a 64 test vector
}

TEST_CASE("operator cache: a corrupt entry is regenerated, not an error", "[unit][cache]") {
  const fs::path dir = fresh_dir("corrupt");
  const OperatorCache cache(dir.string());
  const OperatorSpec spec = small_spec();
  const CachedGrid good = cache.get(spec);
  SECTION("truncated .npy") {
    fs::resize_file(good.path, 100);
  }
  SECTION("garbage spec beside it") {
    std::ofstream(spec_path_for(good.path)) << "{ not json";
  }
  SECTION("a different spec beside it (a collision or an edited entry)") {
    OperatorSpec other = preset_spec("clean-union", 16);
    other.slices = 8;
    save_operator(good.path, other, BiharmonicOperatorGenerator(other).generate());
  }
  const CachedGrid again = cache.get(spec);
  CHECK_FALSE(again.hit);
  REQUIRE(again.warnings.size() == 1);
  CHECK(again.warnings[0].find(again.path) != std::string::npos);
  CHECK(again.grid.data() == good.grid.data());
  CHECK(load_operator(again.path).grid.data() == good.grid.data());
  CHECK(cache.get(spec).hit);
  fs::remove_all(dir);
}

TEST_CASE("operator cache: an unwritable folder is a warning, and no folder means no cache",
          "[unit][cache]") {
  const fs::path dir = fresh_dir("unwritable");
  fs::create_directories(dir);
  std::ofstream(dir / "file") << "a file where the cache folder should be";
  const OperatorSpec spec = small_spec();
  const CachedGrid r = OperatorCache((dir / "file" / "operators").string()).get(spec);
  CHECK_FALSE(r.hit);
  REQUIRE(r.warnings.size() == 1);
  CHECK(r.warnings[0].find("not cached") != std::string::npos);
  CHECK(r.grid.nd() == spec.slices);
  const CachedGrid none = OperatorCache("").get(spec);
  CHECK(none.path.empty());
  CHECK(none.warnings.empty());
  CHECK(none.grid.data() == r.grid.data());
  fs::remove_all(dir);
}

TEST_CASE("operator cache: two writers of one key both end with a valid entry", "[unit][cache]") {
  const fs::path dir = fresh_dir("race");
  const OperatorSpec spec = small_spec();
  for (int round = 0; round < 3; ++round) {
    fs::remove_all(dir);
    CachedGrid a, b;
    std::thread ta([&] { a = OperatorCache(dir.string()).get(spec); });
    std::thread tb([&] { b = OperatorCache(dir.string()).get(spec); });
    ta.join();
    tb.join();
    CHECK(a.warnings.empty());
    CHECK(b.warnings.empty());
    CHECK(a.grid.data() == b.grid.data());
    const StoredOperator stored = load_operator(a.path);
    CHECK(stored.grid.data() == a.grid.data());
    CHECK(temporaries(dir) == 0);
  }
  fs::remove_all(dir);
}

TEST_CASE("operator cache: the default folder follows XDG_CACHE_HOME, then HOME", "[unit][cache]") {
  const char* old_xdg = std::getenv("XDG_CACHE_HOME");
  const std::string saved = old_xdg ? old_xdg : "";
  ::setenv("XDG_CACHE_HOME", "/tmp/xdg-here", 1);
  CHECK(default_operator_cache_dir() == "/tmp/xdg-here/isokit/operators");
  ::setenv("XDG_CACHE_HOME", "relative/ignored", 1);  // the XDG spec: relative paths are invalid
  const char* home = std::getenv("HOME");
  if (home != nullptr && home[0] != '\0')
    CHECK(default_operator_cache_dir() == (fs::path(home) / ".cache/isokit/operators").string());
  if (old_xdg)
    ::setenv("XDG_CACHE_HOME", saved.c_str(), 1);
  else
    ::unsetenv("XDG_CACHE_HOME");
}
