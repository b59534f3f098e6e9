// SPDX-License-Identifier: MIT
/// \file
/// Helpers of the libFuzzer targets (docs/fuzzing.md): the fuzzer's bytes as a file in a
/// per-process scratch folder, and the rule that bad input may only end in `InputError`.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "isokit/core/error.h"

namespace isokit::fuzz {

/// A folder of this process's own under the system temp folder (created on first use).
const std::string& scratch_dir();

/// Writes `size` bytes to `scratch_dir()/name` (replacing it) and returns the path.
std::string write_input(const std::uint8_t* data, std::size_t size, const std::string& name);

/// Runs `f`; an `InputError` is the documented outcome for bad input and is swallowed. Any other
/// exception escapes, and libFuzzer reports it as a finding ("uncaught exception").
template <class F>
void expect_input_error(F&& f) {
  try {
    f();
  } catch (const InputError&) {
  }
}

}  // namespace isokit::fuzz
