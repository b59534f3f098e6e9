// SPDX-License-Identifier: MIT
// Thin kernels over the shared host/device field math: one thread per point.
#include <cuda_runtime.h>

#include <stdexcept>
#include <string>

#include "isokit/implicit/cuda/device_eval.h"

namespace isokit::implicit::cuda {
namespace {

void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess) throw std::runtime_error(std::string("CUDA ") + what + ": " + cudaGetErrorString(e));
}

/// Device buffer owning `count` elements of T; freed on scope exit.
template <class T>
class DeviceArray {
 public:
  explicit DeviceArray(std::size_t count) : count_(count) {
    check(cudaMalloc(reinterpret_cast<void**>(&ptr_), count * sizeof(T)), "cudaMalloc");
  }
  ~DeviceArray() { cudaFree(ptr_); }
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  void upload(const T* host) {
    check(cudaMemcpy(ptr_, host, count_ * sizeof(T), cudaMemcpyHostToDevice), "upload");
  }
  void download(T* host) const {
    check(cudaMemcpy(host, ptr_, count_ * sizeof(T), cudaMemcpyDeviceToHost), "download");
  }
  T* get() const { return ptr_; }

 private:
  T* ptr_{nullptr};
  std::size_t count_;
};

template <class Eval>
__global__ void eval_kernel(Eval eval, const Vec3f* points, std::size_t n, FieldSample* out) {
  const std::size_t i = blockIdx.x * static_cast<std::size_t>(blockDim.x) + threadIdx.x;
  if (i < n) out[i] = eval(points[i]);
}

template <class Eval>
void run(const Eval& eval, const Vec3f* points, std::size_t n, FieldSample* out) {
  if (n == 0) return;
  DeviceArray<Vec3f> d_points(n);
  DeviceArray<FieldSample> d_out(n);
  d_points.upload(points);
  const unsigned block = 256;
  const auto grid = static_cast<unsigned>((n + block - 1) / block);
  eval_kernel<<<grid, block>>>(eval, d_points.get(), n, d_out.get());
  check(cudaGetLastError(), "kernel launch");
  check(cudaDeviceSynchronize(), "kernel");
  d_out.download(out);
}

struct SphereEval {
  SphereParamsT<float> s;
  __device__ FieldSample operator()(const Vec3f& p) const { return eval_sphere(s, p); }
};
struct CapsuleEval {
  CapsuleParamsT<float> c;
  __device__ FieldSample operator()(const Vec3f& p) const { return eval_capsule(c, p); }
};
struct GridEval {
  GridView g;
  __device__ FieldSample operator()(const Vec3f& p) const { return eval_grid(g, p); }
};

}  // namespace

bool device_available() {
  int count = 0;
  return cudaGetDeviceCount(&count) == cudaSuccess && count > 0;
}

const char* device_description() {
  static thread_local cudaDeviceProp prop;
  int count = 0;
  const cudaError_t e = cudaGetDeviceCount(&count);
  if (e != cudaSuccess) return cudaGetErrorString(e);
  if (count == 0) return "no CUDA device";
  check(cudaGetDeviceProperties(&prop, 0), "cudaGetDeviceProperties");
  return prop.name;
}

void eval_sphere(const SphereParamsT<float>& s, const Vec3f* points, std::size_t n, FieldSample* out) {
  run(SphereEval{s}, points, n, out);
}

void eval_capsule(const CapsuleParamsT<float>& c, const Vec3f* points, std::size_t n, FieldSample* out) {
  run(CapsuleEval{c}, points, n, out);
}

void eval_grid(const GridView& grid, const Vec3f* points, std::size_t n, FieldSample* out) {
  // Either storage (grid_math.h): 4 channels per node, as floats or as int16.
  const std::size_t count = 4 * static_cast<std::size_t>(grid.n) * grid.n * grid.n;
  GridView dg = grid;
  dg.occupied = nullptr;  // host memory; eval_grid does not read it
  if (grid.packed) {
    DeviceArray<std::int16_t> d_packed(count);
    d_packed.upload(grid.packed);
    dg.packed = d_packed.get();
    run(GridEval{dg}, points, n, out);
    return;
  }
  DeviceArray<float> d_nodes(count);
  d_nodes.upload(grid.nodes);
  dg.nodes = d_nodes.get();
  run(GridEval{dg}, points, n, out);
}

}  // namespace isokit::implicit::cuda
