// SPDX-License-Identifier: MIT
/// \file
/// The process cache of the geometric methods' precomputations (ddm.h, cor.h), by content key:
/// 64-bit FNV-1a of the rest positions, triangles, weights, joint count, options and a format
/// version, as the operator cache keys its grids (operators/cache.h). Skinners of the same rig
/// (every clip of a rig in `isokit-eval`, the viewer's reloads) share one precomputation. The
/// cache keeps the last `kGeometricCacheEntries` entries. Thread-safe. Private to isokit_skinning.
#pragma once

#include <cstdint>
#include <memory>

#include "isokit/skinning/cor.h"
#include "isokit/skinning/ddm.h"
#include "isokit/skinning/rig.h"

namespace isokit::skinning {

inline constexpr std::size_t kGeometricCacheEntries = 8;

std::uint64_t ddm_cache_key(const Rig& rig, const DdmOptions& o);
std::uint64_t cor_cache_key(const Rig& rig, const CorOptions& o);
/// The precomputation of `rig` with `o`: from the cache, or made (and cached).
std::shared_ptr<const DirectDeltaMush> cached_ddm(const Rig& rig, const DdmOptions& o);
std::shared_ptr<const CorSkinning> cached_cor(const Rig& rig, const CorOptions& o);

}  // namespace isokit::skinning
