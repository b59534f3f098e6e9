// SPDX-License-Identifier: MIT
/// \file
/// Private glTF 2.0 helpers of the rig I/O: a document builder with one binary buffer (written as
/// .glb or as .gltf with an embedded base64 buffer) and a small reader of the glTF container and
/// accessors used to check files before assimp reads them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace isokit::skinning::gltf {

// Component types and buffer-view targets of the glTF 2.0 specification.
constexpr int kByte = 5120;
constexpr int kUnsignedByte = 5121;
constexpr int kShort = 5122;
constexpr int kUnsignedShort = 5123;
constexpr int kUnsignedInt = 5125;
constexpr int kFloat = 5126;
constexpr int kArrayBuffer = 34962;
constexpr int kElementArrayBuffer = 34963;

/// Bytes of one component of a glTF component type (0 for an unknown type).
int component_size(int component_type);
/// Components of an accessor type ("SCALAR" 1 … "MAT4" 16; 0 for an unknown type).
int type_components(const std::string& type);

/// Lower-case extension of `path` including the dot (".glb"), empty when none.
std::string extension(const std::string& path);

/// A glTF document under construction with a single binary buffer (every view 4-byte aligned).
class Builder {
 public:
  Builder();

  nlohmann::json& doc() { return doc_; }
  std::size_t binary_size() const { return bin_.size(); }

  /// Appends raw bytes as a buffer view; `target` 0 = none. Returns the view index.
  int add_view(const void* data, std::size_t bytes, int target = 0);
  /// An accessor over a whole view.
  int add_accessor(int view, int component_type, std::size_t count, const std::string& type,
                   bool normalized = false);
  /// Float accessor (`count` elements of `type`), with exact per-component min/max if `min_max`.
  int add_floats(const float* data, std::size_t count, const std::string& type, bool min_max, int target = 0);
  /// Unsigned integer accessors of the given component type (u8, u16 or u32 data).
  int add_u8(const std::uint8_t* data, std::size_t count, const std::string& type, int target = 0);
  int add_u16(const std::uint16_t* data, std::size_t count, const std::string& type, int target = 0);
  int add_u32(const std::uint32_t* data, std::size_t count, const std::string& type, int target = 0);
  /// A VEC3 float accessor of `count` elements, zero except `values` at `indices` (ascending):
  /// a sparse accessor without a buffer view, with the
  /// min/max of the full array. An all-zero array is written as one explicit zero.
  int add_sparse_vec3(std::size_t count, const std::vector<std::uint32_t>& indices,
                      const std::vector<float>& values);

  /// Writes `.glb` when `binary`, else `.gltf` with the buffer as a base64 data URI.
  /// \throw InputError naming `path` if it cannot be written or the GLB exceeds 4 GiB.
  void write(const std::string& path, bool binary);

 private:
  int add_float_view(const float* data, std::size_t n, int target = 0);

  nlohmann::json doc_;
  std::vector<std::uint8_t> bin_;
};

/// A parsed glTF file: its JSON and its buffers' bytes (GLB chunk, data URI or external file).
struct Document {
  nlohmann::json json;
  std::vector<std::vector<std::uint8_t>> buffers;
};

/// Reads a .gltf or .glb container. \throw InputError naming `path` for a truncated or malformed
/// GLB, invalid JSON, a glTF version other than 2, or a buffer that cannot be read or is short.
Document read_document(const std::string& path);

/// Reads accessor `index` as doubles (`count * components` values; normalized integers mapped to
/// [0, 1] / [-1, 1], sparse substitution applied). \throw InputError naming `what` for a bad
/// accessor (unknown type, view out of range, data past the end of the buffer).
std::vector<double> read_accessor(const Document& doc, int index, int* components, const std::string& what);

/// Base64 (RFC 4648, with padding).
std::string base64_encode(const std::uint8_t* data, std::size_t size);
/// \return false for characters outside the alphabet.
bool base64_decode(const std::string& text, std::vector<std::uint8_t>& out);

}  // namespace isokit::skinning::gltf
