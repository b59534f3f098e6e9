// SPDX-License-Identifier: MIT
// Rig I/O: save_rig -> load_rig round trips (structure, weights with 6 influences, LBS over
// clips), welding, the baked morph-target GLB (JSON structure, min/max, alignment, deltas; also
// re-read by assimp), PLY, and the error messages. Fixtures are built in code; the sample rigs
// are tried only when ISOKIT_SAMPLE_RIGS names their folder.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>

#include <sys/wait.h>

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Importer.hpp>
#include <nlohmann/json.hpp>

#include "isokit/core/error.h"
#include "isokit/core/math.h"
#include "isokit/skinning/rig_io.h"

using namespace isokit::skinning;
namespace fs = std::filesystem;
using nlohmann::json;
namespace track = isokit::track;

namespace {

struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& name) {
    std::random_device rd;
    path = fs::temp_directory_path() / ("isokit_rig_io_" + name + "_" + std::to_string(rd()));
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string file(const std::string& name) const { return (path / name).string(); }
  std::size_t entries() const {
    return static_cast<std::size_t>(std::distance(fs::directory_iterator(path), fs::directory_iterator()));
  }
};

Affine trs(const Eigen::Vector3d& t, const Eigen::AngleAxisd& r,
           const Eigen::Vector3d& s = Eigen::Vector3d::Ones()) {
  Affine a = Affine::Identity();
  a.translate(t);
  a.rotate(r);
  a.scale(s);
  return a;
}

// Linear blend skinning, written out here (the library's LBS belongs to another module).
track::Positions lbs(const Rig& rig, const std::vector<Affine>& local) {
  const std::vector<Affine> m = skinning_matrices(rig, local);
  track::Positions out(rig.rest.rows(), 3);
  for (Eigen::Index v = 0; v < rig.rest.rows(); ++v) {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    const Eigen::Vector3d r = rig.rest.row(v).transpose().cast<double>();
    for (int k = rig.weights.offsets[v]; k < rig.weights.offsets[v + 1]; ++k)
      p += rig.weights.weights[k] * (m[rig.weights.joints[k]] * r);
    out.row(v) = p.transpose().cast<float>();
  }
  return out;
}

double diagonal(const track::Positions& p) {
  return (p.colwise().maxCoeff() - p.colwise().minCoeff()).norm();
}

constexpr int kRings = 12;

// A square bar along x (12 rings of 4 corners), two primitives (rings 0-5 and 5-11, each with its
// own vertex copies), split normals (each side face has its own copies) and end caps; 6 joints
// (root, upper, lower, tip, helperA, helperB), 6 influences on the middle rings; clips "wave"
// (10 frames) and "idle" (3 frames).
Rig bar_rig() {
  Rig rig;
  rig.name = "bar";
  rig.joints = {
      {"root", -1, trs({0.1, 0, 0}, Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ())), Affine::Identity()},
      {"upper", 0, trs({0.2, 0, 0}, Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitZ())), Affine::Identity()},
      {"lower", 1, trs({1.0, 0, 0}, Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY())), Affine::Identity()},
      {"tip", 2, trs({1.0, 0, 0}, Eigen::AngleAxisd(-0.1, Eigen::Vector3d::UnitY())), Affine::Identity()},
      {"helperA", 1, trs({0.5, 0.1, 0}, Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX())),
       Affine::Identity()},
      {"helperB", 2, trs({0.5, -0.1, 0}, Eigen::AngleAxisd(0, Eigen::Vector3d::UnitX()), {1.2, 1.0, 0.9}),
       Affine::Identity()},
  };
  const std::vector<Affine> world = world_transforms(rig, rest_pose(rig));
  for (std::size_t j = 0; j < world.size(); ++j) rig.joints[j].inverse_bind = world[j].inverse(Eigen::Affine);

  const double cy[4] = {-0.1, 0.1, 0.1, -0.1};
  const double cz[4] = {-0.1, -0.1, 0.1, 0.1};
  rig.rest.resize(4 * kRings, 3);
  for (int r = 0; r < kRings; ++r)
    for (int c = 0; c < 4; ++c)
      rig.rest.row(4 * r + c) << static_cast<float>(0.2 * r), static_cast<float>(cy[c]),
          static_cast<float>(cz[c]);

  std::map<std::tuple<int, int, int>, int> copies;  // (primitive * 10 + face, ring, corner) -> output vertex
  std::vector<Eigen::Vector3i> out_tris;
  std::vector<Eigen::Vector3i> welded_tris;
  auto vertex = [&](int key, int r, int c) {
    const auto k = std::make_tuple(key, r, c);
    const auto it = copies.find(k);
    if (it != copies.end()) return it->second;
    const int id = static_cast<int>(rig.output.to_welded.size());
    rig.output.to_welded.push_back(4 * r + c);
    copies[k] = id;
    return id;
  };
  auto tri = [&](int key, std::array<std::pair<int, int>, 3> corners) {
    Eigen::Vector3i o;
    Eigen::Vector3i w;
    for (int k = 0; k < 3; ++k) {
      o[k] = vertex(key, corners[static_cast<std::size_t>(k)].first,
                    corners[static_cast<std::size_t>(k)].second);
      w[k] = 4 * corners[static_cast<std::size_t>(k)].first + corners[static_cast<std::size_t>(k)].second;
    }
    out_tris.push_back(o);
    welded_tris.push_back(w);
  };
  const int split = kRings / 2 - 1;
  for (int p = 0; p < 2; ++p) {
    const int r0 = p == 0 ? 0 : split;
    const int r1 = p == 0 ? split : kRings - 1;
    for (int r = r0; r < r1; ++r)
      for (int s = 0; s < 4; ++s) {
        const int a = s;
        const int b = (s + 1) % 4;
        tri(10 * p + s, {{{r, a}, {r + 1, a}, {r + 1, b}}});
        tri(10 * p + s, {{{r, a}, {r + 1, b}, {r, b}}});
      }
    const int cap = p == 0 ? 0 : kRings - 1;
    tri(10 * p + 5, {{{cap, 0}, {cap, 2}, {cap, 1}}});
    tri(10 * p + 5, {{{cap, 0}, {cap, 3}, {cap, 2}}});
    rig.output.primitive_offsets.push_back(static_cast<int>(out_tris.size()));
  }
  rig.output.triangles.resize(static_cast<Eigen::Index>(out_tris.size()), 3);
  rig.triangles.resize(static_cast<Eigen::Index>(welded_tris.size()), 3);
  for (std::size_t f = 0; f < out_tris.size(); ++f) {
    rig.output.triangles.row(static_cast<Eigen::Index>(f)) = out_tris[f].transpose();
    rig.triangles.row(static_cast<Eigen::Index>(f)) = welded_tris[f].transpose();
  }

  SkinWeights& w = rig.weights;
  w.offsets = {0};
  for (int r = 0; r < kRings; ++r)
    for (int c = 0; c < 4; ++c) {
      std::vector<std::pair<int, float>> infl;
      if (r < 4) {
        infl = {{0, 1.0f - 0.2f * r}, {1, 0.2f * r + 0.05f}};
      } else if (r < 8) {  // all six joints
        for (int j = 0; j < 6; ++j) infl.push_back({j, 0.05f + 0.1f * static_cast<float>((j + r + c) % 6)});
      } else {
        infl = {{2, 0.3f + 0.1f * (r - 8)}, {3, 0.4f}};
      }
      float sum = 0;
      for (const auto& x : infl) sum += x.second;
      for (const auto& x : infl) {
        w.joints.push_back(x.first);
        w.weights.push_back(x.second / sum);
      }
      w.offsets.push_back(static_cast<int>(w.joints.size()));
    }

  Clip wave{"wave", 30, {}, nullptr};
  for (int f = 0; f < 10; ++f) {
    std::vector<Affine> local = rest_pose(rig);
    const double t = f / 9.0;
    local[0] = local[0] * trs({0, 0.05 * t, 0}, Eigen::AngleAxisd(0.3 * t, Eigen::Vector3d::UnitY()));
    local[1] = local[1] * Affine(Eigen::AngleAxisd(0.6 * t, Eigen::Vector3d::UnitZ()));
    local[2] = local[2] * Affine(Eigen::AngleAxisd(-0.9 * t, Eigen::Vector3d(0, 1, 1).normalized()));
    local[3] = local[3] * Affine(Eigen::AngleAxisd(1.2 * t, Eigen::Vector3d::UnitX()));
    local[5] = local[5] * Affine(Eigen::Scaling(1.0 + 0.2 * t, 1.0, 1.0));
    wave.local.push_back(local);
  }
  Clip idle{"idle", 30, {}, nullptr};
  for (int f = 0; f < 3; ++f) {
    std::vector<Affine> local = rest_pose(rig);
    local[4] = local[4] * Affine(Eigen::AngleAxisd(0.2 * f, Eigen::Vector3d::UnitZ()));
    idle.local.push_back(local);
  }
  rig.clips = {wave, idle};
  validate(rig);
  return rig;
}

