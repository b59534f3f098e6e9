// SPDX-License-Identifier: MIT
#include "isokit/operators/io.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "isokit/core/atomic_file.h"
#include "isokit/core/error.h"

namespace isokit::operators {
namespace {

std::string npy_header(int d0, int d1, int d2) {
  std::string dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (" + std::to_string(d0) + ", " +
                     std::to_string(d1) + ", " + std::to_string(d2) + "), }";
  // magic (6) + version (2) + header length (2) + dict, padded with spaces to 64 bytes, '\n' last.
  std::size_t total = 10 + dict.size() + 1;
  const std::size_t pad = (64 - total % 64) % 64;
  dict.append(pad, ' ');
  dict.push_back('\n');
  std::string h("\x93NUMPY\x01\x00", 8);
  const std::uint16_t len = static_cast<std::uint16_t>(dict.size());
  h.push_back(static_cast<char>(len & 0xff));
  h.push_back(static_cast<char>(len >> 8));
  return h + dict;
}

bool little_endian() {
  const std::uint16_t x = 1;
  unsigned char c;
  std::memcpy(&c, &x, 1);
  return c == 1;
}

std::string strip(std::string s) {
  while (!s.empty() && (s.back() == ' ' || s.back() == '\n')) s.pop_back();
  return s;
}

}  // namespace

namespace {

/// The whole stream: one read of the file's size when it can be measured (a 128³ grid is 8 MiB;
/// through a stringstream it was copied three times), else through a stringstream.
std::string read_all(std::ifstream& in) {
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(0, std::ios::beg);
  if (size >= 0 && in) {
    std::string b(static_cast<std::size_t>(size), '\0');
    in.read(b.data(), size);
    if (in.gcount() == size) return b;
    in.clear();
    in.seekg(0, std::ios::beg);
  }
  in.clear();
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

std::string spec_path_for(const std::string& npy_path) {
  const std::size_t slash = npy_path.find_last_of('/');
  const std::size_t dot = npy_path.find_last_of('.');
  if (dot != std::string::npos && (slash == std::string::npos || dot > slash))
    return npy_path.substr(0, dot) + ".json";
  return npy_path + ".json";
}

static std::string npy_bytes(const float* data, int d0, int d1, int d2) {
  std::string out = npy_header(d0, d1, d2);
  const std::size_t n = static_cast<std::size_t>(d0) * d1 * d2;
  const std::size_t at = out.size();
  out.resize(at + n * 4);
  require(little_endian(), "npy writer", "big-endian hosts are not supported", "use a little-endian machine");
  std::memcpy(&out[at], data, n * 4);
  return out;
}

void write_npy_f32(const std::string& path, const float* data, int d0, int d1, int d2) {
  const std::string bytes = npy_bytes(data, d0, d1, d2);
  write_bytes_atomically(path, bytes.data(), bytes.size());
}

std::vector<float> read_npy_f32(const std::string& path, int* d0, int* d1, int* d2) {
  std::ifstream in(path, std::ios::binary);
  require(bool(in), path, "cannot be opened", "check the path (generate it with isokit-opdesigner generate)");
  const std::string b = read_all(in);
  require(b.size() >= 10 && b.compare(0, 6, "\x93NUMPY") == 0, path + ": magic", "not a NumPy .npy file",
          "pass a file written by numpy.save or isokit-opdesigner");
  const int major = static_cast<unsigned char>(b[6]);
  std::size_t hlen, hstart;
  if (major == 1) {
    hlen =
        static_cast<unsigned char>(b[8]) | (static_cast<std::size_t>(static_cast<unsigned char>(b[9])) << 8);
    hstart = 10;
  } else {
    require(major == 2 || major == 3, path + ": version", "unsupported .npy version " + std::to_string(major),
            "save with numpy format version 1, 2 or 3");
    require(b.size() >= 12, path + ": header", "truncated", "regenerate the file");
    hlen = 0;
    for (int i = 0; i < 4; ++i)
      hlen |= static_cast<std::size_t>(static_cast<unsigned char>(b[8 + i])) << (8 * i);
    hstart = 12;
  }
  require(b.size() >= hstart + hlen, path + ": header", "truncated", "regenerate the file");
  const std::string header = b.substr(hstart, hlen);
  auto value_of = [&](const std::string& key) {
    const std::size_t k = header.find("'" + key + "'");
    require(k != std::string::npos, path + ": header." + key, "missing", "regenerate the file");
    const std::size_t colon = header.find(':', k);
    return colon == std::string::npos ? std::string() : header.substr(colon + 1);
  };
  const std::string descr = value_of("descr");
  require(descr.find("'<f4'") != std::string::npos && descr.find("'<f4'") < descr.find(','), path + ": dtype",
          "must be little-endian float32 ('<f4')", "save with numpy.asarray(a, dtype='<f4')");
  const std::string fortran = value_of("fortran_order");
  const std::size_t f0 = fortran.find_first_not_of(' ');
  require(f0 != std::string::npos && fortran.compare(f0, 5, "False") == 0, path + ": fortran_order",
          "must be False (C order)", "save a C-contiguous array");
  const std::string shape_s = value_of("shape");
  const std::size_t open = shape_s.find('('), close = shape_s.find(')');
  require(open != std::string::npos && close != std::string::npos, path + ": shape", "unreadable",
          "regenerate the file");
  std::vector<long long> dims;
  std::stringstream sh(shape_s.substr(open + 1, close - open - 1));
  std::string item;
  while (std::getline(sh, item, ',')) {
    item = strip(item);
    const std::size_t first = item.find_first_not_of(' ');
    if (first == std::string::npos) continue;
    try {
      dims.push_back(std::stoll(item.substr(first)));
    } catch (const std::exception&) {
      throw InputError(path + ": shape: unreadable dimension '" + item + "'; regenerate the file");
    }
  }
  require(dims.size() == 3, path + ": shape",
          "must have 3 dimensions [nd, nf, nf] (got " + std::to_string(dims.size()) + ")",
          "save the operator grid as a 3D array");
  for (long long v : dims)
    require(v >= 1 && v <= 4096, path + ": shape", "dimension out of range (got " + std::to_string(v) + ")",
            "regenerate the file");
  const std::size_t count = static_cast<std::size_t>(dims[0] * dims[1] * dims[2]);
  const std::size_t data_at = hstart + hlen;
  require(b.size() - data_at == count * 4, path + ": data",
          "has " + std::to_string(b.size() - data_at) + " bytes, the shape needs " +
              std::to_string(count * 4) + " (truncated?)",
          "regenerate the file");
  require(little_endian(), "npy reader", "big-endian hosts are not supported", "use a little-endian machine");
  std::vector<float> out(count);
  std::memcpy(out.data(), b.data() + data_at, count * 4);
  *d0 = static_cast<int>(dims[0]);
  *d1 = static_cast<int>(dims[1]);
  *d2 = static_cast<int>(dims[2]);
  return out;
}

void save_operator(const std::string& npy_path, const OperatorSpec& spec, const GridOperator& grid) {
  require(grid.nd() == spec.slices && grid.nf() == spec.resolution, "save_operator",
          "grid shape [" + std::to_string(grid.nd()) + ", " + std::to_string(grid.nf()) +
              "] does not match the spec's slices/resolution",
          "save the grid generated from this spec");
  nlohmann::json j = nlohmann::json::parse(spec_to_json(spec));
  std::string base =
      npy_path.substr(npy_path.find_last_of('/') == std::string::npos ? 0 : npy_path.find_last_of('/') + 1);
  j["grid"] = {{"npy", base},
               {"dtype", "float32"},
               {"shape", {grid.nd(), grid.nf(), grid.nf()}},
               {"layout", "g[k, i1, i2] = g(f1 = i1/(nf-1), f2 = i2/(nf-1); d = k/(nd-1))"}};
  const std::string json_text = j.dump(2) + "\n";
  // Each file goes to a temporary name first; the .npy is written and renamed last, only after the
  // spec succeeded, so a failure never leaves a new .npy beside an old spec.
  const std::string json_path = spec_path_for(npy_path);
  write_text_file_atomically(json_path, json_text);
  write_npy_f32(npy_path, grid.data().data(), grid.nd(), grid.nf(), grid.nf());
}

StoredOperator load_operator(const std::string& npy_path) {
  const std::string json_path = spec_path_for(npy_path);
  std::ifstream in(json_path, std::ios::binary);
  require(bool(in), json_path, "the spec beside " + npy_path + " cannot be opened",
          "keep X.json next to X.npy (isokit-opdesigner generate writes both)");
  std::stringstream ss;
  ss << in.rdbuf();
  StoredOperator s;
  s.spec = spec_from_json(ss.str(), json_path);
  int d0 = 0, d1 = 0, d2 = 0;
  std::vector<float> data = read_npy_f32(npy_path, &d0, &d1, &d2);
  require(d0 == s.spec.slices && d1 == s.spec.resolution && d2 == s.spec.resolution, npy_path + ": shape",
          "[" + std::to_string(d0) + ", " + std::to_string(d1) + ", " + std::to_string(d2) +
              "] does not match " + json_path + " (slices " + std::to_string(s.spec.slices) +
              ", resolution " + std::to_string(s.spec.resolution) + ")",
          "regenerate both files together");
  s.grid = GridOperator(d0, d1, std::move(data));
  return s;
}

}  // namespace isokit::operators
