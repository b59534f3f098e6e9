// SPDX-License-Identifier: MIT
// isokit_load_probe: one load of one file in a process of its own, so that a test can measure the
// load's peak memory (tests/skinning/test_load_budget.cpp, docs/fuzzing.md "Memory budget").
//   isokit_load_probe rig|setup|spec|npy|pose FILE   load it; exit 0, or 2 with the InputError
//   isokit_load_probe none                           load nothing (the process's own baseline)
//   isokit_load_probe seeds DIR                      write the fuzz targets' seed inputs
// Any other outcome (another exception, a crash) exits otherwise, and the test fails.
#include <cstdio>
#include <filesystem>
#include <new>
#include <string>

#include "isokit/core/error.h"
#include "isokit/operators/io.h"
#include "isokit/operators/spec.h"
#include "isokit/skinning/animation.h"
#include "isokit/skinning/procedural.h"
#include "isokit/skinning/rig_io.h"
#include "isokit/skinning/setup.h"
#include "seeds.h"

namespace {

void load(const std::string& kind, const std::string& file) {
  using namespace isokit;
  if (kind == "rig") {
    skinning::load_rig(file);
  } else if (kind == "setup") {
    skinning::load_setup(file);
  } else if (kind == "spec") {
    operators::load_spec(file);
  } else if (kind == "npy") {
    operators::load_operator(file);
  } else if (kind == "pose") {
    skinning::pose_script_animation(skinning::make_cylinder(), file);
  } else if (kind != "none") {
    throw std::logic_error("unknown kind " + kind);
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return 64;
  const std::string kind = argv[1];
  const std::string file = argc > 2 ? argv[2] : "";
  try {
    if (kind == "seeds") {
      isokit::fuzz::write_seeds(file);
      return 0;
    }
    load(kind, file);
    return 0;
  } catch (const isokit::InputError& e) {
    std::printf("%s\n", e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    std::printf("bad_alloc\n");
    return 5;
  } catch (const std::exception& e) {
    std::printf("other exception: %s\n", e.what());
    return 4;
  }
}
