// SPDX-License-Identifier: MIT
/// \file
/// A disk cache of generated grid operators, shared by runs and processes (isokit-skin, tests,
/// scripts): designing an operator means baking with it many times, and a 128³ bulge operator
/// takes about a second to generate (docs/operators.md, "Using a designed operator in skinning").
///
/// - Folder: `default_operator_cache_dir()`, i.e. `${XDG_CACHE_HOME:-$HOME/.cache}/isokit/operators`,
///   or any folder given to OperatorCache.
/// - Entry: `DIR/NAME-HEX.npy` and `DIR/NAME-HEX.json` (the io.h format: NumPy-loadable), NAME the
///   spec's name reduced to `[A-Za-z0-9_-]` (for people browsing the folder), HEX the key.
/// - Key (`operator_cache_key`): 64-bit FNV-1a of the canonical spec JSON (`spec_to_json`, with the
///   name and the controller left out: they do not change the grid), the generator version
///   (kBiharmonicGeneratorVersion), the resolution and the slices.
/// - Atomic: entries are written with `save_operator` (temporary name, then rename), so parallel
///   processes can share the folder: two writers of one key each rename a complete file over the
///   other's, and a reader sees a complete file (both describe the same key).
/// - Never fatal: an unreadable or corrupt entry, or one whose stored spec differs from the
///   requested one, is regenerated and rewritten; a folder that cannot be created or written is a
///   warning (the grid is still returned).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "isokit/operators/biharmonic.h"
#include "isokit/operators/grid_operator.h"
#include "isokit/operators/spec.h"

namespace isokit::operators {

/// What OperatorCache::get returns.
struct CachedGrid {
  GridOperator grid;
  std::uint64_t key{0};  ///< operator_cache_key(spec)
  std::string path;      ///< the entry's .npy (empty when the cache has no folder)
  bool hit{false};       ///< loaded from the cache (true) or generated (false)
  /// Cache problems met on the way (a corrupt entry regenerated, a store that failed), one line
  /// each, naming the file; never errors.
  std::vector<std::string> warnings;
};

class OperatorCache {
 public:
  /// `dir`: the cache folder, created on the first store. Empty: no disk cache (every get
  /// generates, nothing is written).
  explicit OperatorCache(std::string dir);

  const std::string& dir() const { return dir_; }
  /// The .npy path of `spec`'s entry (whether or not it exists); empty when there is no folder.
  std::string path_for(const OperatorSpec& spec) const;

  /// `spec`'s grid: loaded from its entry, or generated with `options` (and its progress
  /// callback) and stored. `regenerate`: skip the lookup (e.g. an entry that failed a check).
  /// \throw isokit::InputError for an invalid spec (as BiharmonicOperatorGenerator); cache
  /// problems are warnings in the result.
  CachedGrid get(const OperatorSpec& spec, const BiharmonicOptions& options = {},
                 bool regenerate = false) const;

 private:
  std::string dir_;
};

/// `$XDG_CACHE_HOME/isokit/operators` when XDG_CACHE_HOME is an absolute path (XDG base
/// directory specification), else `$HOME/.cache/isokit/operators`; empty when neither is set.
std::string default_operator_cache_dir();

/// The cache key of `spec` for a generator version (see the file comment).
std::uint64_t operator_cache_key(const OperatorSpec& spec,
                                 int generator_version = kBiharmonicGeneratorVersion);
/// 16 lowercase hex digits.
std::string hex_key(std::uint64_t key);
/// 64-bit FNV-1a of `bytes`, continuing from `hash` (default: the FNV offset basis).
std::uint64_t fnv1a64(const std::string& bytes, std::uint64_t hash = 0xcbf29ce484222325ull);

}  // namespace isokit::operators
