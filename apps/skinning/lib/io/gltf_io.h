// SPDX-License-Identifier: MIT
/// \file
/// Private glTF 2.0 helpers of the rig I/O, on tinygltf (the container, JSON, buffers, data URIs
/// and the GLB / .gltf writers are tinygltf's): a document builder with one binary buffer
/// (written as .glb or as .gltf with an embedded base64 buffer), the reader of a file, the
/// decoding of accessors (tinygltf leaves it to its users), and the scene of a model as an
/// aiScene (so that the loader reads every format from one structure).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <assimp/scene.h>

// tinygltf (Debian libtinygltf-dev) is compiled into isokit (io/tinygltf.cpp), in a namespace of
// its own: Debian's libdraco, which assimp links, exports an older tinygltf of its own (struct
// layouts differ), and linking libtinygltf.so next to it bound some calls to draco's copy (heap
// corruption on files with images). The rig reads no images and writes none: no stb.
#define tinygltf isokit_tinygltf
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include "isokit/core/load_budget.h"

namespace isokit::skinning::gltf {

// Component types and buffer-view targets of the glTF 2.0 specification.
constexpr int kByte = TINYGLTF_COMPONENT_TYPE_BYTE;
constexpr int kUnsignedByte = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
constexpr int kShort = TINYGLTF_COMPONENT_TYPE_SHORT;
constexpr int kUnsignedShort = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
constexpr int kUnsignedInt = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
constexpr int kFloat = TINYGLTF_COMPONENT_TYPE_FLOAT;
constexpr int kArrayBuffer = TINYGLTF_TARGET_ARRAY_BUFFER;
constexpr int kElementArrayBuffer = TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER;

/// Lower-case extension of `path` including the dot (".glb"), empty when none.
std::string extension(const std::string& path);

/// A glTF document under construction with a single binary buffer (every view 4-byte aligned).
class Builder {
 public:
  Builder();

  tinygltf::Model& model() { return model_; }
  std::size_t binary_size() const { return model_.buffers[0].data.size(); }

  /// Appends raw bytes as a buffer view; `target` 0 = none. Returns the view index.
  int add_view(const void* data, std::size_t bytes, int target = 0);
  /// Float accessor (`count` elements of `type`, "SCALAR" … "MAT4"), with exact per-component
  /// min/max if `min_max`.
  int add_floats(const float* data, std::size_t count, const std::string& type, bool min_max, int target = 0);
  /// Unsigned integer accessors of the given component type (u8, u16 or u32 data).
  int add_u8(const std::uint8_t* data, std::size_t count, const std::string& type, int target = 0);
  int add_u16(const std::uint16_t* data, std::size_t count, const std::string& type, int target = 0);
  int add_u32(const std::uint32_t* data, std::size_t count, const std::string& type, int target = 0);
  /// A VEC3 float accessor of `count` elements, zero except `values` at `indices` (ascending):
  /// a sparse accessor without a buffer view, with the min/max of the full array. An all-zero
  /// array is written as one explicit zero.
  int add_sparse_vec3(std::size_t count, const std::vector<std::uint32_t>& indices,
                      const std::vector<float>& values);

  /// Writes `.glb` when `binary`, else `.gltf` with the buffer as a base64 data URI (atomically).
  /// \throw InputError naming `path` if it cannot be written or the GLB exceeds 4 GiB.
  void write(const std::string& path, bool binary);

 private:
  int add_accessor(int view, int component_type, std::size_t count, const std::string& type);
  int add_float_view(const float* data, std::size_t n, int target = 0);

  tinygltf::Model model_;
};

/// Reads a .gltf or .glb file (its buffers too; images are not decoded). `warnings` gets
/// tinygltf's warnings, one line each. \throw InputError naming `path` for a missing magic in a
/// .glb, a truncated or malformed container, invalid JSON, a buffer that cannot be read, or a
/// glTF version other than 2.
/// `budget`, when given, gets the file's size and its external buffers' as its input.
tinygltf::Model read_model(const std::string& path, std::vector<std::string>* warnings = nullptr,
                           LoadBudget* budget = nullptr);

/// The scene of `model` as the loader reads every format: an aiScene built as assimp's glTF
/// importer builds it (io/gltf_scene.cpp says where and why it differs). `node_names`: one unique
/// name per node. \throw InputError naming `path` for a node cycle or a bad accessor.
/// What it decodes is charged to `budget` when given. A primitive's COLOR_n (n < kMaskColorSet)
/// becomes the mesh's colour set n; its scalar attribute `mask_attribute` (non-empty; the
/// relaxation mask, LoadOptions::mask) becomes colour set kMaskColorSet (r = g = b = value). A
/// colour or mask accessor of another shape is skipped with a line in `warnings` (when given): the
/// file stays readable.
std::unique_ptr<aiScene> to_ai_scene(const tinygltf::Model& model, const std::vector<std::string>& node_names,
                                     const std::string& path, LoadBudget* budget = nullptr,
                                     const std::string& mask_attribute = "",
                                     std::vector<std::string>* warnings = nullptr);

/// The aiMesh colour set that carries a glTF primitive's relaxation-mask attribute.
constexpr unsigned kMaskColorSet = 7;

/// Reads accessor `index` as doubles (`count * components` values; normalized integers mapped to
/// [0, 1] / [-1, 1], sparse substitution applied). Every declared size is checked before anything
/// is allocated: the count against its buffer view and the view against its buffer, the sparse
/// count against the accessor's and its views; an accessor without a buffer view may declare at
/// most as many bytes as the file's buffers hold (or 1 MiB). The decoded doubles are charged to
/// `budget` when given. \throw InputError naming `what` for a bad accessor (unknown type, a count
/// its view does not hold, a view out of its buffer, a load past the budget).
std::vector<double> read_accessor(const tinygltf::Model& model, int index, int* components,
                                  const std::string& what, LoadBudget* budget = nullptr);

}  // namespace isokit::skinning::gltf
