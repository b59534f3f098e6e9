// SPDX-License-Identifier: MIT
/// \file
/// The seed corpora of the fuzz targets (docs/fuzzing.md), written with the project's own writers:
/// OUT/glb, OUT/gltf (save_rig of a small two-joint rig with a clip), OUT/dae, OUT/fbx (that rig
/// exported by assimp, which the loader reads these formats with; the binary .fbx does not load
/// back, assimp's own exporter/importer mismatch, but seeds the parser), OUT/setup (the documented
/// setup example, checked by setup_from_json), OUT/spec (spec_to_json of every preset) and OUT/npy
/// (save_operator of an 8 x 8 x 8 grid). Shared by `isokit_fuzz_seeds` and the load-budget test.
#pragma once

#include <filesystem>

namespace isokit::fuzz {

/// Writes every seed under `out` (creating the folders). \throw std::exception on a write error.
void write_seeds(const std::filesystem::path& out);

}  // namespace isokit::fuzz
