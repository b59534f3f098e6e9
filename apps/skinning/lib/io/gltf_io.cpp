// SPDX-License-Identifier: MIT
#include "io/gltf_io.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <ostream>
#include <stdexcept>

#include "isokit/core/atomic_file.h"
#include "isokit/core/error.h"
#include "isokit/core/load_budget.h"

namespace isokit::skinning::gltf {

namespace fs = std::filesystem;

namespace {

bool little_endian_host() {
  const std::uint16_t one = 1;
  std::uint8_t first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

std::size_t pad4(std::size_t n) {
  return (n + 3) & ~std::size_t{3};
}

int type_code(const std::string& type) {
  if (type == "SCALAR") return TINYGLTF_TYPE_SCALAR;
  if (type == "VEC2") return TINYGLTF_TYPE_VEC2;
  if (type == "VEC3") return TINYGLTF_TYPE_VEC3;
  if (type == "VEC4") return TINYGLTF_TYPE_VEC4;
  if (type == "MAT4") return TINYGLTF_TYPE_MAT4;
  throw std::logic_error("gltf::Builder: unsupported accessor type " + type);
}

/// Components of an accessor type ("SCALAR" 1 … "MAT4" 16).
std::size_t components(const std::string& type) {
  return static_cast<std::size_t>(
      tinygltf::GetNumComponentsInType(static_cast<std::uint32_t>(type_code(type))));
}

template <typename T>
std::vector<std::uint8_t> to_le_bytes(const T* data, std::size_t n) {
  std::vector<std::uint8_t> out(n * sizeof(T));
  for (std::size_t i = 0; i < n; ++i) {
    const auto v = static_cast<std::uint64_t>(data[i]);
    for (std::size_t b = 0; b < sizeof(T); ++b)
      out[i * sizeof(T) + b] = static_cast<std::uint8_t>(v >> (8 * b));
  }
  return out;
}

// tinygltf reads images through a callback; the rig needs none, so they are left undecoded.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                void*) {
  return true;
}

// tinygltf's messages can span lines; an InputError is one line.
std::string one_line(std::string s) {
  std::replace(s.begin(), s.end(), '\n', ' ');
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

}  // namespace

std::string extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// ---------------------------------------------------------------------------------------------
// Builder

Builder::Builder() {
  model_.asset.version = "2.0";
  model_.asset.generator = "isokit";
  model_.buffers.resize(1);
}

int Builder::add_view(const void* data, std::size_t bytes, int target) {
  std::vector<unsigned char>& bin = model_.buffers[0].data;
  const std::size_t offset = bin.size();
  bin.resize(pad4(offset + bytes), 0);
  if (bytes > 0) std::memcpy(bin.data() + offset, data, bytes);
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteOffset = offset;
  view.byteLength = bytes;
  view.target = target;
  model_.bufferViews.push_back(view);
  return static_cast<int>(model_.bufferViews.size()) - 1;
}

int Builder::add_accessor(int view, int component_type, std::size_t count, const std::string& type) {
  tinygltf::Accessor a;
  a.bufferView = view;
  a.componentType = component_type;
  a.count = count;
  a.type = type_code(type);
  model_.accessors.push_back(a);
  return static_cast<int>(model_.accessors.size()) - 1;
}

int Builder::add_float_view(const float* data, std::size_t n, int target) {
  if (little_endian_host()) return add_view(data, n * sizeof(float), target);
  std::vector<std::uint32_t> bits(n);
  std::memcpy(bits.data(), data, n * sizeof(float));
  const auto le = to_le_bytes(bits.data(), n);
  return add_view(le.data(), le.size(), target);
}

int Builder::add_floats(const float* data, std::size_t count, const std::string& type, bool min_max,
                        int target) {
  const std::size_t c = components(type);
  const int acc = add_accessor(add_float_view(data, count * c, target), kFloat, count, type);
  if (min_max && count > 0) {
    std::vector<float> lo(c, std::numeric_limits<float>::infinity());
    std::vector<float> hi(c, -std::numeric_limits<float>::infinity());
    for (std::size_t i = 0; i < count; ++i)
      for (std::size_t k = 0; k < c; ++k) {
        lo[k] = std::min(lo[k], data[i * c + k]);
        hi[k] = std::max(hi[k], data[i * c + k]);
      }
    tinygltf::Accessor& a = model_.accessors[static_cast<std::size_t>(acc)];
    a.minValues.assign(lo.begin(), lo.end());
    a.maxValues.assign(hi.begin(), hi.end());
  }
  return acc;
}

int Builder::add_u8(const std::uint8_t* data, std::size_t count, const std::string& type, int target) {
  return add_accessor(add_view(data, count * components(type), target), kUnsignedByte, count, type);
}

int Builder::add_u16(const std::uint16_t* data, std::size_t count, const std::string& type, int target) {
  const auto bytes = to_le_bytes(data, count * components(type));
  return add_accessor(add_view(bytes.data(), bytes.size(), target), kUnsignedShort, count, type);
}

int Builder::add_u32(const std::uint32_t* data, std::size_t count, const std::string& type, int target) {
  const auto bytes = to_le_bytes(data, count * components(type));
  return add_accessor(add_view(bytes.data(), bytes.size(), target), kUnsignedInt, count, type);
}

int Builder::add_sparse_vec3(std::size_t count, const std::vector<std::uint32_t>& indices,
                             const std::vector<float>& values) {
  const int acc = add_accessor(-1, kFloat, count, "VEC3");
  const bool has_zeros = count > indices.size();
  std::vector<double> lo(3, has_zeros ? 0.0 : std::numeric_limits<double>::infinity());
  std::vector<double> hi(3, has_zeros ? 0.0 : -std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < indices.size(); ++i)
    for (std::size_t k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], static_cast<double>(values[3 * i + k]));
      hi[k] = std::max(hi[k], static_cast<double>(values[3 * i + k]));
    }
  if (count == 0) lo = hi = {0.0, 0.0, 0.0};
  model_.accessors[static_cast<std::size_t>(acc)].minValues = lo;
  model_.accessors[static_cast<std::size_t>(acc)].maxValues = hi;
  if (count == 0) return acc;
  // An all-zero accessor: glTF allows one without data, but assimp 5.2 rejects it, so it carries
  // one explicit zero (sparse count must be >= 1). Index views carry no target; the indices take
  // the smallest component type that holds the largest.
  const std::vector<std::uint32_t> zero_index{0};
  const std::vector<float> zero_value{0.0f, 0.0f, 0.0f};
  const std::vector<std::uint32_t>& idx = indices.empty() ? zero_index : indices;
  const std::vector<float>& val = indices.empty() ? zero_value : values;
  const std::uint32_t last = idx.back();
  int index_view = 0;
  int index_type = kUnsignedInt;
  if (last <= 0xFF) {
    const std::vector<std::uint8_t> v(idx.begin(), idx.end());
    index_view = add_view(v.data(), v.size());
    index_type = kUnsignedByte;
  } else if (last <= 0xFFFF) {
    const std::vector<std::uint16_t> v(idx.begin(), idx.end());
    const auto bytes = to_le_bytes(v.data(), v.size());
    index_view = add_view(bytes.data(), bytes.size());
    index_type = kUnsignedShort;
  } else {
    const auto bytes = to_le_bytes(idx.data(), idx.size());
    index_view = add_view(bytes.data(), bytes.size());
  }
  const int values_view = add_float_view(val.data(), val.size());
  tinygltf::Accessor& a = model_.accessors[static_cast<std::size_t>(acc)];
  a.sparse.isSparse = true;
  a.sparse.count = static_cast<int>(idx.size());
  a.sparse.indices.bufferView = index_view;
  a.sparse.indices.byteOffset = 0;
  a.sparse.indices.componentType = index_type;
  a.sparse.values.bufferView = values_view;
  a.sparse.values.byteOffset = 0;
  return acc;
}

