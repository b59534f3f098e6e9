// SPDX-License-Identifier: MIT
// Fuzz target: `load_rig` on the fuzzer's bytes saved as `input.<ISOKIT_FUZZ_EXT>` (glb and gltf
// through tinygltf, fbx and dae through assimp). Expected outcome for bad input: InputError.
//
// assimp runs in process here (LoadOptions::isolate_importer = false), so that libFuzzer sees the
// coverage of isokit's conversion code and stops at assimp's own crashes (docs/fuzzing.md, known
// limits). With ISOKIT_FUZZ_ISOLATE=1 the target reads as isokit-skin does (assimp in a child
// process, 5 s and 1 GiB limits): every assimp failure must then end as an InputError.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "fuzz_util.h"
#include "isokit/skinning/rig_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool isolate = [] {
    const char* v = std::getenv("ISOKIT_FUZZ_ISOLATE");
    return v != nullptr && *v != '\0' && std::string(v) != "0";
  }();
  const std::string path = isokit::fuzz::write_input(data, size, "input." ISOKIT_FUZZ_EXT);
  isokit::skinning::LoadOptions options;
  options.isolate_importer = isolate;
  options.importer_timeout_seconds = 5;
  options.importer_memory_mib = 1024;
  isokit::fuzz::expect_input_error([&] { isokit::skinning::load_rig(path, options); });
  return 0;
}
