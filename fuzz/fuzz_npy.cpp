// SPDX-License-Identifier: MIT
// Fuzz target: the .npy reader through `load_operator` (which calls `read_npy_f32`): the fuzzer's
// bytes are `op.npy`, beside a fixed valid spec `op.json` (resolution 8, 8 slices). Expected
// outcome for bad input: InputError.
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include "fuzz_util.h"
#include "isokit/operators/io.h"

namespace {
void write_spec_once(const std::string& npy_path) {
  static bool written = false;
  if (written) return;
  isokit::operators::OperatorSpec spec = isokit::operators::preset_spec("contact", 8);
  spec.slices = 8;
  isokit::operators::save_spec(spec, isokit::operators::spec_path_for(npy_path));
  written = true;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = isokit::fuzz::write_input(data, size, "op.npy");
  write_spec_once(path);
  isokit::fuzz::expect_input_error([&] { isokit::operators::load_operator(path); });
  return 0;
}
