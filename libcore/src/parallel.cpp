// SPDX-License-Identifier: MIT
#include "isokit/core/parallel.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace isokit {

void parallel_for(std::size_t n, std::size_t grain,
                  const std::function<void(std::size_t, std::size_t)>& body) {
  if (n == 0) return;
  if (grain == 0 || n <= grain) {
    body(0, n);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain),
                    [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
}

}  // namespace isokit
