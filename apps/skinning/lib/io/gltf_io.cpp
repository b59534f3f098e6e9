// SPDX-License-Identifier: MIT
#include "io/gltf_io.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>

#include "isokit/core/atomic_file.h"
#include "isokit/core/error.h"

namespace isokit::skinning::gltf {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr std::uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr std::uint32_t kChunkJson = 0x4E4F534A;
constexpr std::uint32_t kChunkBin = 0x004E4942;

bool little_endian_host() {
  const std::uint16_t one = 1;
  std::uint8_t first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

void put_u32(std::ostream& out, std::uint32_t v) {
  const char b[4] = {static_cast<char>(v & 0xFF), static_cast<char>((v >> 8) & 0xFF),
                     static_cast<char>((v >> 16) & 0xFF), static_cast<char>((v >> 24) & 0xFF)};
  out.write(b, 4);
}

std::uint32_t get_u32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}

std::size_t pad4(std::size_t n) {
  return (n + 3) & ~std::size_t{3};
}

std::string percent_decode(const std::string& s) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size()) {
      const std::string hex = s.substr(i + 1, 2);
      char* end = nullptr;
      const long v = std::strtol(hex.c_str(), &end, 16);
      if (end == hex.c_str() + 2) {
        out.push_back(static_cast<char>(v));
        i += 2;
        continue;
      }
    }
    out.push_back(s[i]);
  }
  return out;
}

std::vector<std::uint8_t> read_bytes(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  require(in.is_open(), what, "cannot open '" + path + "'", "check that the file exists and is readable");
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  require(!in.bad(), what, "read error on '" + path + "'", "check the file");
  return bytes;
}

}  // namespace

int component_size(int component_type) {
  switch (component_type) {
    case kByte:
    case kUnsignedByte:
      return 1;
    case kShort:
    case kUnsignedShort:
      return 2;
    case kUnsignedInt:
    case kFloat:
      return 4;
    default:
      return 0;
  }
}

int type_components(const std::string& type) {
  if (type == "SCALAR") return 1;
  if (type == "VEC2") return 2;
  if (type == "VEC3") return 3;
  if (type == "VEC4" || type == "MAT2") return 4;
  if (type == "MAT3") return 9;
  if (type == "MAT4") return 16;
  return 0;
}

std::string extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// ---------------------------------------------------------------------------------------------
// Builder

Builder::Builder() {
  doc_["asset"] = {{"version", "2.0"}, {"generator", "isokit"}};
}

int Builder::add_view(const void* data, std::size_t bytes, int target) {
  const std::size_t offset = bin_.size();
  bin_.resize(pad4(offset + bytes), 0);
  if (bytes > 0) std::memcpy(bin_.data() + offset, data, bytes);
  json view = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}};
  if (target != 0) view["target"] = target;
  json& views = doc_["bufferViews"];
  views.push_back(view);
  return static_cast<int>(views.size()) - 1;
}

int Builder::add_accessor(int view, int component_type, std::size_t count, const std::string& type,
                          bool normalized) {
  json a = {{"componentType", component_type}, {"count", count}, {"type", type}};
  if (view >= 0) a["bufferView"] = view;
  if (normalized) a["normalized"] = true;
  json& accessors = doc_["accessors"];
  accessors.push_back(a);
  return static_cast<int>(accessors.size()) - 1;
}

int Builder::add_float_view(const float* data, std::size_t n, int target) {
  if (little_endian_host()) return add_view(data, n * sizeof(float), target);
  std::vector<std::uint8_t> le(n * 4);
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t u;
    std::memcpy(&u, data + i, 4);
    for (std::size_t b = 0; b < 4; ++b) le[4 * i + b] = static_cast<std::uint8_t>(u >> (8 * b));
  }
  return add_view(le.data(), le.size(), target);
}