// Positions of the output vertices.
track::Positions output_positions(const Rig& rig, const track::Positions& welded) {
  track::Positions out(static_cast<Eigen::Index>(rig.output.to_welded.size()), 3);
  for (std::size_t i = 0; i < rig.output.to_welded.size(); ++i)
    out.row(static_cast<Eigen::Index>(i)) = welded.row(rig.output.to_welded[i]);
  return out;
}

std::map<std::string, float> weights_of(const Rig& rig, int welded_vertex) {
  std::map<std::string, float> m;
  float sum = 0;
  for (int k = rig.weights.offsets[welded_vertex]; k < rig.weights.offsets[welded_vertex + 1]; ++k)
    sum += rig.weights.weights[k];
  for (int k = rig.weights.offsets[welded_vertex]; k < rig.weights.offsets[welded_vertex + 1]; ++k)
    m[rig.joints[rig.weights.joints[k]].name] += rig.weights.weights[k] / sum;
  return m;
}

std::vector<std::uint8_t> read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<std::uint8_t>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void write_all(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::uint32_t u32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}

struct Glb {
  json doc;
  std::vector<std::uint8_t> bin;
};

// Parses a GLB and checks its container: header length, 4-byte chunk alignment, buffer size.
Glb parse_glb(const std::string& path) {
  const std::vector<std::uint8_t> bytes = read_all(path);
  REQUIRE(bytes.size() >= 20);
  CHECK(u32(bytes.data()) == 0x46546C67u);
  CHECK(u32(bytes.data() + 4) == 2u);
  CHECK(u32(bytes.data() + 8) == bytes.size());
  const std::uint32_t json_len = u32(bytes.data() + 12);
  CHECK(u32(bytes.data() + 16) == 0x4E4F534Au);
  CHECK(json_len % 4 == 0);
  Glb g;
  g.doc = json::parse(std::string(bytes.begin() + 20, bytes.begin() + 20 + json_len));
  const std::size_t at = 20 + json_len;
  if (at < bytes.size()) {
    const std::uint32_t bin_len = u32(bytes.data() + at);
    CHECK(u32(bytes.data() + at + 4) == 0x004E4942u);
    CHECK(bin_len % 4 == 0);
    CHECK(at + 8 + bin_len == bytes.size());
    g.bin.assign(bytes.begin() + static_cast<std::ptrdiff_t>(at + 8), bytes.end());
    REQUIRE(g.doc["buffers"].size() == 1);
    const std::size_t declared = g.doc["buffers"][0]["byteLength"].get<std::size_t>();
    CHECK(declared <= bin_len);
    CHECK(bin_len - declared < 4);
    for (const json& v : g.doc["bufferViews"]) {
      CHECK(v.value("byteOffset", 0) % 4 == 0);
      CHECK(v.value("byteOffset", std::size_t{0}) + v["byteLength"].get<std::size_t>() <= declared);
    }
  }
  return g;
}

