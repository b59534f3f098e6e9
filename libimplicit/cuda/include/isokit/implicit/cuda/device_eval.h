// SPDX-License-Identifier: MIT
/// \file
/// CUDA evaluation of the field math in `field_math.h` and `grid_math.h` (the same inline
/// functions the CPU runs).
/// Host-side API without CUDA headers. All functions throw `std::runtime_error` with the CUDA
/// error string on failure, including when no device is present.
#pragma once

#include <cstddef>

#include "isokit/implicit/field_math.h"
#include "isokit/implicit/grid_math.h"

namespace isokit::implicit::cuda {

/// True when the CUDA runtime reports at least one usable device.
bool device_available();
/// Name of device 0, or the runtime's reason why there is none.
const char* device_description();

/// Evaluates `n` host points on the device (copies in and out).
void eval_sphere(const SphereParamsT<float>& s, const Vec3f* points, std::size_t n, FieldSample* out);
void eval_capsule(const CapsuleParamsT<float>& c, const Vec3f* points, std::size_t n, FieldSample* out);
/// `grid.nodes` or `grid.packed` is a host pointer (`4 n^3` floats or int16); it is uploaded for
/// the call.
void eval_grid(const GridView& grid, const Vec3f* points, std::size_t n, FieldSample* out);

}  // namespace isokit::implicit::cuda
