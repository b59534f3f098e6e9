// SPDX-License-Identifier: MIT
// Fuzz target: the skinning setup JSON (`setup_from_json`). Expected outcome for bad input:
// InputError.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_util.h"
#include "isokit/skinning/setup.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  isokit::fuzz::expect_input_error([&] { isokit::skinning::setup_from_json(text, "fuzz.json"); });
  return 0;
}