int Builder::add_floats(const float* data, std::size_t count, const std::string& type, bool min_max,
                        int target) {
  const int c = type_components(type);
  const int view = add_float_view(data, count * static_cast<std::size_t>(c), target);
  const int acc = add_accessor(view, kFloat, count, type);
  if (min_max && count > 0) {
    std::vector<float> lo(static_cast<std::size_t>(c), std::numeric_limits<float>::infinity());
    std::vector<float> hi(static_cast<std::size_t>(c), -std::numeric_limits<float>::infinity());
    for (std::size_t i = 0; i < count; ++i)
      for (int k = 0; k < c; ++k) {
        const float v = data[i * static_cast<std::size_t>(c) + static_cast<std::size_t>(k)];
        lo[static_cast<std::size_t>(k)] = std::min(lo[static_cast<std::size_t>(k)], v);
        hi[static_cast<std::size_t>(k)] = std::max(hi[static_cast<std::size_t>(k)], v);
      }
    doc_["accessors"][static_cast<std::size_t>(acc)]["min"] = lo;
    doc_["accessors"][static_cast<std::size_t>(acc)]["max"] = hi;
  }
  return acc;
}

namespace {
template <typename T>
std::vector<std::uint8_t> to_le_bytes(const T* data, std::size_t n) {
  std::vector<std::uint8_t> out(n * sizeof(T));
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint64_t v = static_cast<std::uint64_t>(data[i]);
    for (std::size_t b = 0; b < sizeof(T); ++b)
      out[i * sizeof(T) + b] = static_cast<std::uint8_t>(v >> (8 * b));
  }
  return out;
}
}  // namespace

int Builder::add_u8(const std::uint8_t* data, std::size_t count, const std::string& type, int target) {
  const std::size_t n = count * static_cast<std::size_t>(type_components(type));
  return add_accessor(add_view(data, n, target), kUnsignedByte, count, type);
}

int Builder::add_u16(const std::uint16_t* data, std::size_t count, const std::string& type, int target) {
  const auto bytes = to_le_bytes(data, count * static_cast<std::size_t>(type_components(type)));
  return add_accessor(add_view(bytes.data(), bytes.size(), target), kUnsignedShort, count, type);
}

int Builder::add_u32(const std::uint32_t* data, std::size_t count, const std::string& type, int target) {
  const auto bytes = to_le_bytes(data, count * static_cast<std::size_t>(type_components(type)));
  return add_accessor(add_view(bytes.data(), bytes.size(), target), kUnsignedInt, count, type);
}

int Builder::add_sparse_vec3(std::size_t count, const std::vector<std::uint32_t>& indices,
                             const std::vector<float>& values) {
  const int acc = add_accessor(-1, kFloat, count, "VEC3");
  std::vector<float> lo(3, count > indices.size() ? 0.0f : std::numeric_limits<float>::infinity());
  std::vector<float> hi(3, count > indices.size() ? 0.0f : -std::numeric_limits<float>::infinity());
  for (std::size_t i = 0; i < indices.size(); ++i)
    for (std::size_t k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], values[3 * i + k]);
      hi[k] = std::max(hi[k], values[3 * i + k]);
    }
  if (count == 0) lo = hi = {0.0f, 0.0f, 0.0f};
  json& a = doc_["accessors"][static_cast<std::size_t>(acc)];
  a["min"] = lo;
  a["max"] = hi;
  if (indices.empty() && count > 0) {
    // An all-zero accessor: glTF allows one without data, but assimp 5.2 rejects it, so it
    // carries one explicit zero (sparse count must be >= 1).
    const std::uint8_t index = 0;
    const float zero[3] = {0.0f, 0.0f, 0.0f};
    const int index_view = add_view(&index, 1);
    const int values_view = add_float_view(zero, 3);
    json& z = doc_["accessors"][static_cast<std::size_t>(acc)];
    z["sparse"] = {{"count", 1},
                   {"indices", {{"bufferView", index_view}, {"componentType", kUnsignedByte}}},
                   {"values", {{"bufferView", values_view}}}};
    return acc;
  }
  if (indices.empty()) return acc;
  // Index views must not carry a target; the smallest component type that holds the largest index.
  const std::uint32_t last = indices.back();
  int index_view = 0;
  int index_type = kUnsignedInt;
  if (last <= 0xFF) {
    std::vector<std::uint8_t> v(indices.begin(), indices.end());
    index_view = add_view(v.data(), v.size());
    index_type = kUnsignedByte;
  } else if (last <= 0xFFFF) {
    std::vector<std::uint16_t> v(indices.begin(), indices.end());
    const auto bytes = to_le_bytes(v.data(), v.size());
    index_view = add_view(bytes.data(), bytes.size());
    index_type = kUnsignedShort;
  } else {
    const auto bytes = to_le_bytes(indices.data(), indices.size());
    index_view = add_view(bytes.data(), bytes.size());
  }
  const int values_view = add_float_view(values.data(), values.size());
  json& a2 = doc_["accessors"][static_cast<std::size_t>(acc)];
  a2["sparse"] = {{"count", indices.size()},
                  {"indices", {{"bufferView", index_view}, {"componentType", index_type}}},
                  {"values", {{"bufferView", values_view}}}};
  return acc;
}

