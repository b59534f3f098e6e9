// SPDX-License-Identifier: MIT
/// \file
/// Parallel loops over index ranges. Every parallel loop in isokit goes through `parallel_for`
/// with an explicit grain size; grain 0 runs the very same functor serially over the whole range,
/// which tests use to prove that serial and parallel runs agree bit for bit.
#pragma once

#include <cstddef>
#include <functional>

namespace isokit {

/// Default number of items per task for cheap per-item work (field evaluations).
inline constexpr std::size_t kDefaultGrain = 1024;

/// Calls `body(begin, end)` over disjoint sub-ranges covering `[0, n)`.
/// \param grain items per task; 0 = one serial call `body(0, n)` on the calling thread.
/// The body must only write to per-index outputs (no shared accumulation).
void parallel_for(std::size_t n, std::size_t grain,
                  const std::function<void(std::size_t, std::size_t)>& body);

}  // namespace isokit
