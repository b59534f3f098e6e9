// SPDX-License-Identifier: MIT
#include "isokit/operators/cache.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <system_error>

#include "isokit/core/error.h"
#include "isokit/operators/io.h"

namespace isokit::operators {

namespace fs = std::filesystem;

namespace {

/// The part of a spec that determines its grid: the name and the controller reset.
OperatorSpec grid_part(const OperatorSpec& spec) {
  OperatorSpec g = spec;
  g.name = "custom";
  g.controller = "contact";
  g.controller_knots.clear();
  return g;
}

/// The spec's name reduced to `[A-Za-z0-9_-]`, at most 40 characters ("op" when nothing is left).
std::string file_stem(const std::string& name) {
  std::string s;
  for (char c : name) {
    const bool ok =
        (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_';
    if (ok && s.size() < 40) s += c;
  }
  return s.empty() ? "op" : s;
}

/// The entry at `path` when it exists, is readable and holds `spec`'s grid. A missing .npy is a
/// plain miss (also while another process is between its two renames); anything else that fails
/// adds a warning.
bool load_entry(const std::string& path, const OperatorSpec& spec, CachedGrid& out) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return false;
  try {
    StoredOperator stored = load_operator(path);
    if (!(grid_part(stored.spec) == grid_part(spec))) {
      out.warnings.push_back(path + ": the cached spec differs from the requested one (key collision or " +
                             "an edited entry); regenerated");
      return false;
    }
    out.grid = std::move(stored.grid);
    return true;
  } catch (const InputError& e) {
    out.warnings.push_back(path + ": cache entry unreadable (" + e.what() + "); regenerated");
  }
  return false;
}

/// Stores `grid` at `path`, its folder created first; failures become warnings.
void store_entry(const std::string& path, const OperatorSpec& spec, const GridOperator& grid,
                 std::vector<std::string>& warnings) {
  std::error_code ec;
  fs::create_directories(fs::path(path).parent_path(), ec);
  if (ec) {
    warnings.push_back(fs::path(path).parent_path().string() + ": cannot create the operator cache folder (" +
                       ec.message() +
                       "); the operator is not cached (set XDG_CACHE_HOME to a writable folder)");
    return;
  }
  try {
    save_operator(path, spec, grid);
  } catch (const InputError& e) {
    warnings.push_back(std::string("the operator is not cached: ") + e.what());
  }
}

}  // namespace

OperatorCache::OperatorCache(std::string dir) : dir_(std::move(dir)) {}

std::string OperatorCache::path_for(const OperatorSpec& spec) const {
  if (dir_.empty()) return {};
  return (fs::path(dir_) / (file_stem(spec.name) + "-" + hex_key(operator_cache_key(spec)) + ".npy"))
      .string();
}

CachedGrid OperatorCache::get(const OperatorSpec& spec, const BiharmonicOptions& options,
                              bool regenerate) const {
  CachedGrid out;
  out.key = operator_cache_key(spec);
  out.path = path_for(spec);
  if (!out.path.empty() && !regenerate && load_entry(out.path, spec, out)) {
    out.hit = true;
    return out;
  }
  out.grid = BiharmonicOperatorGenerator(spec, options).generate();
  if (!out.path.empty()) store_entry(out.path, spec, out.grid, out.warnings);
  return out;
}

std::string default_operator_cache_dir() {
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  if (xdg != nullptr && xdg[0] == '/') return (fs::path(xdg) / "isokit" / "operators").string();
  const char* home = std::getenv("HOME");
  if (home != nullptr && home[0] != '\0')
    return (fs::path(home) / ".cache" / "isokit" / "operators").string();
  return {};
}

std::uint64_t operator_cache_key(const OperatorSpec& spec, int generator_version) {
  std::uint64_t h = fnv1a64(spec_to_json(grid_part(spec)));
  h = fnv1a64("\ngenerator " + std::to_string(generator_version), h);
  return fnv1a64("\nresolution " + std::to_string(spec.resolution) + " slices " + std::to_string(spec.slices),
                 h);
}

std::string hex_key(std::uint64_t key) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(key));
  return buf;
}

std::uint64_t fnv1a64(const std::string& bytes, std::uint64_t hash) {
  for (unsigned char c : bytes) {
    hash ^= c;
    hash *= 0x100000001b3ull;
  }
  return hash;
}

}  // namespace isokit::operators
