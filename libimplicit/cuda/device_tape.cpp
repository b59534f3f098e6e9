// SPDX-License-Identifier: MIT
// DeviceTape, host side: uploads a program's sparse records at a pose (pointers re-targeted to device
// copies, shared arrays uploaded once) and calls the kernel in tape_kernels.cu.
#include <map>
#include <string>
#include <vector>

#include "isokit/core/error.h"
#include "isokit/implicit/cuda/device_tape.h"
#include "tape_view.h"

namespace isokit::implicit::cuda {
namespace {

/// Owning device buffer, freed on destruction.
class Buffer {
 public:
  Buffer() = default;
  Buffer(const void* host, std::size_t bytes) { assign(host, bytes); }
  /// Allocates without uploading (an output buffer).
  explicit Buffer(std::size_t bytes) { resize(bytes); }
  ~Buffer() { detail::device_free(ptr_); }
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  Buffer(Buffer&& o) noexcept : ptr_(o.ptr_), bytes_(o.bytes_) { o.ptr_ = nullptr, o.bytes_ = 0; }
  void assign(const void* host, std::size_t bytes) {
    resize(bytes);
    detail::copy_to_device(ptr_, host, bytes);
  }
  void resize(std::size_t bytes) {
    if (bytes == bytes_) return;
    detail::device_free(ptr_);
    ptr_ = nullptr;  // stays empty if the allocation throws
    bytes_ = 0;
    ptr_ = detail::device_alloc(bytes);
    bytes_ = bytes;
  }
  template <class T>
  T* as() const {
    return static_cast<T*>(ptr_);
  }

 private:
  void* ptr_{nullptr};
  std::size_t bytes_{0};
};

}  // namespace

struct DeviceTape::Impl {
  TapeSparseLayout view;  // device pointers
  std::size_t leaf_count{0};
  Buffer frames, lca, nodes, leaves, controllers, grids;
  std::vector<Buffer> arrays;                    // leaf grids and operator data, uploaded once
  std::map<const void*, const void*> device_of;  // host array -> its device copy

  template <class T>
  const T* upload_array(const T* host, std::size_t count) {
    if (!host) return nullptr;
    const auto it = device_of.find(host);
    if (it != device_of.end()) return static_cast<const T*>(it->second);
    arrays.emplace_back(host, count * sizeof(T));
    const T* d = arrays.back().as<const T>();
    device_of[host] = d;
    return d;
  }
  void upload_leaves(const TapeSparseLayout& l) {
    std::vector<TapeLeaf> records(l.leaf_records, l.leaf_records + l.leaves);
    for (TapeLeaf& leaf : records) {
      const std::size_t n = static_cast<std::size_t>(leaf.grid.n);
      // Either storage (grid_math.h): the view's pointer that is set is re-targeted.
      leaf.grid.nodes = upload_array(leaf.grid.nodes, 4 * n * n * n);
      leaf.grid.packed = upload_array(leaf.grid.packed, 4 * n * n * n);
      leaf.grid.occupied = nullptr;  // the device code evaluates every leaf whose box holds the point
    }
    leaves.assign(records.data(), records.size() * sizeof(TapeLeaf));
    frames.assign(l.frames, 18 * l.frame_stride * sizeof(float));
    view.leaf_records = leaves.as<const TapeLeaf>();
    view.frames = frames.as<const float>();
  }
};

DeviceTape::DeviceTape(const Program& program, const Pose& pose) : impl_(std::make_unique<Impl>()) {
  const TapeSparseLayout l = sparse_layout(program, pose);
  for (std::size_t k = 0; k < l.leaves; ++k)
    require(l.leaf_records[k].grid.valid(), "program leaf " + std::to_string(k),
            "is not a sampled grid (only grid leaves run on the device)", "sample the primitives into grids");
  Impl& d = *impl_;
  d.leaf_count = l.leaves;
  d.view.leaves = l.leaves;
  d.view.frame_stride = l.frame_stride;
  d.view.node_count = l.node_count;
  d.view.operator_count = l.operator_count;
  d.upload_leaves(l);
  d.lca.assign(l.lca, l.leaves * l.leaves);
  d.nodes.assign(l.nodes, l.node_count * sizeof(TapeSparseNode));
  d.controllers.assign(l.controllers, l.operator_count * sizeof(operators::ControllerTable));
  std::vector<operators::GridOperatorView> grids(l.grids, l.grids + l.operator_count);
  for (operators::GridOperatorView& g : grids) {
    // A program's views read their padded copy, float or packed (program.h); `data` is null.
    if (!g.padded && !g.packed) continue;
    g.data = nullptr;
    g.padded = d.upload_array(g.padded, g.padded_size());
    g.packed = d.upload_array(g.packed, g.padded_size());
    g.packed_tiles = d.upload_array(g.packed_tiles, 2 * g.packed_tile_count());
  }
  d.grids.assign(grids.data(), grids.size() * sizeof(operators::GridOperatorView));
  d.view.lca = d.lca.as<const std::uint8_t>();
  d.view.nodes = d.nodes.as<const TapeSparseNode>();
  d.view.controllers = d.controllers.as<const operators::ControllerTable>();
  d.view.grids = d.grids.as<const operators::GridOperatorView>();
}

DeviceTape::~DeviceTape() = default;

void DeviceTape::update_transforms(const Program& program, const Pose& pose) {
  const TapeSparseLayout l = sparse_layout(program, pose);
  require(l.leaves == impl_->leaf_count, "program", "has a different structure than the device copy",
          "build a new DeviceTape");
  impl_->upload_leaves(l);
}

void DeviceTape::eval(const Vec3f* points, std::size_t n, FieldSample* out) const {
  if (n == 0) return;
  Buffer d_points(points, n * sizeof(Vec3f));
  Buffer d_out(n * sizeof(FieldSample));
  detail::launch_tape_eval(impl_->view, d_points.as<const Vec3f>(), n, d_out.as<FieldSample>());
  detail::copy_to_host(out, d_out.as<FieldSample>(), n * sizeof(FieldSample));
}

}  // namespace isokit::implicit::cuda