void Builder::write(const std::string& path, bool binary) {
  if (!bin_.empty()) {
    json buffer = {{"byteLength", bin_.size()}};
    if (!binary)
      buffer["uri"] = "data:application/octet-stream;base64," + base64_encode(bin_.data(), bin_.size());
    doc_["buffers"] = json::array({buffer});
  }
  std::string text = doc_.dump();
  if (!binary) {
    write_stream_atomically(
        path, [&](std::ostream& out) { out.write(text.data(), static_cast<std::streamsize>(text.size())); });
    return;
  }
  text.resize(pad4(text.size()), ' ');
  const std::uint64_t total = 12 + 8 + static_cast<std::uint64_t>(text.size()) +
                              (bin_.empty() ? 0 : 8 + static_cast<std::uint64_t>(bin_.size()));
  require(total <= std::numeric_limits<std::uint32_t>::max(), path,
          "the GLB would be " + std::to_string(total) + " bytes, over the format's 4 GiB limit",
          "write fewer frames or vertices");
  write_stream_atomically(path, [&](std::ostream& out) {
    put_u32(out, kGlbMagic);
    put_u32(out, 2);
    put_u32(out, static_cast<std::uint32_t>(total));
    put_u32(out, static_cast<std::uint32_t>(text.size()));
    put_u32(out, kChunkJson);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    if (!bin_.empty()) {
      put_u32(out, static_cast<std::uint32_t>(bin_.size()));
      put_u32(out, kChunkBin);
      out.write(reinterpret_cast<const char*>(bin_.data()), static_cast<std::streamsize>(bin_.size()));
    }
  });
}

// ---------------------------------------------------------------------------------------------
// Reader