void Builder::write(const std::string& path, bool binary) {
  if (model_.buffers[0].data.empty()) model_.buffers.clear();
  const std::uint64_t bin = model_.buffers.empty() ? 0 : pad4(model_.buffers[0].data.size());
  // A bound of the JSON chunk (an accessor with its views and min/max takes < 1 KiB of JSON).
  const std::uint64_t json_bound = 1024 * 1024 + 2048 * static_cast<std::uint64_t>(model_.accessors.size());
  require(!binary || 28 + bin + json_bound <= std::numeric_limits<std::uint32_t>::max(), path,
          "the GLB would pass the format's 4 GiB limit (" + std::to_string(bin) + " bytes of data)",
          "write fewer frames or vertices");
  tinygltf::TinyGLTF writer;
  write_stream_atomically(path, [&](std::ostream& out) {
    require(writer.WriteGltfSceneToStream(&model_, out, false, binary), path, "tinygltf could not write it",
            "check the free disk space");
  });
}

// ---------------------------------------------------------------------------------------------
// Reader

tinygltf::Model read_model(const std::string& path, std::vector<std::string>* warnings, LoadBudget* budget) {
  std::ifstream in(path, std::ios::binary);
  require(in.is_open(), path, "cannot open the file", "check that the file exists and is readable");
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  require(!in.bad(), path, "read error", "check the file");
  const bool glb = bytes.size() >= 4 && bytes.compare(0, 4, "glTF") == 0;
  require(glb || extension(path) != ".glb", path + ": GLB header", "missing the 'glTF' magic bytes",
          "give a binary glTF 2.0 file (or rename a JSON glTF file to .gltf)");
  require(bytes.size() <= std::numeric_limits<unsigned int>::max(), path, "is larger than 4 GiB",
          "give a smaller file");
  // tinygltf reports a truncated GLB only as "Invalid glTF binary": the header's length says more.
  std::uint32_t declared = 0;
  for (std::size_t b = 0; glb && bytes.size() >= 12 && b < 4; ++b)
    declared |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[8 + b])) << (8 * b);
  require(declared <= bytes.size(), path + ": GLB header",
          "declares " + std::to_string(declared) + " bytes but the file has " + std::to_string(bytes.size()) +
              " (truncated)",
          "the file is incomplete; copy or export it again");
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(skip_image, nullptr);
  tinygltf::Model model;
  std::string err;
  std::string warn;
  const std::string dir = fs::path(path).parent_path().string();
  const auto size = static_cast<unsigned int>(bytes.size());
  const bool ok =
      glb ? loader.LoadBinaryFromMemory(&model, &err, &warn,
                                        reinterpret_cast<const unsigned char*>(bytes.data()), size, dir)
          : loader.LoadASCIIFromString(&model, &err, &warn, bytes.data(), size, dir);
  require(ok, path + ": glTF", "tinygltf cannot read it: " + one_line(err.empty() ? warn : err),
          "the file is truncated or malformed (invalid JSON, a missing buffer); export it again");
  const std::string& version = model.asset.version;
  require(version.rfind("2", 0) == 0, path + ": asset.version", "is not \"2.x\"", "export as glTF 2.0");
  if (warnings != nullptr && !warn.empty()) warnings->push_back("tinygltf: " + one_line(warn));
  if (budget != nullptr) {
    // The input: the file, and for a .gltf the buffers it references (files or data URIs, decoded).
    budget->add_input(bytes.size());
    for (std::size_t b = 0; !glb && b < model.buffers.size(); ++b)
      budget->add_input(model.buffers[b].data.size());
  }
  return model;
}

