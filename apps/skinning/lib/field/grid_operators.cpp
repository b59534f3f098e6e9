// SPDX-License-Identifier: MIT
#include "isokit/skinning/grid_operators.h"

#include <cstdint>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>

#include "isokit/core/error.h"
#include "isokit/operators/cache.h"
#include "isokit/operators/checks.h"

namespace isokit::skinning {

namespace {

/// Grids already checked in this process, by cache key.
struct ProcessGrids {
  std::mutex mutex;
  std::map<std::uint64_t, std::shared_ptr<const operators::GridOperator>> grids;
};

ProcessGrids& process_grids() {
  static ProcessGrids g;
  return g;
}

/// Where a grid comes from, for progress lines ("contact", "my_op.json") and error messages
/// (the spec file's path, or "preset contact (resolution R, slices S)").
struct GridSource {
  std::string name;
  std::string source;
};

GridSource grid_source(const SkinSetup& setup, const SpecFile* file, JointOperator op) {
  if (file != nullptr) return {std::filesystem::path(file->path).filename().string(), file->path};
  return {to_string(op), std::string("preset ") + to_string(op) + " (resolution " +
                             std::to_string(setup.operator_resolution) + ", slices " +
                             std::to_string(setup.operator_slices) + ")"};
}

/// The cache's answer and its warnings, on the progress channel.
void report(const operators::CachedGrid& got, const std::string& name, const Progress& progress) {
  if (!progress) return;
  for (const std::string& w : got.warnings) progress("operator " + name + ": warning: " + w, 1, 1);
  if (got.hit) progress("operator " + name + ": cache hit " + got.path, 1, 1);
}

/// `spec`'s grid from the disk cache or generated, checked. \throw InputError naming `src`.
std::shared_ptr<const operators::GridOperator> checked_grid(const operators::OperatorSpec& spec,
                                                            const GridSource& src, const Progress& progress) {
  const operators::OperatorCache cache(operators::default_operator_cache_dir());
  operators::BiharmonicOptions options;
  if (progress)
    options.progress = [&](int done, int total) { progress("operator " + src.name, done, total); };
  operators::CachedGrid got = cache.get(spec, options);
  report(got, src.name, progress);
  std::optional<operators::CheckFailure> failure = operators::check_operator(spec, got.grid);
  if (failure && got.hit) {  // a damaged entry that still parses: generate it anew once
    got = cache.get(spec, options, true);
    report(got, src.name, progress);
    failure = operators::check_operator(spec, got.grid);
  }
  if (failure) throw InputError(src.source + ": " + failure->message());
  return std::make_shared<const operators::GridOperator>(std::move(got.grid));
}

}  // namespace

operators::OperatorSpec grid_spec(const SkinSetup& setup, const SpecFile* file, JointOperator op) {
  require(op == JointOperator::kContact || op == JointOperator::kBulge, "grid_spec",
          std::string("operator '") + to_string(op) + "' has no grid", "pass contact or bulge");
  operators::OperatorSpec spec =
      file != nullptr ? file->spec : operators::preset_spec(to_string(op), setup.operator_resolution);
  spec.resolution = setup.operator_resolution;
  spec.slices = setup.operator_slices;
  return spec;
}

std::string describe_joint_operator(const SkinSetup& setup, const std::string& joint, JointOperator op) {
  const SpecFile* file = setup.spec_for(joint, op);
  if (op != JointOperator::kContact && op != JointOperator::kBulge) return to_string(op);
  if (file == nullptr) return std::string(to_string(op)) + " (preset)";
  return std::string(to_string(op)) + " (spec " + file->path + ", hash " +
         operators::hex_key(operators::operator_cache_key(grid_spec(setup, file, op))) + ")";
}

JointGridOperator joint_grid_operator(const SkinSetup& setup, const std::string& joint, JointOperator op,
                                      const Progress& progress) {
  const SpecFile* file = setup.spec_for(joint, op);
  const operators::OperatorSpec spec = grid_spec(setup, file, op);
  const std::string preset_controller =
      op == JointOperator::kBulge ? setup.bulge_controller : setup.contact_controller;
  JointGridOperator out{
      nullptr, file != nullptr ? spec.make_controller() : operators::Controller::preset(preset_controller),
      describe_joint_operator(setup, joint, op)};
  const std::uint64_t key = operators::operator_cache_key(spec);
  ProcessGrids& grids = process_grids();
  std::lock_guard<std::mutex> lock(grids.mutex);
  auto it = grids.grids.find(key);
  if (it == grids.grids.end())
    it = grids.grids.emplace(key, checked_grid(spec, grid_source(setup, file, op), progress)).first;
  out.grid = it->second;
  return out;
}

}  // namespace isokit::skinning
