// SPDX-License-Identifier: MIT
/// \file
/// Grid operators on disk: `X.npy` (NumPy format 1.0, little-endian float32, C order, shape
/// `[nd, nf, nf]`, d slowest, then f1, then f2) with its spec beside it as `X.json` (the spec
/// plus a "grid" object naming the .npy and its shape). Both are written to temporary names and
/// renamed, so a failure never leaves a half-written file.
#pragma once

#include <string>

#include "isokit/operators/grid_operator.h"
#include "isokit/operators/spec.h"

namespace isokit::operators {

struct StoredOperator {
  OperatorSpec spec;
  GridOperator grid;
};

/// `X.json` for `X.npy`.
std::string spec_path_for(const std::string& npy_path);

/// Writes the spec beside `npy_path`, then `npy_path` (each atomically: a failed spec leaves the
/// .npy untouched). \throw isokit::InputError if the grid's shape does not match the spec or a
/// file cannot be written (the message names the file).
void save_operator(const std::string& npy_path, const OperatorSpec& spec, const GridOperator& grid);

/// Reads and validates both files. \throw isokit::InputError naming the file and the field
/// (missing/truncated file, wrong magic/dtype/order/shape, spec errors, shape vs spec mismatch).
StoredOperator load_operator(const std::string& npy_path);

/// Raw .npy float32 3D array I/O (used by the above).
void write_npy_f32(const std::string& path, const float* data, int d0, int d1, int d2);
std::vector<float> read_npy_f32(const std::string& path, int* d0, int* d1, int* d2);

}  // namespace isokit::operators