float read_float(const std::vector<std::uint8_t>& bin, std::size_t at) {
  const std::uint32_t u = u32(bin.data() + at);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

// Float accessor values (dense or sparse) of a parsed GLB.
std::vector<float> float_accessor(const Glb& g, int index, int comps) {
  const json& a = g.doc["accessors"][static_cast<std::size_t>(index)];
  REQUIRE(a["componentType"].get<int>() == 5126);
  const std::size_t count = a["count"].get<std::size_t>();
  std::vector<float> out(count * static_cast<std::size_t>(comps), 0.0f);
  auto view_start = [&](int v) {
    return g.doc["bufferViews"][static_cast<std::size_t>(v)].value("byteOffset", std::size_t{0});
  };
  if (a.contains("bufferView")) {
    const std::size_t start = view_start(a["bufferView"].get<int>()) + a.value("byteOffset", std::size_t{0});
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = read_float(g.bin, start + 4 * i);
  }
  if (a.contains("sparse")) {
    const json& s = a["sparse"];
    const std::size_t n = s["count"].get<std::size_t>();
    const int itype = s["indices"]["componentType"].get<int>();
    const std::size_t istart = view_start(s["indices"]["bufferView"].get<int>());
    const std::size_t vstart = view_start(s["values"]["bufferView"].get<int>());
    for (std::size_t e = 0; e < n; ++e) {
      std::size_t idx = 0;
      if (itype == 5121) idx = g.bin[istart + e];
      if (itype == 5123)
        idx = static_cast<std::size_t>(g.bin[istart + 2 * e] | (g.bin[istart + 2 * e + 1] << 8));
      if (itype == 5125) idx = u32(g.bin.data() + istart + 4 * e);
      REQUIRE(idx < count);
      for (int k = 0; k < comps; ++k)
        out[idx * static_cast<std::size_t>(comps) + static_cast<std::size_t>(k)] = read_float(
            g.bin, vstart + 4 * (e * static_cast<std::size_t>(comps) + static_cast<std::size_t>(k)));
    }
  }
  return out;
}

void check_min_max(const Glb& g, int index) {
  const json& a = g.doc["accessors"][static_cast<std::size_t>(index)];
  REQUIRE(a.contains("min"));
  REQUIRE(a.contains("max"));
  const std::vector<float> v = float_accessor(g, index, 3);
  for (int k = 0; k < 3; ++k) {
    float lo = INFINITY;
    float hi = -INFINITY;
    for (std::size_t i = static_cast<std::size_t>(k); i < v.size(); i += 3) {
      lo = std::min(lo, v[i]);
      hi = std::max(hi, v[i]);
    }
    CHECK(a["min"][static_cast<std::size_t>(k)].get<float>() == lo);
    CHECK(a["max"][static_cast<std::size_t>(k)].get<float>() == hi);
  }
}

std::string base64(const std::vector<std::uint8_t>& d) {
  static const char* abc = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string s;
  for (std::size_t i = 0; i < d.size(); i += 3) {
    const std::uint32_t v = (static_cast<std::uint32_t>(d[i]) << 16) |
                            (i + 1 < d.size() ? static_cast<std::uint32_t>(d[i + 1]) << 8 : 0u) |
                            (i + 2 < d.size() ? d[i + 2] : 0u);
    s += abc[(v >> 18) & 63];
    s += abc[(v >> 12) & 63];
    s += i + 1 < d.size() ? abc[(v >> 6) & 63] : '=';
    s += i + 2 < d.size() ? abc[v & 63] : '=';
  }
  return s;
}

// A hand-made .gltf: one triangle (positions `pos`), optionally skinned to a chain of `joints`
// nodes with JOINTS_0 = `joint_index` for every vertex, optionally an animated chain without skin.
std::string tiny_gltf(const std::vector<float>& pos, bool skin, int joints, int joint_index,
                      bool animated_chain) {
  std::vector<std::uint8_t> buf;
  auto add = [&](const void* p, std::size_t n) {
    const std::size_t off = buf.size();
    buf.resize(off + n);
    std::memcpy(buf.data() + off, p, n);
    while (buf.size() % 4) buf.push_back(0);
    return off;
  };
  json views = json::array();
  json accs = json::array();
  auto acc = [&](const void* p, std::size_t n, int ctype, int count, const char* type) {
    views.push_back({{"buffer", 0}, {"byteOffset", add(p, n)}, {"byteLength", n}});
    accs.push_back(
        {{"bufferView", views.size() - 1}, {"componentType", ctype}, {"count", count}, {"type", type}});
    return accs.size() - 1;
  };
  const std::uint16_t idx[3] = {0, 1, 2};
  json attrs;
  attrs["POSITION"] = acc(pos.data(), 36, 5126, 3, "VEC3");
  accs[attrs["POSITION"].get<std::size_t>()]["min"] = {0, 0, 0};
  accs[attrs["POSITION"].get<std::size_t>()]["max"] = {1, 1, 0};
  const auto ind = acc(idx, 6, 5123, 3, "SCALAR");
  json nodes = json::array({{{"name", "body"}, {"mesh", 0}}});
  json doc;
  if (skin) {
    const std::uint16_t jv[12] = {static_cast<std::uint16_t>(joint_index), 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    const float wv[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
    attrs["JOINTS_0"] = acc(jv, 24, 5123, 3, "VEC4");
    attrs["WEIGHTS_0"] = acc(wv, 48, 5126, 3, "VEC4");
    nodes[0]["skin"] = 0;
    json list = json::array();
    for (int j = 0; j < joints; ++j) list.push_back(j + 1);
    doc["skins"] = json::array({{{"joints", list}}});
  }
  if (skin || animated_chain) {
    for (int j = 0; j < joints; ++j) {
      json n = {{"name", "j" + std::to_string(j)}, {"translation", {0, 0.5, 0}}};
      if (j + 1 < joints) n["children"] = {j + 2};
      nodes.push_back(n);
    }
  }
  if (animated_chain) {
    const float times[2] = {0, 1};
    const float rot[8] = {0, 0, 0, 1, 0, 0, 0.7071068f, 0.7071068f};
    const auto in = acc(times, 8, 5126, 2, "SCALAR");
    accs[in]["min"] = {0};
    accs[in]["max"] = {1};
    const auto out = acc(rot, 32, 5126, 2, "VEC4");
    doc["animations"] =
        json::array({{{"name", "turn"},
                      {"samplers", {{{"input", in}, {"output", out}}}},
                      {"channels", {{{"sampler", 0}, {"target", {{"node", 2}, {"path", "rotation"}}}}}}}});
  }
  json scene_nodes = {0};
  if (skin || animated_chain) scene_nodes.push_back(1);
  doc["asset"] = {{"version", "2.0"}};
  doc["scene"] = 0;
  doc["scenes"] = {{{"nodes", scene_nodes}}};
  doc["nodes"] = nodes;
  doc["meshes"] = {{{"primitives", {{{"attributes", attrs}, {"indices", ind}}}}}};
  doc["accessors"] = accs;
  doc["bufferViews"] = views;
  doc["buffers"] = {
      {{"byteLength", buf.size()}, {"uri", "data:application/octet-stream;base64," + base64(buf)}}};
  return doc.dump();
}

const std::vector<float> kTriangle = {0, 0, 0, 1, 0, 0, 0, 1, 0};

template <typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const isokit::InputError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST_CASE("rig_io: save -> load keeps joints, 6-influence weights, primitives and LBS over clips",
          "[skinning][io]") {
  const Rig rig = bar_rig();
  TempDir dir("roundtrip");
  const std::string ext = GENERATE(std::string(".glb"), std::string(".gltf"));
  const std::string path = dir.file("bar" + ext);
  save_rig(rig, path);
  LoadReport report;
  const Rig back = load_rig(path, {}, &report);
  INFO(path);
  CHECK(back.name == path);
  CHECK(report.meshes == 2);
  CHECK(report.max_influences == 6);
  CHECK(report.weights_from_file);

  // Skeleton: same names and parents (order may differ: the loader walks the node tree).
  REQUIRE(back.joints.size() == rig.joints.size());
  for (const Joint& j : rig.joints) {
    const int b = back.joint_index(j.name);
    REQUIRE(b >= 0);
    const Joint& jb = back.joints[static_cast<std::size_t>(b)];
    CHECK((j.parent < 0 ? std::string() : rig.joints[static_cast<std::size_t>(j.parent)].name) ==
          (jb.parent < 0 ? std::string() : back.joints[static_cast<std::size_t>(jb.parent)].name));
    CHECK(jb.rest_local.matrix().isApprox(j.rest_local.matrix(), 1e-6));
    CHECK(jb.inverse_bind.matrix().isApprox(j.inverse_bind.matrix(), 1e-6));
  }
  // Mesh: same welded count, same output vertices, triangles and primitive ranges.
  CHECK(back.rest.rows() == rig.rest.rows());
  REQUIRE(back.output.to_welded.size() == rig.output.to_welded.size());
  CHECK(back.output.triangles == rig.output.triangles);
  CHECK(back.output.primitive_offsets == rig.output.primitive_offsets);
  const track::Positions out_a = output_positions(rig, rig.rest);
  const track::Positions out_b = output_positions(back, back.rest);
  CHECK((out_a - out_b).cwiseAbs().maxCoeff() <= 1e-6f);
  // Weights per output vertex, by joint name.
  for (std::size_t i = 0; i < rig.output.to_welded.size(); ++i) {
    const auto wa = weights_of(rig, rig.output.to_welded[i]);
    const auto wb = weights_of(back, back.output.to_welded[i]);
    REQUIRE(wa.size() == wb.size());
    for (const auto& [name, x] : wa) CHECK(std::abs(wb.at(name) - x) <= 1e-6f);
  }
  // Clips and skinning.
  REQUIRE(back.clips.size() == 2);
  const double diag = diagonal(rig.rest);
  for (std::size_t c = 0; c < rig.clips.size(); ++c) {
    const Clip& ca = rig.clips[c];
    const Clip& cb = back.clips[c];
    const auto fb = clip_frames(cb);
    CHECK(cb.name == ca.name);
    CHECK(cb.fps == 30);
    REQUIRE(fb.size() == ca.local.size());
    for (std::size_t f = 0; f < ca.local.size(); ++f) {
      const track::Positions pa = output_positions(rig, lbs(rig, ca.local[f]));
      const track::Positions pb = output_positions(back, lbs(back, fb[f]));
      INFO("clip " << ca.name << " frame " << f);
      CHECK((pa - pb).cwiseAbs().maxCoeff() <= 1e-5 * diag);
    }
  }
  const track::Positions rest = lbs(back, rest_pose(back));
  CHECK((rest - back.rest).cwiseAbs().maxCoeff() <= 1e-5 * diag);
}

TEST_CASE("rig_io: glTF JSON of a saved rig has two weight sets and valid accessors", "[skinning][io]") {
  TempDir dir("json");
  save_rig(bar_rig(), dir.file("bar.glb"));
  const Glb g = parse_glb(dir.file("bar.glb"));
  const json& prims = g.doc["meshes"][0]["primitives"];
  REQUIRE(prims.size() == 2);
  for (const json& p : prims) {
    CHECK(p["attributes"].contains("JOINTS_1"));
    CHECK(p["attributes"].contains("WEIGHTS_1"));
    CHECK_FALSE(p["attributes"].contains("JOINTS_2"));
    check_min_max(g, p["attributes"]["POSITION"].get<int>());
  }
  CHECK(g.doc["skins"][0]["joints"].size() == 6);
  CHECK(g.doc["animations"].size() == 2);
}

TEST_CASE("rig_io: duplicate positions are welded, the output mapping restores the file's vertices",
          "[skinning][io]") {
  const Rig rig = bar_rig();
  TempDir dir("weld");
  // As saved: the bar's output vertices (split normals, two primitives) weld back to 4 per ring.
  save_rig(rig, dir.file("bar.glb"));
  LoadReport report;
  const Rig back = load_rig(dir.file("bar.glb"), {}, &report);
  CHECK(report.file_vertices == static_cast<int>(rig.output.to_welded.size()));
  CHECK(report.welded_vertices == 4 * kRings);
  CHECK(report.welded_vertices < report.file_vertices);
  const track::Positions original = output_positions(rig, rig.rest);
  CHECK(output_positions(back, back.rest) == original);
  CHECK(back.triangles.rows() == rig.triangles.rows());

  // LoadOptions::mesh picks meshes by mesh or node name and lists the names when none matches.
  LoadOptions pick;
  pick.mesh = "isokit_mesh";
  CHECK(load_rig(dir.file("bar.glb"), pick).rest.rows() == rig.rest.rows());
  pick.mesh = "arm";
  CHECK_THAT(error_of([&] { load_rig(dir.file("bar.glb"), pick); }),
             Catch::Contains("'arm'") && Catch::Contains("isokit_mesh"));

  // Nearly equal positions: kept apart by exact welding, merged by a tolerance.
  Rig near = rig;
  near.output = OutputMesh{};
  near.clips.clear();
  const Eigen::Index n = near.rest.rows();
  near.rest.conservativeResize(n + 3, 3);
  near.rest.row(n) = near.rest.row(0) + Eigen::RowVector3f(1e-5f, 0, 0);
  near.rest.row(n + 1) = near.rest.row(1);
  near.rest.row(n + 2) = near.rest.row(4) + Eigen::RowVector3f(0, 1e-5f, 0);
  near.triangles.conservativeResize(near.triangles.rows() + 1, 3);
  near.triangles.row(near.triangles.rows() - 1) << static_cast<int>(n), static_cast<int>(n + 1),
      static_cast<int>(n + 2);
  SkinWeights& w = near.weights;
  for (int k = 0; k < 3; ++k) {
    w.joints.push_back(0);
    w.weights.push_back(1.0f);
    w.offsets.push_back(w.offsets.back() + 1);
  }
  validate(near);
  save_rig(near, dir.file("near.gltf"));
  LoadReport exact;
  load_rig(dir.file("near.gltf"), {}, &exact);
  CHECK(exact.welded_vertices == static_cast<int>(n) + 2);  // only the exact copy of vertex 1 merges
  LoadOptions tol;
  tol.weld_tolerance = 1e-4;
  LoadReport merged;
  const Rig m = load_rig(dir.file("near.gltf"), tol, &merged);
  CHECK(merged.welded_vertices == static_cast<int>(n));
  CHECK(merged.dropped_triangles == 0);
  CHECK_FALSE(merged.warnings.empty());  // the copies' weights differ: averaged, and said so
  validate(m);
}

TEST_CASE("rig_io: baked GLB is valid glTF whose morph targets reproduce the frames", "[skinning][io]") {
  const Rig rig = bar_rig();
  // Frames: rest, then only the tip and lower joint bend (the first rings stay put: sparse).
  std::vector<track::Positions> frames;
  for (int f = 0; f < 6; ++f) {
    std::vector<Affine> local = rest_pose(rig);
    local[3] = local[3] * Affine(Eigen::AngleAxisd(0.2 * f, Eigen::Vector3d::UnitZ()));
    local[2] = local[2] * Affine(Eigen::AngleAxisd(0.1 * f, Eigen::Vector3d::UnitY()));
    frames.push_back(f == 0 ? rig.rest : lbs(rig, local));
  }
  TempDir dir("baked");
  const auto interp = GENERATE(MorphInterpolation::kLinear, MorphInterpolation::kStep);
  BakedGlbOptions opt;
  opt.interpolation = interp;
  const std::string path = dir.file("baked.glb");
  write_baked_glb(rig, frames, 24.0, path, opt);
  CHECK(dir.entries() == 1);

  const Glb g = parse_glb(path);
  const std::size_t nout = rig.output.to_welded.size();
  const json& prim = g.doc["meshes"][0]["primitives"][0];
  check_min_max(g, prim["attributes"]["POSITION"].get<int>());
  REQUIRE(prim["targets"].size() == frames.size());
  CHECK(g.doc["meshes"][0]["weights"].size() == frames.size());
  CHECK(g.doc["meshes"][0]["extras"]["targetNames"].size() == frames.size());
  const std::vector<float> rest = float_accessor(g, prim["attributes"]["POSITION"].get<int>(), 3);
  REQUIRE(rest.size() == 3 * nout);
  int sparse = 0;
  int zero = 0;
  const double diag = diagonal(rig.rest);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const int a = prim["targets"][k]["POSITION"].get<int>();
    check_min_max(g, a);
    const json& acc = g.doc["accessors"][static_cast<std::size_t>(a)];
    CHECK_FALSE((acc.contains("sparse") && acc.contains("bufferView")));
    sparse += acc.contains("sparse");
    CHECK(prim["targets"][k].contains("NORMAL"));
    const std::vector<float> delta = float_accessor(g, a, 3);
    zero += std::all_of(delta.begin(), delta.end(), [](float x) { return x == 0.0f; });
    double err = 0;
    for (std::size_t i = 0; i < nout; ++i)
      for (int c = 0; c < 3; ++c)
        err = std::max(err, std::abs(static_cast<double>(rest[3 * i + static_cast<std::size_t>(c)] +
                                                         delta[3 * i + static_cast<std::size_t>(c)]) -
                                     frames[k](rig.output.to_welded[i], c)));
    CHECK(err <= 1e-6 * diag);
  }
  CHECK(zero == 1);    // frame 0 is the rest pose
  CHECK(sparse >= 1);  // frames where only part of the bar moves
  const json& anim = g.doc["animations"][0];
  const json& sampler = anim["samplers"][0];
  CHECK(sampler["interpolation"] == (interp == MorphInterpolation::kStep ? "STEP" : "LINEAR"));
  CHECK(g.doc["accessors"][sampler["input"].get<std::size_t>()]["count"] == frames.size());
  CHECK(g.doc["accessors"][sampler["input"].get<std::size_t>()]["max"][0].get<float>() == Approx(5.0 / 24.0));
  CHECK(g.doc["accessors"][sampler["output"].get<std::size_t>()]["count"] == frames.size() * frames.size());
  CHECK(anim["channels"][0]["target"]["path"] == "weights");

  // assimp reads it: one mesh with one morph target per frame (absolute positions).
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path, aiProcess_ValidateDataStructure);
  REQUIRE(scene != nullptr);
  REQUIRE(scene->mNumMeshes == 1);
  const aiMesh* mesh = scene->mMeshes[0];
  REQUIRE(mesh->mNumVertices == nout);
  REQUIRE(mesh->mNumAnimMeshes == frames.size());
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const aiAnimMesh* am = mesh->mAnimMeshes[k];
    double err = 0;
    for (std::size_t i = 0; i < nout; ++i) {
      const aiVector3D& p = am->mVertices[i];
      const Eigen::RowVector3f q = frames[k].row(rig.output.to_welded[i]);
      err =
          std::max({err, std::abs(static_cast<double>(p.x - q.x())),
                    std::abs(static_cast<double>(p.y - q.y())), std::abs(static_cast<double>(p.z - q.z()))});
    }
    CHECK(err <= 1e-6 * diag);
  }
  REQUIRE(scene->mNumAnimations == 1);
  CHECK(scene->mAnimations[0]->mNumMorphMeshChannels == 1);
}