namespace {

/// The JSON text and the binary chunk of a GLB container.
struct GlbChunks {
  std::string text;
  const std::uint8_t* bin = nullptr;
  std::size_t bin_size = 0;
};

/// Splits a GLB file (`bytes` starts with the magic) into its chunks, checking the header.
GlbChunks split_glb(const std::vector<std::uint8_t>& bytes, const std::string& path) {
  GlbChunks chunks;
  require(bytes.size() >= 20, path + ": GLB header",
          "file too short (" + std::to_string(bytes.size()) + " bytes)",
          "the file is truncated; export it again");
  const std::uint32_t version = get_u32(bytes.data() + 4);
  const std::uint32_t length = get_u32(bytes.data() + 8);
  require(version == 2, path + ": GLB header", "container version " + std::to_string(version) + " is not 2",
          "export as glTF 2.0");
  require(length <= bytes.size(), path + ": GLB header",
          "declares " + std::to_string(length) + " bytes but the file has " + std::to_string(bytes.size()) +
              " (truncated)",
          "the file is incomplete; copy or export it again");
  std::size_t at = 12;
  bool first = true;
  while (at + 8 <= length) {
    const std::uint32_t chunk_len = get_u32(bytes.data() + at);
    const std::uint32_t chunk_type = get_u32(bytes.data() + at + 4);
    require(at + 8 + static_cast<std::size_t>(chunk_len) <= length,
            path + ": GLB chunk at byte " + std::to_string(at), "runs past the end of the file",
            "the file is truncated or corrupt; export it again");
    const std::uint8_t* data = bytes.data() + at + 8;
    if (first) {
      require(chunk_type == kChunkJson, path + ": GLB", "first chunk is not JSON", "export a valid GLB");
      chunks.text.assign(reinterpret_cast<const char*>(data), chunk_len);
    } else if (chunk_type == kChunkBin && chunks.bin == nullptr) {
      chunks.bin = data;
      chunks.bin_size = chunk_len;
    }
    first = false;
    at += 8 + pad4(chunk_len);
  }
  require(!first, path + ": GLB", "has no JSON chunk", "export a valid GLB");
  return chunks;
}

/// Parses the glTF JSON and checks that it is a glTF 2.x object.
json parse_gltf_json(const std::string& text, const std::string& path) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {
    throw InputError(path + ": glTF JSON: " + e.what() + "; fix the file or export it again");
  }
  require(j.is_object(), path + ": glTF JSON", "top level is not an object", "give a glTF 2.0 file");
  const json* asset = j.contains("asset") ? &j["asset"] : nullptr;
  const bool v2 = asset != nullptr && asset->is_object() && asset->contains("version") &&
                  (*asset)["version"].is_string() &&
                  (*asset)["version"].get<std::string>().rfind("2", 0) == 0;
  require(v2, path + ": asset.version", "is not \"2.x\"", "export as glTF 2.0");
  return j;
}

/// The bytes of `buffers[i]`: the GLB binary chunk (no uri), a base64 data URI or a file beside
/// `path`; at least its byteLength.
std::vector<std::uint8_t> read_buffer(const json& b, std::size_t i, const std::string& path, bool glb,
                                      const GlbChunks& chunks) {
  const std::string what = path + ": buffers[" + std::to_string(i) + "]";
  require(b.is_object() && b.contains("byteLength") && b["byteLength"].is_number_unsigned(), what,
          "has no byteLength", "fix the file");
  const std::size_t length = b["byteLength"].get<std::size_t>();
  std::vector<std::uint8_t> data;
  if (!b.contains("uri")) {
    require(glb && i == 0 && chunks.bin != nullptr, what, "has no uri and there is no GLB binary chunk",
            "fix the file");
    data.assign(chunks.bin, chunks.bin + chunks.bin_size);
  } else {
    require(b["uri"].is_string(), what, "uri is not a string", "fix the file");
    const std::string uri = b["uri"].get<std::string>();
    if (uri.rfind("data:", 0) == 0) {
      const std::size_t comma = uri.find(',');
      require(comma != std::string::npos && uri.substr(0, comma).find(";base64") != std::string::npos, what,
              "data URI is not base64", "fix the file");
      require(base64_decode(uri.substr(comma + 1), data), what, "invalid base64 data", "fix the file");
    } else {
      const fs::path file = fs::path(path).parent_path() / percent_decode(uri);
      data = read_bytes(file.string(), what);
    }
  }
  require(
      data.size() >= length, what,
      "holds " + std::to_string(data.size()) + " bytes, fewer than its byteLength " + std::to_string(length),
      "the buffer is truncated; export the file again");
  return data;
}

/// One component at `p` of glTF component type `type` as a double (normalized integers mapped to
/// [0, 1] / [-1, 1] when `norm`).
double decode_component(const std::uint8_t* p, int type, bool norm) {
  switch (type) {
    case kByte: {
      const auto v = static_cast<std::int8_t>(p[0]);
      return norm ? std::max(v / 127.0, -1.0) : v;
    }
    case kUnsignedByte:
      return norm ? p[0] / 255.0 : p[0];
    case kShort: {
      const auto v = static_cast<std::int16_t>(p[0] | (p[1] << 8));
      return norm ? std::max(v / 32767.0, -1.0) : v;
    }
    case kUnsignedShort: {
      const unsigned v = static_cast<unsigned>(p[0] | (p[1] << 8));
      return norm ? v / 65535.0 : v;
    }
    case kUnsignedInt:
      return get_u32(p);
    default: {
      const std::uint32_t u = get_u32(p);
      float f;
      std::memcpy(&f, &u, 4);
      return f;
    }
  }
}