namespace {

/// One component at `p` of glTF component type `type` as a double (normalized integers mapped to
/// [0, 1] / [-1, 1] when `norm`).
double decode_component(const unsigned char* p, int type, bool norm) {
  auto le = [&](int bytes) {
    std::uint32_t u = 0;
    for (int b = 0; b < bytes; ++b) u |= static_cast<std::uint32_t>(p[b]) << (8 * b);
    return u;
  };
  switch (type) {
    case kByte: {
      const auto v = static_cast<std::int8_t>(p[0]);
      return norm ? std::max(v / 127.0, -1.0) : v;
    }
    case kUnsignedByte:
      return norm ? p[0] / 255.0 : p[0];
    case kShort: {
      const auto v = static_cast<std::int16_t>(le(2));
      return norm ? std::max(v / 32767.0, -1.0) : v;
    }
    case kUnsignedShort:
      return norm ? le(2) / 65535.0 : le(2);
    case kUnsignedInt:
      return le(4);
    default: {
      const std::uint32_t u = le(4);
      float f;
      std::memcpy(&f, &u, 4);
      return f;
    }
  }
}

/// Where `n` elements of `c` components of `type` lie in buffer view `view` at `offset`, checked
/// against the view and the view against its buffer before anything is allocated (a file can
/// declare any count: found by fuzzing, docs/fuzzing.md). Errors name `item`.
struct ViewSpan {
  const unsigned char* begin{nullptr};
  std::size_t stride{0};
  int component_bytes{0};
};

ViewSpan locate(const tinygltf::Model& m, int view, std::size_t offset, std::size_t n, int type, int c,
                const std::string& item) {
  require(view >= 0 && static_cast<std::size_t>(view) < m.bufferViews.size(), item,
          "buffer view " + std::to_string(view) + " does not exist", "fix the file");
  const tinygltf::BufferView& v = m.bufferViews[static_cast<std::size_t>(view)];
  require(v.buffer >= 0 && static_cast<std::size_t>(v.buffer) < m.buffers.size(), item,
          "buffer " + std::to_string(v.buffer) + " does not exist", "fix the file");
  const int cs = tinygltf::GetComponentSizeInBytes(static_cast<std::uint32_t>(type));
  require(cs > 0, item, "has an unknown component type", "fix the file");
  const auto elem = static_cast<std::size_t>(cs * c);
  const std::size_t stride = v.byteStride > 0 ? v.byteStride : elem;
  const std::vector<unsigned char>& data = m.buffers[static_cast<std::size_t>(v.buffer)].data;
  require(v.byteLength <= data.size() && v.byteOffset <= data.size() - v.byteLength, item,
          "buffer view " + std::to_string(view) + " (" + std::to_string(v.byteLength) + " bytes at " +
              std::to_string(v.byteOffset) + ") runs past the end of its " + std::to_string(data.size()) +
              "-byte buffer",
          "the file is truncated or corrupt");
  // offset + (n - 1) * stride + elem <= byteLength, without overflow.
  const bool fits = n == 0 || (offset <= v.byteLength && elem <= v.byteLength - offset &&
                               (n - 1) <= (v.byteLength - offset - elem) / stride);
  require(fits, item,
          "declares " + std::to_string(n) + " elements of " + std::to_string(elem) +
              " bytes but its buffer view " + std::to_string(view) + " holds " +
              std::to_string(v.byteLength) + " bytes",
          "the file is truncated or corrupt");
  if (n == 0) return {nullptr, stride, cs};  // nothing is read: no pointer past the buffer is formed
  return {data.data() + v.byteOffset + offset, stride, cs};
}

/// Decodes `n` elements of `c` components from a checked span into `put(element, component, value)`.
template <class Put>
void decode(const ViewSpan& s, std::size_t n, int type, int c, bool norm, Put put) {
  for (std::size_t e = 0; e < n; ++e)
    for (int k = 0; k < c; ++k)
      put(e, k,
          decode_component(s.begin + e * s.stride + static_cast<std::size_t>(k * s.component_bytes), type,
                           norm));
}

/// Bytes an accessor without a buffer view (zeros, then its sparse values) may declare: as many as
/// the file's buffers hold together, or `kMinUnbackedBytes` when they hold less.
constexpr std::uint64_t kMinUnbackedBytes = 1 << 20;

std::uint64_t buffer_bytes(const tinygltf::Model& m) {
  std::uint64_t total = 0;
  for (const tinygltf::Buffer& b : m.buffers) total += b.data.size();
  return total;
}

}  // namespace