TEST_CASE("rig_io: baked GLB errors leave no file behind", "[skinning][io]") {
  const Rig rig = bar_rig();
  TempDir dir("baked_err");
  std::vector<track::Positions> frames(3, rig.rest);
  frames[1](0, 0) += 1.0f;
  BakedGlbOptions tiny;
  tiny.max_bytes = 100;
  const std::string path = dir.file("big.glb");
  const std::string msg = error_of([&] { write_baked_glb(rig, frames, 30, path, tiny); });
  CHECK_THAT(msg, Catch::Contains(path));
  CHECK(dir.entries() == 0);
  frames[2].conservativeResize(3, 3);
  CHECK_THAT(error_of([&] { write_baked_glb(rig, frames, 30, path); }), Catch::Contains("frame 2"));
  CHECK_THAT(error_of([&] { write_baked_glb(rig, {rig.rest}, 30, dir.file("missing/x.glb")); }),
             Catch::Contains("missing"));
  CHECK_THAT(error_of([&] { write_baked_glb(rig, {rig.rest}, 30, dir.file("x.gltf")); }),
             Catch::Contains(".glb"));
  CHECK(dir.entries() == 0);
}

TEST_CASE("rig_io: saved and baked glTF pass the Khronos validator with no error or warning",
          "[skinning][io]") {
  // Runs tests/skinning/validate_gltf.js under node (npm gltf-validator); skipped without them.
  if (std::system("node --version > /dev/null 2>&1") != 0) {
    WARN("node not found: the Khronos validator is not run");
    return;
  }
  const Rig rig = bar_rig();
  TempDir dir("validator");
  std::vector<track::Positions> frames;
  for (int f = 0; f < 4; ++f) {
    std::vector<Affine> local = rest_pose(rig);
    local[3] = local[3] * Affine(Eigen::AngleAxisd(0.3 * f, Eigen::Vector3d::UnitZ()));
    frames.push_back(f == 0 ? rig.rest : lbs(rig, local));
  }
  save_rig(rig, dir.file("rig.glb"));
  save_rig(rig, dir.file("rig.gltf"));
  write_baked_glb(rig, frames, 30, dir.file("baked.glb"));
  BakedGlbOptions dense;
  dense.sparse = false;
  dense.normals = false;
  dense.interpolation = MorphInterpolation::kStep;
  write_baked_glb(rig, frames, 30, dir.file("dense.glb"), dense);
  const std::string log = dir.file("validator.txt");
  std::string command = "node '" ISOKIT_TEST_SOURCE_DIR "/skinning/validate_gltf.js'";
  for (const char* f : {"rig.glb", "rig.gltf", "baked.glb", "dense.glb"}) command += " '" + dir.file(f) + "'";
  const int status = std::system((command + " > '" + log + "' 2>&1").c_str());
  const std::vector<std::uint8_t> bytes = read_all(log);
  const std::string out(bytes.begin(), bytes.end());
  const int rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (rc == 77) {
    WARN("the Khronos validator is not installed (npm install -g gltf-validator): " << out);
    return;
  }
  INFO(out);
  CHECK(rc == 0);
  CHECK_THAT(out, Catch::Contains("baked.glb: errors 0 warnings 0") &&
                      Catch::Contains("rig.gltf: errors 0 warnings 0"));
}