/// Reads the buffer views of one accessor; errors name `item`.
struct AccessorReader {
  const Document& doc;
  const std::string& item;
  bool normalized;

  /// Reads `n` elements of `c` components from a view into `put(element, component, value)`.
  void read_view(int view_index, std::size_t byte_offset, std::size_t n, int type, int c,
                 const std::string& sub, const std::function<void(std::size_t, int, double)>& put) const {
    const json& j = doc.json;
    require(j.contains("bufferViews") && view_index >= 0 &&
                static_cast<std::size_t>(view_index) < j["bufferViews"].size(),
            item + sub, "buffer view " + std::to_string(view_index) + " does not exist", "fix the file");
    const json& v = j["bufferViews"][static_cast<std::size_t>(view_index)];
    const int buffer = v.value("buffer", -1);
    require(buffer >= 0 && static_cast<std::size_t>(buffer) < doc.buffers.size(), item + sub,
            "buffer " + std::to_string(buffer) + " does not exist", "fix the file");
    const std::size_t elem = static_cast<std::size_t>(component_size(type) * c);
    const std::size_t stride =
        v.value("byteStride", std::size_t{0}) > 0 ? v["byteStride"].get<std::size_t>() : elem;
    const std::size_t begin = v.value("byteOffset", std::size_t{0}) + byte_offset;
    const std::size_t view_len = v.value("byteLength", std::size_t{0});
    const std::vector<std::uint8_t>& data = doc.buffers[static_cast<std::size_t>(buffer)];
    if (n == 0) return;
    const std::size_t need = byte_offset + (n - 1) * stride + elem;
    require(need <= view_len && v.value("byteOffset", std::size_t{0}) + view_len <= data.size(), item + sub,
            "data runs past the end of its buffer view or buffer", "the file is truncated or corrupt");
    const int cs = component_size(type);
    for (std::size_t e = 0; e < n; ++e)
      for (int k = 0; k < c; ++k)
        put(e, k,
            decode_component(data.data() + begin + e * stride + static_cast<std::size_t>(k * cs), type,
                             normalized));
  }

  /// Applies the accessor's sparse substitution `s` to `out` (`count` elements of `comps`).
  void read_sparse(const json& s, std::size_t count, int ctype, int comps, std::vector<double>& out) const {
    const std::size_t n = s.value("count", std::size_t{0});
    std::vector<std::size_t> idx(n);
    const json& si = s["indices"];
    const int itype = si.value("componentType", kUnsignedInt);
    require(itype == kUnsignedByte || itype == kUnsignedShort || itype == kUnsignedInt, item,
            "sparse index type is invalid", "fix the file");
    read_view(si.value("bufferView", -1), si.value("byteOffset", std::size_t{0}), n, itype, 1,
              " sparse indices", [&](std::size_t e, int, double x) { idx[e] = static_cast<std::size_t>(x); });
    for (std::size_t i : idx) require(i < count, item, "sparse index out of range", "fix the file");
    const json& sv = s["values"];
    read_view(sv.value("bufferView", -1), sv.value("byteOffset", std::size_t{0}), n, ctype, comps,
              " sparse values", [&](std::size_t e, int k, double x) {
                out[idx[e] * static_cast<std::size_t>(comps) + static_cast<std::size_t>(k)] = x;
              });
  }
};

}  // namespace