std::vector<double> read_accessor(const tinygltf::Model& m, int index, int* components,
                                  const std::string& what, LoadBudget* budget) {
  const std::string item = what + " (accessor " + std::to_string(index) + ")";
  require(index >= 0 && static_cast<std::size_t>(index) < m.accessors.size(), item, "does not exist",
          "fix the file");
  const tinygltf::Accessor& a = m.accessors[static_cast<std::size_t>(index)];
  const int comps = tinygltf::GetNumComponentsInType(static_cast<std::uint32_t>(a.type));
  const int cs = tinygltf::GetComponentSizeInBytes(static_cast<std::uint32_t>(a.componentType));
  require(comps > 0 && cs > 0, item, "has an unknown componentType or type", "fix the file");
  const auto c = static_cast<std::size_t>(comps);
  *components = comps;
  // Every declared size is checked against what backs it before the first allocation.
  ViewSpan dense;
  if (a.bufferView >= 0) {
    dense = locate(m, a.bufferView, a.byteOffset, a.count, a.componentType, comps, item);
  } else {
    const std::uint64_t declared = static_cast<std::uint64_t>(a.count) * c * static_cast<std::uint64_t>(cs);
    const std::uint64_t bound = std::max(buffer_bytes(m), kMinUnbackedBytes);
    require(a.count <= bound && declared <= bound, item,
            "has no buffer view but declares " + std::to_string(a.count) + " elements (" +
                std::to_string(declared) + " bytes), more than the file's buffers hold (" +
                std::to_string(buffer_bytes(m)) + " bytes)",
            "the file is corrupt: fix the accessor's count");
  }
  const auto n = static_cast<std::size_t>(a.sparse.isSparse ? std::max(a.sparse.count, 0) : 0);
  ViewSpan sparse_idx;
  ViewSpan sparse_val;
  if (a.sparse.isSparse) {
    const int itype = a.sparse.indices.componentType;
    require(itype == kUnsignedByte || itype == kUnsignedShort || itype == kUnsignedInt, item,
            "sparse index type is invalid", "fix the file");
    require(n <= a.count, item,
            "sparse count " + std::to_string(n) + " is larger than the accessor's count " +
                std::to_string(a.count),
            "fix the file");
    sparse_idx = locate(m, a.sparse.indices.bufferView, static_cast<std::size_t>(a.sparse.indices.byteOffset),
                        n, itype, 1, item + " sparse indices");
    sparse_val = locate(m, a.sparse.values.bufferView, static_cast<std::size_t>(a.sparse.values.byteOffset),
                        n, a.componentType, comps, item + " sparse values");
  }
  if (budget != nullptr)
    budget->charge(a.count, c * sizeof(double) + (n > 0 ? sizeof(std::size_t) : 0), item);
  std::vector<double> out(a.count * c, 0.0);
  if (a.bufferView >= 0)
    decode(dense, a.count, a.componentType, comps, a.normalized,
           [&](std::size_t e, int k, double x) { out[e * c + static_cast<std::size_t>(k)] = x; });
  if (!a.sparse.isSparse) return out;
  std::vector<std::size_t> idx(n);
  decode(sparse_idx, n, a.sparse.indices.componentType, 1, false,
         [&](std::size_t e, int, double x) { idx[e] = static_cast<std::size_t>(x); });
  for (std::size_t i : idx) require(i < a.count, item, "sparse index out of range", "fix the file");
  decode(sparse_val, n, a.componentType, comps, a.normalized,
         [&](std::size_t e, int k, double x) { out[idx[e] * c + static_cast<std::size_t>(k)] = x; });
  return out;
}

}  // namespace isokit::skinning::gltf
