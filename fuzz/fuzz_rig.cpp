// SPDX-License-Identifier: MIT
// Fuzz target: `load_rig` on the fuzzer's bytes saved as `input.<ISOKIT_FUZZ_EXT>` (glb and gltf
// through tinygltf, fbx and dae through assimp). Expected outcome for bad input: InputError.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "isokit/skinning/rig_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = isokit::fuzz::write_input(data, size, "input." ISOKIT_FUZZ_EXT);
  isokit::fuzz::expect_input_error([&] { isokit::skinning::load_rig(path); });
  return 0;
}