TEST_CASE("rig_io: write_ply writes binary little-endian PLY", "[skinning][io]") {
  const Rig rig = bar_rig();
  TempDir dir("ply");
  const std::string path = dir.file("rest.ply");
  write_ply(path, rig.rest, rig.triangles);
  const std::vector<std::uint8_t> bytes = read_all(path);
  const std::string text(bytes.begin(), bytes.end());
  const std::size_t end = text.find("end_header\n");
  REQUIRE(end != std::string::npos);
  CHECK(text.rfind("ply\nformat binary_little_endian 1.0\n", 0) == 0);
  CHECK(text.find("element vertex " + std::to_string(rig.rest.rows())) != std::string::npos);
  CHECK(text.find("element face " + std::to_string(rig.triangles.rows())) != std::string::npos);
  const std::size_t body = end + 11;
  CHECK(bytes.size() == body + 12 * static_cast<std::size_t>(rig.rest.rows()) +
                            13 * static_cast<std::size_t>(rig.triangles.rows()));
  CHECK(read_float(bytes, body + 12 * 5 + 4) == rig.rest(5, 1));
  const std::size_t faces = body + 12 * static_cast<std::size_t>(rig.rest.rows());
  CHECK(bytes[faces] == 3);
  CHECK(static_cast<int>(u32(bytes.data() + faces + 1)) == rig.triangles(0, 0));
  track::Triangles bad = rig.triangles;
  bad(0, 0) = 1000;
  CHECK_THAT(error_of([&] { write_ply(dir.file("bad.ply"), rig.rest, bad); }), Catch::Contains("triangle 0"));
  CHECK_FALSE(fs::exists(dir.file("bad.ply")));
}

