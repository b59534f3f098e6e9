// SPDX-License-Identifier: MIT
/// \file
/// A device copy of a sparse `Program` at a `Pose` (issue 7, step 1): leaf frames and boxes, leaf
/// grids, the sparse composition records, controllers and grid operators, evaluated one thread per point by
/// the same inline math the CPU runs (`eval_grid_inside_scalar`, `compose_node`). Host-side API
/// without CUDA headers; every function throws `std::runtime_error` with the CUDA error string
/// on failure (including when no device is present).
///
/// Not yet verified on a device (written in a session without a GPU): `tests/gpu/test_gpu_tape`
/// compares it with the CPU evaluators and is skipped until a machine with a GPU runs it.
#pragma once

#include <cstddef>
#include <memory>

#include "isokit/implicit/pose.h"
#include "isokit/implicit/program.h"

namespace isokit::implicit::cuda {

class DeviceTape {
 public:
  /// Uploads `program` at `pose`. \throw InputError when the program is not sparse, the pose is
  /// not the program's, or a leaf is not a sampled grid (only grids run on the device);
  /// std::runtime_error on CUDA errors.
  DeviceTape(const Program& program, const Pose& pose);
  ~DeviceTape();
  DeviceTape(const DeviceTape&) = delete;
  DeviceTape& operator=(const DeviceTape&) = delete;

  /// Uploads the leaves' transforms of another pose of the program given at construction (the
  /// controller tables stay those uploaded then).
  void update_transforms(const Program& program, const Pose& pose);

  /// Evaluates `n` host points (copies in and out).
  void eval(const Vec3f* points, std::size_t n, FieldSample* out) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace isokit::implicit::cuda