Document read_document(const std::string& path) {
  const std::vector<std::uint8_t> bytes = read_bytes(path, path);
  const bool glb = bytes.size() >= 4 && get_u32(bytes.data()) == kGlbMagic;
  require(glb || extension(path) != ".glb", path + ": GLB header", "missing the 'glTF' magic bytes",
          "give a binary glTF 2.0 file (or rename a JSON glTF file to .gltf)");
  Document doc;
  GlbChunks chunks;
  if (glb)
    chunks = split_glb(bytes, path);
  else
    chunks.text.assign(bytes.begin(), bytes.end());
  doc.json = parse_gltf_json(chunks.text, path);
  if (doc.json.contains("buffers")) {
    const json& buffers = doc.json["buffers"];
    require(buffers.is_array(), path + ": buffers", "is not an array", "fix the file");
    for (std::size_t i = 0; i < buffers.size(); ++i)
      doc.buffers.push_back(read_buffer(buffers[i], i, path, glb, chunks));
  }
  return doc;
}

std::vector<double> read_accessor(const Document& doc, int index, int* components, const std::string& what) {
  const json& j = doc.json;
  const std::string item = what + " (accessor " + std::to_string(index) + ")";
  require(j.contains("accessors") && index >= 0 && static_cast<std::size_t>(index) < j["accessors"].size(),
          item, "does not exist", "fix the file");
  const json& a = j["accessors"][static_cast<std::size_t>(index)];
  const int ctype = a.value("componentType", 0);
  const int csize = component_size(ctype);
  const int comps = type_components(a.value("type", std::string()));
  require(csize > 0 && comps > 0 && a.contains("count"), item, "has an unknown componentType or type",
          "fix the file");
  const std::size_t count = a["count"].get<std::size_t>();
  const AccessorReader reader{doc, item, a.value("normalized", false)};
  *components = comps;
  std::vector<double> out(count * static_cast<std::size_t>(comps), 0.0);
  if (a.contains("bufferView"))
    reader.read_view(a["bufferView"].get<int>(), a.value("byteOffset", std::size_t{0}), count, ctype, comps,
                     "", [&](std::size_t e, int k, double x) {
                       out[e * static_cast<std::size_t>(comps) + static_cast<std::size_t>(k)] = x;
                     });
  if (a.contains("sparse")) reader.read_sparse(a["sparse"], count, ctype, comps, out);
  return out;
}

// ---------------------------------------------------------------------------------------------
// Base64

namespace {
constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
}

std::string base64_encode(const std::uint8_t* data, std::size_t size) {
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < size; i += 3) {
    const std::uint32_t v = (static_cast<std::uint32_t>(data[i]) << 16) |
                            (static_cast<std::uint32_t>(data[i + 1]) << 8) | data[i + 2];
    out.push_back(kAlphabet[(v >> 18) & 63]);
    out.push_back(kAlphabet[(v >> 12) & 63]);
    out.push_back(kAlphabet[(v >> 6) & 63]);
    out.push_back(kAlphabet[v & 63]);
  }
  if (i < size) {
    std::uint32_t v = static_cast<std::uint32_t>(data[i]) << 16;
    if (i + 1 < size) v |= static_cast<std::uint32_t>(data[i + 1]) << 8;
    out.push_back(kAlphabet[(v >> 18) & 63]);
    out.push_back(kAlphabet[(v >> 12) & 63]);
    out.push_back(i + 1 < size ? kAlphabet[(v >> 6) & 63] : '=');
    out.push_back('=');
  }
  return out;
}

bool base64_decode(const std::string& text, std::vector<std::uint8_t>& out) {
  int table[256];
  std::fill(std::begin(table), std::end(table), -1);
  for (int k = 0; k < 64; ++k) table[static_cast<unsigned char>(kAlphabet[k])] = k;
  out.clear();
  out.reserve(text.size() / 4 * 3);
  std::uint32_t acc = 0;
  int bits = 0;
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '=') break;
    if (c == '\n' || c == '\r' || c == ' ') continue;
    const int v = table[c];
    if (v < 0) return false;
    acc = (acc << 6) | static_cast<std::uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<std::uint8_t>((acc >> bits) & 0xFF));
    }
  }
  return true;
}

}  // namespace isokit::skinning::gltf
