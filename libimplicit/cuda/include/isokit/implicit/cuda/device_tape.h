// SPDX-License-Identifier: MIT
/// \file
/// A device copy of a sparse `Tape` (issue 7, step 1): leaf frames and boxes, leaf grids, the
/// sparse composition records, controllers and grid operators, evaluated one thread per point by
/// the same inline math the CPU runs (`eval_grid_inside_scalar`, `compose_node`). Host-side API
/// without CUDA headers; every function throws `std::runtime_error` with the CUDA error string
/// on failure (including when no device is present).
///
/// Not yet verified on a device (written in a session without a GPU): `tests/gpu/test_gpu_tape`
/// compares it with the CPU tape and is skipped until a machine with a GPU runs it.
#pragma once

#include <cstddef>
#include <memory>

#include "isokit/implicit/tape.h"

namespace isokit::implicit::cuda {

class DeviceTape {
 public:
  /// Uploads `tape`. \throw InputError when the tape is not sparse or has a leaf that is not a
  /// sampled grid (only grids run on the device); std::runtime_error on CUDA errors.
  explicit DeviceTape(const Tape& tape);
  ~DeviceTape();
  DeviceTape(const DeviceTape&) = delete;
  DeviceTape& operator=(const DeviceTape&) = delete;

  /// Uploads the leaves' transforms again (after `Tape::set_leaf_transform`; the tape must have
  /// the same structure as at construction).
  void update_transforms(const Tape& tape);

  /// Evaluates `n` host points (copies in and out).
  void eval(const Vec3f* points, std::size_t n, FieldSample* out) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace isokit::implicit::cuda
