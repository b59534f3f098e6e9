// SPDX-License-Identifier: MIT
#include "pipeline/geometric_cache.h"

#include <deque>
#include <mutex>
#include <string>
#include <utility>

#include "isokit/operators/cache.h"

namespace isokit::skinning {

namespace {

/// Bumped whenever a precomputation's result changes for the same input.
constexpr int kGeometricFormatVersion = 1;

template <class T>
std::uint64_t hash_bytes(const T* data, std::size_t count, std::uint64_t h) {
  return operators::fnv1a64(std::string(reinterpret_cast<const char*>(data), count * sizeof(T)), h);
}

/// The rig's part of both keys: rest positions, triangles, weights, joints.
std::uint64_t rig_key(const Rig& rig, const std::string& method) {
  std::uint64_t h = operators::fnv1a64(method + ":" + std::to_string(kGeometricFormatVersion));
  h = hash_bytes(rig.rest.data(), static_cast<std::size_t>(rig.rest.size()), h);
  h = hash_bytes(rig.triangles.data(), static_cast<std::size_t>(rig.triangles.size()), h);
  h = hash_bytes(rig.weights.offsets.data(), rig.weights.offsets.size(), h);
  h = hash_bytes(rig.weights.joints.data(), rig.weights.joints.size(), h);
  h = hash_bytes(rig.weights.weights.data(), rig.weights.weights.size(), h);
  const std::size_t joints = rig.joints.size();
  return hash_bytes(&joints, 1, h);
}

template <class T>
struct Cache {
  std::mutex mutex;
  std::deque<std::pair<std::uint64_t, std::shared_ptr<const T>>> entries;

  template <class Make>
  std::shared_ptr<const T> get(std::uint64_t key, Make make) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      for (const auto& e : entries)
        if (e.first == key) return e.second;
    }
    std::shared_ptr<const T> made = make();  // outside the lock: other rigs are not held up
    std::lock_guard<std::mutex> lock(mutex);
    entries.emplace_back(key, made);
    while (entries.size() > kGeometricCacheEntries) entries.pop_front();
    return made;
  }
};

}  // namespace

std::uint64_t ddm_cache_key(const Rig& rig, const DdmOptions& o) {
  const double values[] = {double(o.smoothing_steps),          o.lambda, o.kappa, o.alpha, o.prune,
                           double(static_cast<int>(o.variant))};
  return hash_bytes(values, 6, rig_key(rig, "ddm"));
}

std::uint64_t cor_cache_key(const Rig& rig, const CorOptions& o) {
  const double values[] = {o.sigma, double(static_cast<int>(o.fallback))};
  return hash_bytes(values, 2, rig_key(rig, "cor"));
}

std::shared_ptr<const DirectDeltaMush> cached_ddm(const Rig& rig, const DdmOptions& o) {
  static Cache<DirectDeltaMush> cache;
  return cache.get(ddm_cache_key(rig, o), [&] {
    return std::make_shared<const DirectDeltaMush>(rig.rest, rig.triangles, rig.weights,
                                                   static_cast<int>(rig.joints.size()), o);
  });
}

std::shared_ptr<const CorSkinning> cached_cor(const Rig& rig, const CorOptions& o) {
  static Cache<CorSkinning> cache;
  return cache.get(cor_cache_key(rig, o), [&] {
    return std::make_shared<const CorSkinning>(rig.rest, rig.triangles, rig.weights, o);
  });
}

}  // namespace isokit::skinning
