// SPDX-License-Identifier: MIT
// Internal: write a whole file under a temporary name, then rename it into place.
#pragma once

#include <cstddef>
#include <string>

namespace isokit::operators::detail {

/// \throw std::runtime_error naming the path if writing or renaming fails (the temporary file is
/// removed).
void write_file_atomic(const std::string& path, const void* data, std::size_t size);

}  // namespace isokit::operators::detail
