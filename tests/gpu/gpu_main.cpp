// SPDX-License-Identifier: MIT
// Catch2 main of the gpu-labelled tests: without a CUDA device the program prints why and exits
// 77, which CTest reports as "skipped" (never as passed).
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include <cstdio>

#include "isokit/implicit/cuda/device_eval.h"

int main(int argc, char** argv) {
  using namespace isokit::implicit;
  if (!cuda::device_available()) {
    std::printf("SKIPPED: no CUDA device (%s)\n", cuda::device_description());
    return 77;
  }
  std::printf("CUDA device: %s\n", cuda::device_description());
  return Catch::Session().run(argc, argv);
}
