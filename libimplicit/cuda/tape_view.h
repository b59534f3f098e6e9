// SPDX-License-Identifier: MIT
// Internal to the CUDA backend: the kernel launch and the few runtime calls the host side needs
// (kept out of the .cu so that the host code, which builds tape records with Eigen-based
// headers around, is compiled by the host compiler only).
#pragma once

#include <cstddef>

#include "isokit/implicit/tape_records.h"

namespace isokit::implicit::cuda::detail {

/// Device memory (std::runtime_error with the CUDA message on failure).
void* device_alloc(std::size_t bytes);
void device_free(void* p) noexcept;
void copy_to_device(void* dst, const void* src, std::size_t bytes);
void copy_to_host(void* dst, const void* src, std::size_t bytes);

/// out[i] = eval_sparse_layout(layout, points[i]) for i < n; every pointer (the layout's too) on
/// the device. Waits for the kernel.
void launch_tape_eval(const TapeSparseLayout& layout, const Vec3f* points, std::size_t n, FieldSample* out);

}  // namespace isokit::implicit::cuda::detail
