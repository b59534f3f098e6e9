// SPDX-License-Identifier: MIT
// isokit_fuzz_seeds OUT: writes the seed corpora of the fuzz targets (seeds.h, docs/fuzzing.md).
// isokit_fuzz_seeds --budget-mb BYTES: prints the load budget of an input of BYTES bytes in MiB
// (isokit/core/load_budget.h), which scripts/run-fuzz.sh passes to libFuzzer's -malloc_limit_mb.
#include <cstdlib>
#include <iostream>
#include <string>

#include "isokit/core/load_budget.h"
#include "seeds.h"

int main(int argc, char** argv) {
  if (argc == 3 && std::string(argv[1]) == "--budget-mb") {
    const std::uint64_t bytes = std::strtoull(argv[2], nullptr, 10);
    std::cout << (isokit::load_budget_bytes(bytes) + (1u << 20) - 1) / (1u << 20) << "\n";
    return 0;
  }
  if (argc != 2) {
    std::cerr << "usage: isokit_fuzz_seeds OUT_DIR | --budget-mb INPUT_BYTES\n";
    return 2;
  }
  try {
    isokit::fuzz::write_seeds(argv[1]);
  } catch (const std::exception& e) {
    std::cerr << "isokit_fuzz_seeds: " << e.what() << "\n";
    return 1;
  }
  std::cout << "seeds written to " << argv[1] << "\n";
  return 0;
}
