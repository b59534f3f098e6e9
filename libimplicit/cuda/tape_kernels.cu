// SPDX-License-Identifier: MIT
// The program kernel: one thread per point runs `eval_sparse_layout`, the host/device evaluator
// that the CPU tests compare with `SparseEvaluator::eval` bit for bit.
#include <cuda_runtime.h>

#include <stdexcept>
#include <string>

#include "tape_view.h"

namespace isokit::implicit::cuda::detail {
namespace {

void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess) throw std::runtime_error(std::string("CUDA ") + what + ": " + cudaGetErrorString(e));
}

__global__ void eval_kernel(TapeSparseLayout t, const Vec3f* points, std::size_t n, FieldSample* out) {
  const std::size_t i = blockIdx.x * static_cast<std::size_t>(blockDim.x) + threadIdx.x;
  if (i < n) out[i] = eval_sparse_layout(t, points[i]);
}

}  // namespace

void* device_alloc(std::size_t bytes) {
  void* p = nullptr;
  if (bytes) check(cudaMalloc(&p, bytes), "cudaMalloc");
  return p;
}
void device_free(void* p) noexcept {
  cudaFree(p);
}
void copy_to_device(void* dst, const void* src, std::size_t bytes) {
  if (bytes) check(cudaMemcpy(dst, src, bytes, cudaMemcpyHostToDevice), "upload");
}
void copy_to_host(void* dst, const void* src, std::size_t bytes) {
  if (bytes) check(cudaMemcpy(dst, src, bytes, cudaMemcpyDeviceToHost), "download");
}

void launch_tape_eval(const TapeSparseLayout& layout, const Vec3f* points, std::size_t n, FieldSample* out) {
  if (n == 0) return;
  const unsigned block = 128;
  const auto grid = static_cast<unsigned>((n + block - 1) / block);
  eval_kernel<<<grid, block>>>(layout, points, n, out);
  check(cudaGetLastError(), "tape kernel launch");
  check(cudaDeviceSynchronize(), "tape kernel");
}

}  // namespace isokit::implicit::cuda::detail