TEST_CASE("rig_io: load errors name the file, the item and the fix", "[skinning][io]") {
  TempDir dir("errors");
  const Rig rig = bar_rig();

  const std::string missing = dir.file("nope.glb");
  std::string msg = error_of([&] { load_rig(missing); });
  CHECK_THAT(msg, Catch::Contains(missing) && Catch::Contains("does not exist"));

  save_rig(rig, dir.file("bar.glb"));
  std::vector<std::uint8_t> bytes = read_all(dir.file("bar.glb"));
  bytes.resize(bytes.size() / 2);
  const std::string truncated = dir.file("truncated.glb");
  write_all(truncated, std::string(bytes.begin(), bytes.end()));
  msg = error_of([&] { load_rig(truncated); });
  CHECK_THAT(msg, Catch::Contains(truncated) && Catch::Contains("truncated"));

  const std::string bad_json = dir.file("bad.gltf");
  write_all(bad_json, "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [");
  msg = error_of([&] { load_rig(bad_json); });
  CHECK_THAT(msg, Catch::Contains(bad_json) && Catch::Contains("JSON"));

  const std::string garbage = dir.file("garbage.fbx");
  write_all(garbage, "this is not an FBX file");
  msg = error_of([&] { load_rig(garbage); });
  CHECK_THAT(msg, Catch::Contains(garbage) && Catch::Contains("assimp"));

  // A mesh without skin or skeleton (the baked GLB) and a lone triangle.
  write_baked_glb(rig, {rig.rest}, 30, dir.file("baked.glb"));
  msg = error_of([&] { load_rig(dir.file("baked.glb")); });
  CHECK_THAT(msg, Catch::Contains(dir.file("baked.glb")) && Catch::Contains("no skin"));
  write_all(dir.file("plain.gltf"), tiny_gltf(kTriangle, false, 0, 0, false));
  CHECK_THAT(error_of([&] { load_rig(dir.file("plain.gltf")); }), Catch::Contains("no skin"));

  // Weights naming a joint the skin does not have (assimp would drop them silently).
  write_all(dir.file("badjoint.gltf"), tiny_gltf(kTriangle, true, 2, 7, false));
  msg = error_of([&] { load_rig(dir.file("badjoint.gltf")); });
  CHECK_THAT(msg, Catch::Contains(dir.file("badjoint.gltf")) && Catch::Contains("JOINTS_0 names joint 7"));

  // Non-finite positions.
  std::vector<float> nan_pos = kTriangle;
  nan_pos[4] = std::nanf("");
  write_all(dir.file("nan.gltf"), tiny_gltf(nan_pos, true, 2, 0, false));
  msg = error_of([&] { load_rig(dir.file("nan.gltf")); });
  CHECK_THAT(
      msg, Catch::Contains(dir.file("nan.gltf")) && Catch::Contains("vertex 1") && Catch::Contains("finite"));

  // Writers: bad extension, missing folder, invalid names.
  CHECK_THAT(error_of([&] { save_rig(rig, dir.file("bar.obj")); }), Catch::Contains(".glb or .gltf"));
  CHECK_THAT(error_of([&] { save_rig(rig, dir.file("no/such/bar.glb")); }),
             Catch::Contains("does not exist"));
  Rig dup = rig;
  dup.joints[1].name = "root";
  CHECK_THAT(error_of([&] { save_rig(dup, dir.file("dup.glb")); }), Catch::Contains("unique"));
  CHECK_FALSE(fs::exists(dir.file("dup.glb")));
}

TEST_CASE("rig_io: a mesh with a skeleton but no weights loads with empty weights", "[skinning][io]") {
  TempDir dir("noweights");
  write_all(dir.file("chain.gltf"), tiny_gltf(kTriangle, false, 3, 0, true));
  LoadReport report;
  const Rig rig = load_rig(dir.file("chain.gltf"), {}, &report);
  CHECK(rig.weights.empty());
  CHECK_FALSE(report.weights_from_file);
  REQUIRE(rig.joints.size() == 3);
  CHECK(rig.joints[0].name == "j0");
  CHECK(rig.joints[1].parent == 0);
  REQUIRE(rig.clips.size() == 1);
  CHECK(rig.clips[0].name == "turn");
  CHECK(rig.clips[0].frame_count() == 31);  // 1 s at 30 fps
  // The animated joint turns by 90 degrees about z over the clip.
  const Eigen::Matrix3d end = clip_frames(rig.clips[0]).back()[1].linear();
  CHECK(end.isApprox(Eigen::AngleAxisd(isokit::kPi / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix(), 1e-5));

  // Skinned, with ignore_weights: skeleton kept, weights dropped.
  write_all(dir.file("skinned.gltf"), tiny_gltf(kTriangle, true, 2, 1, false));
  LoadOptions opt;
  opt.ignore_weights = true;
  const Rig no_w = load_rig(dir.file("skinned.gltf"), opt);
  CHECK(no_w.weights.empty());
  CHECK(no_w.joints.size() == 2);
  const Rig with_w = load_rig(dir.file("skinned.gltf"));
  REQUIRE_FALSE(with_w.weights.empty());
  CHECK(with_w.joints[static_cast<std::size_t>(with_w.weights.joints[0])].name == "j1");
}

// COLLADA: a two-joint strip (quads), a bind-shape matrix (z + 0.5), a mesh node moved by x + 5
// (ignored: skinned), and a 1 s matrix animation turning "upper" by 90 degrees about z.
const char* const kStripDae = R"DAE(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Y_UP</up_axis></asset>
  <library_geometries>
    <geometry id="strip-mesh" name="strip">
      <mesh>
        <source id="strip-pos">
          <float_array id="strip-pos-array" count="18">0 0 0 1 0 0 0 1 0 1 1 0 0 2 0 1 2 0</float_array>
          <technique_common><accessor source="#strip-pos-array" count="6" stride="3">
            <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
          </accessor></technique_common>
        </source>
        <vertices id="strip-verts"><input semantic="POSITION" source="#strip-pos"/></vertices>
        <polylist count="2"><input semantic="VERTEX" source="#strip-verts" offset="0"/>
          <vcount>4 4</vcount><p>0 1 3 2 2 3 5 4</p></polylist>
      </mesh>
    </geometry>
  </library_geometries>
  <library_controllers>
    <controller id="strip-skin"><skin source="#strip-mesh">
      <bind_shape_matrix>1 0 0 0 0 1 0 0 0 0 1 0.5 0 0 0 1</bind_shape_matrix>
      <source id="joints"><Name_array id="joints-array" count="2">lower upper</Name_array>
        <technique_common><accessor source="#joints-array" count="2" stride="1"><param name="JOINT" type="name"/></accessor></technique_common></source>
      <source id="binds"><float_array id="binds-array" count="32">1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1 1 0 0 0 0 1 0 -1 0 0 1 0 0 0 0 1</float_array>
        <technique_common><accessor source="#binds-array" count="2" stride="16"><param name="TRANSFORM" type="float4x4"/></accessor></technique_common></source>
      <source id="weights"><float_array id="weights-array" count="2">1 0.5</float_array>
        <technique_common><accessor source="#weights-array" count="2" stride="1"><param name="WEIGHT" type="float"/></accessor></technique_common></source>
      <joints><input semantic="JOINT" source="#joints"/><input semantic="INV_BIND_MATRIX" source="#binds"/></joints>
      <vertex_weights count="6"><input semantic="JOINT" source="#joints" offset="0"/><input semantic="WEIGHT" source="#weights" offset="1"/>
        <vcount>1 1 2 2 1 1</vcount><v>0 0 0 0 0 1 1 1 0 1 1 1 1 0 1 0</v></vertex_weights>
    </skin></controller>
  </library_controllers>
  <library_animations><animation id="bend" name="bend">
    <source id="bend-in"><float_array id="bend-in-array" count="2">0 1</float_array>
      <technique_common><accessor source="#bend-in-array" count="2" stride="1"><param name="TIME" type="float"/></accessor></technique_common></source>
    <source id="bend-out"><float_array id="bend-out-array" count="32">1 0 0 0 0 1 0 1 0 0 1 0 0 0 0 1 0 -1 0 0 1 0 0 1 0 0 1 0 0 0 0 1</float_array>
      <technique_common><accessor source="#bend-out-array" count="2" stride="16"><param name="TRANSFORM" type="float4x4"/></accessor></technique_common></source>
    <source id="bend-interp"><Name_array id="bend-interp-array" count="2">LINEAR LINEAR</Name_array>
      <technique_common><accessor source="#bend-interp-array" count="2" stride="1"><param name="INTERPOLATION" type="name"/></accessor></technique_common></source>
    <sampler id="bend-sampler"><input semantic="INPUT" source="#bend-in"/><input semantic="OUTPUT" source="#bend-out"/><input semantic="INTERPOLATION" source="#bend-interp"/></sampler>
    <channel source="#bend-sampler" target="upper/transform"/>
  </animation></library_animations>
  <library_visual_scenes>
    <visual_scene id="scene">
      <node id="lower" sid="lower" name="lower" type="JOINT"><matrix sid="transform">1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1</matrix>
        <node id="upper" sid="upper" name="upper" type="JOINT"><matrix sid="transform">1 0 0 0 0 1 0 1 0 0 1 0 0 0 0 1</matrix></node>
      </node>
      <node id="strip" name="strip"><matrix sid="transform">1 0 0 5 0 1 0 0 0 0 1 0 0 0 0 1</matrix>
        <instance_controller url="#strip-skin"><skeleton>#lower</skeleton></instance_controller></node>
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
)DAE";

