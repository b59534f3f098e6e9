// SPDX-License-Identifier: MIT
// Fuzz target: the operator spec JSON (`spec_from_json`, what `load_spec` parses), and the curves
// of a spec that parses (`polyline` at a few d). Expected outcome for bad input: InputError.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_util.h"
#include "isokit/operators/spec.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  isokit::fuzz::expect_input_error([&] {
    const isokit::operators::OperatorSpec spec = isokit::operators::spec_from_json(text, "fuzz.json");
    for (const auto& curve : spec.curves)
      for (double d : {0.0, 0.5, 1.0}) curve.polyline(d);
    spec.make_controller();
  });
  return 0;
}