TEST_CASE("rig_io: COLLADA skin, bind shape and matrix animation", "[skinning][io]") {
  TempDir dir("dae");
  write_all(dir.file("strip.dae"), kStripDae);
  LoadReport report;
  const Rig rig = load_rig(dir.file("strip.dae"), {}, &report);
  REQUIRE(rig.joints.size() == 2);
  CHECK(rig.joints[0].name == "lower");
  CHECK(rig.joints[1].name == "upper");
  CHECK(rig.joints[1].parent == 0);
  CHECK(report.welded_vertices == 6);                           // quads triangulated, corners welded
  CHECK(rig.rest.col(2).cwiseAbs().maxCoeff() == Approx(0.5));  // bind shape matrix applied
  CHECK(rig.rest.col(0).minCoeff() == Approx(0.0));             // mesh node transform ignored
  REQUIRE(rig.clips.size() == 1);
  CHECK(rig.clips[0].name == "bend");
  REQUIRE(rig.clips[0].frame_count() == 31);
  const track::Positions end = lbs(rig, clip_frames(rig.clips[0]).back());
  for (Eigen::Index v = 0; v < rig.rest.rows(); ++v) {
    const Eigen::Vector3f r = rig.rest.row(v).transpose();
    Eigen::Vector3f expected = r;
    const Eigen::Vector3f turned(1.0f - r.y(), 1.0f + r.x(), r.z());  // 90 degrees about (0, 1, z)
    if (r.y() > 1.5f) expected = turned;
    if (std::abs(r.y() - 1.0f) < 0.5f) expected = 0.5f * (r + turned);
    CHECK((end.row(v).transpose() - expected).norm() <= 1e-5f);
  }
}

TEST_CASE("rig_io: sample rigs named by ISOKIT_SAMPLE_RIGS load and skin", "[skinning][io][samples]") {
  const char* folder = std::getenv("ISOKIT_SAMPLE_RIGS");
  if (folder == nullptr) return;  // optional: only where the sample folder exists
  for (const char* name : {"Fox.glb", "RiggedSimple.gltf", "SimpleSkin.gltf"}) {
    const std::string path = (fs::path(folder) / name).string();
    if (!fs::exists(path)) continue;
    LoadReport report;
    const Rig rig = load_rig(path, {}, &report);
    std::ostringstream s;
    s << name << ": " << report.file_vertices << " file vertices -> " << report.welded_vertices << " welded, "
      << rig.triangles.rows() << " triangles, " << report.meshes << " primitive(s), " << rig.joints.size()
      << " joints, max " << report.max_influences << " influences, clips:";
    for (const Clip& c : rig.clips) s << " " << c.name << "(" << c.frame_count() << ")";
    for (const std::string& w : report.warnings) s << "\n  warning: " << w;
    WARN(s.str());
    const double diag = diagonal(rig.rest);
    for (const Clip& c : rig.clips)
      for (const auto& pose : clip_frames(c)) {
        const track::Positions p = lbs(rig, pose);
        REQUIRE(p.allFinite());
        CHECK(diagonal(p) > 0.5 * diag);
        CHECK(diagonal(p) < 2.0 * diag);
      }
    CHECK((lbs(rig, rest_pose(rig)) - rig.rest).cwiseAbs().maxCoeff() <= 1e-4 * diag);
    // Written by save_rig and read back: the same skinning.
    TempDir dir("samples");
    save_rig(rig, dir.file("copy.glb"));
    const Rig back = load_rig(dir.file("copy.glb"));
    REQUIRE(back.output.to_welded.size() == rig.output.to_welded.size());
    REQUIRE(back.clips.size() == rig.clips.size());
    for (std::size_t c = 0; c < rig.clips.size(); ++c) {
      const auto fa = clip_frames(rig.clips[c]);
      const auto fb = clip_frames(back.clips[c]);
      REQUIRE(fb.size() == fa.size());
      for (std::size_t f = 0; f < fa.size(); f += 5)
        CHECK((output_positions(rig, lbs(rig, fa[f])) - output_positions(back, lbs(back, fb[f])))
                  .cwiseAbs()
                  .maxCoeff() <= 1e-5 * diag);
    }
  }
}

namespace {

// The bar with a relaxation mask that varies along it: 0 at the root end, 1 at the tip.
Rig masked_bar() {
  Rig rig = bar_rig();
  const float lo = rig.rest.col(0).minCoeff(), hi = rig.rest.col(0).maxCoeff();
  rig.relax_mask.resize(static_cast<std::size_t>(rig.rest.rows()));
  for (Eigen::Index v = 0; v < rig.rest.rows(); ++v)
    rig.relax_mask[static_cast<std::size_t>(v)] = std::round(4.0f * (rig.rest(v, 0) - lo) / (hi - lo)) / 4.0f;
  return rig;
}

}  // namespace

TEST_CASE("rig_io: the relaxation mask round-trips as the glTF attribute _RELAX_MASK",
          "[skinning][io][mask][unit]") {
  const Rig rig = masked_bar();
  TempDir dir("mask");
  const std::string ext = GENERATE(std::string(".glb"), std::string(".gltf"));
  save_rig(rig, dir.file("bar" + ext));
  LoadReport report;
  const Rig back = load_rig(dir.file("bar" + ext), {}, &report);
  REQUIRE(back.relax_mask.size() == static_cast<std::size_t>(back.rest.rows()));
  CHECK(report.mask_source == "attribute _RELAX_MASK");
  // Welded back to the same vertices (output order), the same values.
  for (Eigen::Index v = 0; v < back.rest.rows(); ++v) {
    Eigen::Index same = -1;
    for (Eigen::Index u = 0; u < rig.rest.rows(); ++u)
      if (rig.rest.row(u) == back.rest.row(v)) same = u;
    REQUIRE(same >= 0);
    CHECK(back.relax_mask[std::size_t(v)] == rig.relax_mask[std::size_t(same)]);
  }
  // Another attribute name, or none: no mask.
  LoadOptions other;
  other.mask.attribute = "_PAINT";
  CHECK(load_rig(dir.file("bar" + ext), other).relax_mask.empty());
  other.mask.attribute.clear();
  CHECK(load_rig(dir.file("bar" + ext), other).relax_mask.empty());
  // A rig without a mask writes none.
  save_rig(bar_rig(), dir.file("plain" + ext));
  CHECK(load_rig(dir.file("plain" + ext)).relax_mask.empty());

  // The baked glb carries it too, one value per output vertex.
  const std::vector<track::Positions> frames(2, rig.rest);
  write_baked_glb(rig, frames, 24.0, dir.file("baked.glb"));
  const Glb g = parse_glb(dir.file("baked.glb"));
  const json& attrs = g.doc["meshes"][0]["primitives"][0]["attributes"];
  REQUIRE(attrs.contains("_RELAX_MASK"));
  const std::vector<float> m = float_accessor(g, attrs["_RELAX_MASK"].get<int>(), 1);
  REQUIRE(m.size() == rig.output.to_welded.size());
  for (std::size_t o = 0; o < m.size(); ++o)
    CHECK(m[o] == rig.relax_mask[static_cast<std::size_t>(rig.output.to_welded[o])]);
}

TEST_CASE("rig_io: the relaxation mask from a vertex-colour set, and bad masks",
          "[skinning][io][mask][unit]") {
  const Rig rig = masked_bar();
  TempDir dir("mask_color");
  save_rig(rig, dir.file("bar.gltf"));
  // Replace each primitive's _RELAX_MASK by COLOR_0 = (0.25, 0, 2, 1) in a second buffer, as a
  // painter's vertex colours would carry it (the blue channel out of range: clamped).
  json doc = json::parse(std::ifstream(dir.file("bar.gltf")));
  std::vector<std::uint8_t> bin;
  for (json& mesh : doc["meshes"])
    for (json& prim : mesh["primitives"]) {
      const int mask_accessor = prim["attributes"]["_RELAX_MASK"].get<int>();
      const std::size_t n = doc["accessors"][std::size_t(mask_accessor)]["count"].get<std::size_t>();
      prim["attributes"].erase("_RELAX_MASK");
      const std::size_t offset = bin.size();
      for (std::size_t i = 0; i < n; ++i)
        for (const float x : {0.25f, 0.f, 2.f, 1.f}) {
          std::uint8_t b[4];
          std::memcpy(b, &x, 4);
          bin.insert(bin.end(), b, b + 4);
        }
      json view = {{"buffer", doc["buffers"].size()}, {"byteOffset", offset}, {"byteLength", 16 * n}};
      doc["bufferViews"].push_back(view);
      json acc = {{"bufferView", doc["bufferViews"].size() - 1},
                  {"componentType", 5126},
                  {"count", n},
                  {"type", "VEC4"}};
      doc["accessors"].push_back(acc);
      prim["attributes"]["COLOR_0"] = doc["accessors"].size() - 1;
    }
  doc["buffers"].push_back(
      {{"byteLength", bin.size()}, {"uri", "data:application/octet-stream;base64," + base64(bin)}});
  std::ofstream(dir.file("painted.gltf")) << doc.dump();
  LoadOptions o;
  o.mask.color_set = 0;
  o.mask.channel = 0;
  LoadReport report;
  Rig red = load_rig(dir.file("painted.gltf"), o, &report);
  CHECK(report.mask_source == "vertex colour set 0 channel r");
  REQUIRE(red.relax_mask.size() == static_cast<std::size_t>(red.rest.rows()));
  for (float m : red.relax_mask) CHECK(m == 0.25f);
  o.mask.channel = 2;  // 2.0: clamped to 1
  for (float m : load_rig(dir.file("painted.gltf"), o).relax_mask) CHECK(m == 1.0f);
  o.mask.color_set = 1;  // no such set: no mask
  CHECK(load_rig(dir.file("painted.gltf"), o).relax_mask.empty());
  CHECK(load_rig(dir.file("painted.gltf")).relax_mask.empty());  // no attribute, no set chosen
  // Colours of another shape (VEC2) are skipped with a warning: the file still loads.
  for (const json& mesh : doc["meshes"])
    for (const json& prim : mesh["primitives"])
      doc["accessors"][prim["attributes"]["COLOR_0"].get<std::size_t>()]["type"] = "VEC2";
  std::ofstream(dir.file("two.gltf")) << doc.dump();
  o.mask.color_set = 0;
  o.mask.channel = 0;
  LoadReport two;
  CHECK(load_rig(dir.file("two.gltf"), o, &two).relax_mask.empty());
  CHECK(std::any_of(two.warnings.begin(), two.warnings.end(),
                    [](const std::string& w) { return w.find("COLOR_0") != std::string::npos; }));
  o.mask.color_set = 9;
  CHECK_THAT(error_of([&] { load_rig(dir.file("painted.gltf"), o); }), Catch::Contains("mask.color_set"));
  o.mask.color_set = 0;
  o.mask.channel = 4;
  CHECK_THAT(error_of([&] { load_rig(dir.file("painted.gltf"), o); }), Catch::Contains("mask.channel"));

  // A rig's own mask must fit it.
  Rig bad = masked_bar();
  bad.relax_mask.pop_back();
  CHECK_THAT(error_of([&] { validate(bad); }),
             Catch::Contains("relaxation mask") && Catch::Contains("values for"));
  bad = masked_bar();
  bad.relax_mask[3] = -0.5f;
  CHECK_THAT(error_of([&] { validate(bad); }), Catch::Contains("relaxation mask of vertex 3"));
}

TEST_CASE(
    "rig_io: the relaxation mask from a COLLADA colour set, read in the importer's child and in process",
    "[skinning][io][mask][unit]") {
  // The strip with a colour per vertex: red 0.3, green = y / 2 (0 at the root end, 1 at the tip).
  std::string dae = kStripDae;
  const std::string colours = R"(<source id="strip-col">
          <float_array id="strip-col-array" count="24">0.3 0 0 1 0.3 0 0 1 0.3 0.5 0 1 0.3 0.5 0 1 0.3 1 0 1 0.3 1 0 1</float_array>
          <technique_common><accessor source="#strip-col-array" count="6" stride="4">
            <param name="R" type="float"/><param name="G" type="float"/><param name="B" type="float"/><param name="A" type="float"/>
          </accessor></technique_common>
        </source>
        <vertices id="strip-verts">)";
  const std::size_t at = dae.find("<vertices id=\"strip-verts\">");
  REQUIRE(at != std::string::npos);
  dae.replace(at, std::string("<vertices id=\"strip-verts\">").size(), colours);
  const std::string vertex_input = R"(<input semantic="VERTEX" source="#strip-verts" offset="0"/>)";
  const std::size_t in = dae.find(vertex_input);
  REQUIRE(in != std::string::npos);
  dae.insert(in + vertex_input.size(), R"(<input semantic="COLOR" source="#strip-col" offset="0" set="0"/>)");
  TempDir dir("dae_mask");
  write_all(dir.file("painted.dae"), dae.c_str());
  for (const bool isolate : {true, false}) {
    INFO((isolate ? "in the importer's child" : "in process"));
    LoadOptions o;
    o.isolate_importer = isolate;
    o.mask.color_set = 0;
    o.mask.channel = 1;
    LoadReport report;
    const Rig rig = load_rig(dir.file("painted.dae"), o, &report);
    CHECK(report.mask_source == "vertex colour set 0 channel g");
    REQUIRE(rig.relax_mask.size() == static_cast<std::size_t>(rig.rest.rows()));
    for (Eigen::Index v = 0; v < rig.rest.rows(); ++v)
      CHECK(rig.relax_mask[std::size_t(v)] == Approx(rig.rest(v, 1) / 2.0f).margin(1e-6));
    // Without the setup's choice a COLLADA file has no mask (the attribute is glTF's).
    o.mask.color_set = -1;
    CHECK(load_rig(dir.file("painted.dae"), o).relax_mask.empty());
  }
}
