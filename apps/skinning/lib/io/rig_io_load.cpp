// SPDX-License-Identifier: MIT
// load_rig: scene -> Rig (merged, welded mesh; joints parents first with the bind pose as rest
// pose; all weight sets; clips sampled at a fixed rate). glTF files are read by tinygltf, checked
// (joint indices of every weight set, finite data) and turned into an aiScene (gltf_scene.cpp);
// FBX and COLLADA are read by assimp. Both go through the same Loader.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <unordered_map>
#include <utility>

#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Importer.hpp>

#include "io/gltf_io.h"
#include "io/isolated.h"
#include "io/rig_wire.h"
#include "isokit/core/error.h"
#include "isokit/core/load_budget.h"
#include "isokit/skinning/procedural.h"
#include "isokit/skinning/rig_io.h"
#include "rig/clip_keys.h"

namespace isokit::skinning {

namespace {

namespace fs = std::filesystem;

// Most frames a clip may have when sampled (a day at 30 fps, 2.6 M frames, is beyond any rig's
// clip; the bound keeps a corrupt key time from overflowing the frame count).
constexpr int kMaxClipFrames = 10000000;

// Relative tolerance under which two bind matrices of one joint count as equal.
constexpr double kBindTolerance = 1e-4;

Affine to_affine(const aiMatrix4x4& m) {
  Eigen::Matrix4d e;
  e << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4;
  Affine a;
  a.matrix() = e;
  a.matrix().row(3) << 0, 0, 0, 1;
  return a;
}

// Bottom row (0, 0, 0, 1) within float rounding (exporters write 0.99999988); `to_affine` then
// drops the row.
bool is_affine(const aiMatrix4x4& m) {
  return std::abs(m.d1) < 1e-5 && std::abs(m.d2) < 1e-5 && std::abs(m.d3) < 1e-5 && std::abs(m.d4 - 1) < 1e-5;
}

double max_abs(const Eigen::Matrix4d& m) {
  return m.cwiseAbs().maxCoeff();
}

bool nearly_equal(const Affine& a, const Affine& b) {
  const double scale = std::max({1.0, max_abs(a.matrix()), max_abs(b.matrix())});
  return max_abs(a.matrix() - b.matrix()) <= kBindTolerance * scale;
}

// Identity within float rounding; `length` is the scale of the translations that formed `a`.
bool nearly_identity(const Affine& a, double length) {
  return (a.linear() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= 1e-6 &&
         a.translation().cwiseAbs().maxCoeff() <= 1e-6 * std::max(1.0, length);
}

bool has_shear(const Affine& a) {
  const Eigen::Matrix3d g = a.linear().transpose() * a.linear();
  const double diag = g.diagonal().cwiseAbs().maxCoeff();
  double off = 0;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (r != c) off = std::max(off, std::abs(g(r, c)));
  return off > 1e-4 * std::max(diag, 1e-30);
}

std::string quote(const std::string& s) {
  return "'" + s + "'";
}

// ---------------------------------------------------------------------------------------------
// glTF pre-check

struct GltfInfo {
  std::vector<std::string> skin_joint_names;  ///< assimp's names of the skins' joint nodes
  /// Per node: a unique name (the file's name; `NAME#k` for the k-th node sharing it).
  std::vector<std::string> node_names;
  /// Unique name -> the file's name, for the nodes renamed (empty: every name is unique).
  std::map<std::string, std::string> file_names;
};

// An unnamed glTF node is "nodes[i]" (as assimp names it).
std::string gltf_node_name(const std::vector<tinygltf::Node>& nodes, std::size_t i) {
  return nodes[i].name.empty() ? "nodes[" + std::to_string(i) + "]" : nodes[i].name;
}

/// Unique node names (glTF allows duplicates): the first node (in file order) keeps its name, the
/// k-th node sharing it is `NAME#k` (k = 2, 3, ...; skipping names the file already uses).
void unique_node_names(const std::vector<tinygltf::Node>& nodes, GltfInfo& info) {
  std::set<std::string> taken;
  for (std::size_t i = 0; i < nodes.size(); ++i) taken.insert(gltf_node_name(nodes, i));
  std::map<std::string, int> seen;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const std::string name = gltf_node_name(nodes, i);
    std::string unique = name;
    if (++seen[name] > 1) {
      for (int k = seen[name]; taken.count(unique = name + "#" + std::to_string(k)) > 0;) ++k;
      taken.insert(unique);
      info.file_names[unique] = name;
    }
    info.node_names.push_back(unique);
  }
}

/// Checks every skin's joint indices and inverse bind matrices; collects the joint names.
void check_skins(const tinygltf::Model& model, const std::string& path, GltfInfo& info, LoadBudget& budget) {
  std::set<std::string> names;
  for (std::size_t s = 0; s < model.skins.size(); ++s) {
    const std::string what = path + ": skins[" + std::to_string(s) + "]";
    const std::vector<int>& joints = model.skins[s].joints;
    for (std::size_t k = 0; k < joints.size(); ++k) {
      require(joints[k] >= 0 && static_cast<std::size_t>(joints[k]) < model.nodes.size(),
              what + ".joints[" + std::to_string(k) + "]", "names a node that does not exist",
              "fix the file or export it again");
      const std::string name = info.node_names[static_cast<std::size_t>(joints[k])];
      if (names.insert(name).second) info.skin_joint_names.push_back(name);
    }
    if (model.skins[s].inverseBindMatrices >= 0) {
      int comps = 0;
      const std::vector<double> m = gltf::read_accessor(model, model.skins[s].inverseBindMatrices, &comps,
                                                        what + ".inverseBindMatrices", &budget);
      require(comps == 16 && m.size() >= 16 * joints.size(), what + ".inverseBindMatrices",
              "needs one MAT4 per joint", "fix the file or export it again");
      for (double x : m)
        require(std::isfinite(x), what + ".inverseBindMatrices", "has a non-finite value",
                "fix the bind pose and export again");
    }
  }
}

/// Every attribute of a primitive has as many elements as its POSITION (glTF 2.0, 3.7.2.1).
void check_attribute_counts(const tinygltf::Model& model, const std::map<std::string, int>& attrs,
                            const std::string& where) {
  const auto pos = attrs.find("POSITION");
  if (pos == attrs.end()) return;
  auto count = [&](int a, const std::string& name) {
    require(a >= 0 && static_cast<std::size_t>(a) < model.accessors.size(), where + " " + name,
            "names accessor " + std::to_string(a) + ", which does not exist",
            "fix the file or export it again");
    return model.accessors[static_cast<std::size_t>(a)].count;
  };
  const std::size_t nv = count(pos->second, "POSITION");
  for (const auto& [name, a] : attrs)
    require(count(a, name) == nv, where + " " + name,
            "has " + std::to_string(count(a, name)) + " elements but POSITION has " + std::to_string(nv),
            "the file is corrupt: every attribute of a primitive has one element per vertex");
}

/// Checks one skinned primitive: finite positions, JOINTS_n / WEIGHTS_n in pairs of VEC4 with
/// non-negative weights on joints below the skin's `njoints`.
void check_skinned_primitive(const tinygltf::Model& model, const std::map<std::string, int>& attrs,
                             const std::string& where, std::size_t njoints, LoadBudget& budget) {
  check_attribute_counts(model, attrs, where);
  if (attrs.count("POSITION")) {
    int comps = 0;
    const std::vector<double> pos =
        gltf::read_accessor(model, attrs.at("POSITION"), &comps, where + " POSITION", &budget);
    for (std::size_t i = 0; i < pos.size(); ++i)
      require(std::isfinite(pos[i]), where + " vertex " + std::to_string(i / 3), "position is not finite",
              "fix the mesh and export again");
  }
  for (int set = 0;; ++set) {
    const std::string jn = "JOINTS_" + std::to_string(set);
    const std::string wn = "WEIGHTS_" + std::to_string(set);
    if (!attrs.count(jn) && !attrs.count(wn)) break;
    require(attrs.count(jn) && attrs.count(wn), where, jn + " and " + wn + " must come together",
            "fix the file or export it again");
    int jc = 0;
    int wc = 0;
    const std::vector<double> jv = gltf::read_accessor(model, attrs.at(jn), &jc, where + " " + jn, &budget);
    const std::vector<double> wv = gltf::read_accessor(model, attrs.at(wn), &wc, where + " " + wn, &budget);
    require(jc == 4 && wc == 4 && jv.size() == wv.size(), where,
            jn + "/" + wn + " are not VEC4 of equal count", "fix the file or export it again");
    for (std::size_t i = 0; i < wv.size(); ++i) {
      const std::string vtx = where + " vertex " + std::to_string(i / 4);
      require(std::isfinite(wv[i]) && wv[i] >= 0, vtx, wn + " has a negative or non-finite weight",
              "fix the skin weights and export again");
      require(wv[i] == 0 || jv[i] < static_cast<double>(njoints), vtx,
              jn + " names joint " + format_number(jv[i]) + " but the skin has " + std::to_string(njoints) +
                  " joints",
              "fix the skin (every weighted joint index must be below the skin's joint count)");
    }
  }
}

/// Checks every node that has a mesh and a skin, and each of its mesh's primitives.
void check_skinned_nodes(const tinygltf::Model& model, const std::string& path, LoadReport& report,
                         LoadBudget& budget) {
  std::set<std::pair<std::size_t, std::size_t>> checked;  // (mesh, joint count): each checked once
  for (std::size_t n = 0; n < model.nodes.size(); ++n) {
    const tinygltf::Node& node = model.nodes[n];
    if (node.mesh < 0 || node.skin < 0) continue;
    const auto m = static_cast<std::size_t>(node.mesh);
    const auto s = static_cast<std::size_t>(node.skin);
    require(m < model.meshes.size() && s < model.skins.size(),
            path + ": node " + quote(gltf_node_name(model.nodes, n)),
            "names a mesh or skin that does not exist", "fix the file or export it again");
    if (!node.matrix.empty() || !node.translation.empty() || !node.rotation.empty() || !node.scale.empty())
      report.warnings.push_back("node " + quote(gltf_node_name(model.nodes, n)) +
                                " has a transform; it is ignored because the mesh is skinned (glTF rule)");
    const std::size_t njoints = model.skins[s].joints.size();
    if (!checked.insert({m, njoints}).second) continue;
    const tinygltf::Mesh& mesh = model.meshes[m];
    const std::string mesh_name = mesh.name.empty() ? "meshes[" + std::to_string(m) + "]" : mesh.name;
    for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
      const std::string where = path + ": mesh " + quote(mesh_name) + " primitive " + std::to_string(p);
      check_skinned_primitive(model, mesh.primitives[p].attributes, where, njoints, budget);
    }
  }
}

GltfInfo check_gltf(const tinygltf::Model& model, const std::string& path, LoadReport& report,
                    LoadBudget& budget) {
  GltfInfo info;
  unique_node_names(model.nodes, info);
  check_skins(model, path, info, budget);
  check_skinned_nodes(model, path, report, budget);
  for (std::size_t s = 0; s < model.skins.size(); ++s)
    if (model.skins[s].inverseBindMatrices < 0)
      report.warnings.push_back("skin " + std::to_string(s) +
                                " has no inverse bind matrices: identities (glTF default)");
  if (!info.file_names.empty())
    report.warnings.push_back(
        std::to_string(info.file_names.size()) + " node(s) share a name with another (first " +
        quote(info.file_names.begin()->second) + " -> " + quote(info.file_names.begin()->first) +
        "); joints are selected by the unique name (docs/skinning-io.md)");
  return info;
}

// ---------------------------------------------------------------------------------------------
// Scene nodes

struct Node {
  const aiNode* ai{nullptr};
  int parent{-1};
  int depth{0};
  std::string name;
  Affine local{Affine::Identity()};
  Affine world{Affine::Identity()};
};

struct Nodes {
  std::vector<Node> list;  ///< depth-first pre-order: parents before children
  std::unordered_map<std::string, std::vector<int>> by_name;
};

Nodes collect_nodes(const aiScene* scene, const std::string& path) {
  Nodes nodes;
  std::vector<std::pair<const aiNode*, int>> stack{{scene->mRootNode, -1}};
  while (!stack.empty()) {
    const auto [ai, parent] = stack.back();
    stack.pop_back();
    Node n;
    n.ai = ai;
    n.parent = parent;
    n.name = ai->mName.C_Str();
    const std::string what = path + ": node " + quote(n.name);
    require(is_affine(ai->mTransformation), what, "transform is projective", "fix the node's transform");
    n.local = to_affine(ai->mTransformation);
    require(n.local.matrix().allFinite(), what, "transform is not finite", "fix the node's transform");
    if (parent >= 0) {
      n.depth = nodes.list[static_cast<std::size_t>(parent)].depth + 1;
      n.world = nodes.list[static_cast<std::size_t>(parent)].world * n.local;
    } else {
      n.world = n.local;
    }
    const int index = static_cast<int>(nodes.list.size());
    nodes.by_name[n.name].push_back(index);
    nodes.list.push_back(std::move(n));
    for (unsigned c = ai->mNumChildren; c-- > 0;) stack.push_back({ai->mChildren[c], index});
  }
  return nodes;
}

// ---------------------------------------------------------------------------------------------
// Welding

struct Key {
  std::uint32_t x, y, z;
  bool operator==(const Key& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct KeyHash {
  std::size_t operator()(const Key& k) const {
    return (static_cast<std::size_t>(k.x) * 73856093u) ^ (static_cast<std::size_t>(k.y) * 19349663u) ^
           (static_cast<std::size_t>(k.z) * 83492791u);
  }
};

std::uint32_t float_bits(float v) {
  if (v == 0.0f) v = 0.0f;  // -0 == +0
  std::uint32_t u;
  std::memcpy(&u, &v, 4);
  return u;
}

// Welded id of each point (ids by first occurrence).
std::vector<int> weld(const std::vector<Eigen::Vector3f>& p, double tolerance) {
  const std::size_t n = p.size();
  std::vector<int> root(n);
  for (std::size_t i = 0; i < n; ++i) root[i] = static_cast<int>(i);
  auto find = [&](int i) {
    while (root[static_cast<std::size_t>(i)] != i) {
      root[static_cast<std::size_t>(i)] = root[static_cast<std::size_t>(root[static_cast<std::size_t>(i)])];
      i = root[static_cast<std::size_t>(i)];
    }
    return i;
  };
  if (tolerance <= 0) {
    std::unordered_map<Key, int, KeyHash> first;
    for (std::size_t i = 0; i < n; ++i) {
      const Key k{float_bits(p[i].x()), float_bits(p[i].y()), float_bits(p[i].z())};
      const auto [it, inserted] = first.emplace(k, static_cast<int>(i));
      if (!inserted) root[i] = it->second;
    }
  } else {
    struct Cell {
      long long x, y, z;
      bool operator==(const Cell& o) const { return x == o.x && y == o.y && z == o.z; }
    };
    struct CellHash {
      std::size_t operator()(const Cell& c) const {
        return static_cast<std::size_t>(c.x * 73856093LL ^ c.y * 19349663LL ^ c.z * 83492791LL);
      }
    };
    std::unordered_map<Cell, std::vector<int>, CellHash> grid;
    const double tol2 = tolerance * tolerance;
    for (std::size_t i = 0; i < n; ++i) {
      const Cell c{static_cast<long long>(std::floor(p[i].x() / tolerance)),
                   static_cast<long long>(std::floor(p[i].y() / tolerance)),
                   static_cast<long long>(std::floor(p[i].z() / tolerance))};
      for (long long dx = -1; dx <= 1; ++dx)
        for (long long dy = -1; dy <= 1; ++dy)
          for (long long dz = -1; dz <= 1; ++dz) {
            const auto it = grid.find(Cell{c.x + dx, c.y + dy, c.z + dz});
            if (it == grid.end()) continue;
            for (int j : it->second)
              if ((p[i] - p[static_cast<std::size_t>(j)]).cast<double>().squaredNorm() <= tol2) {
                const int a = find(static_cast<int>(i));
                const int b = find(j);
                if (a != b) root[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
              }
          }
      grid[c].push_back(static_cast<int>(i));
    }
  }
  std::vector<int> id(n, -1);
  std::vector<int> id_of_root(n, -1);
  int next = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto r = static_cast<std::size_t>(find(static_cast<int>(i)));
    if (id_of_root[r] < 0) id_of_root[r] = next++;
    id[i] = id_of_root[r];
  }
  return id;
}

// ---------------------------------------------------------------------------------------------
// Animation sampling

// Keys of an assimp channel as a key track (times in ticks; values as the sampler uses them).
KeyTrack<Eigen::Vector3d> key_track(const aiVectorKey* keys, unsigned n) {
  KeyTrack<Eigen::Vector3d> out;
  out.time.reserve(n);
  out.value.reserve(n);
  for (unsigned k = 0; k < n; ++k) {
    out.time.push_back(keys[k].mTime);
    out.value.emplace_back(keys[k].mValue.x, keys[k].mValue.y, keys[k].mValue.z);
  }
  return out;
}

KeyTrack<Eigen::Quaterniond> key_track(const aiQuatKey* keys, unsigned n) {
  KeyTrack<Eigen::Quaterniond> out;
  out.time.reserve(n);
  out.value.reserve(n);
  for (unsigned k = 0; k < n; ++k) {
    const aiQuaternion& x = keys[k].mValue;
    out.time.push_back(keys[k].mTime);
    out.value.push_back(Eigen::Quaterniond(x.w, x.x, x.y, x.z).normalized());
  }
  return out;
}

void check_keys(const aiNodeAnim* ch, const std::string& what) {
  for (unsigned k = 0; k < ch->mNumPositionKeys; ++k) {
    const auto& v = ch->mPositionKeys[k];
    require(std::isfinite(v.mTime) && std::isfinite(v.mValue.x) && std::isfinite(v.mValue.y) &&
                std::isfinite(v.mValue.z),
            what, "a translation key is not finite", "fix the animation and export again");
  }
  for (unsigned k = 0; k < ch->mNumRotationKeys; ++k) {
    const auto& v = ch->mRotationKeys[k];
    const double norm = std::sqrt(v.mValue.w * v.mValue.w + v.mValue.x * v.mValue.x +
                                  v.mValue.y * v.mValue.y + v.mValue.z * v.mValue.z);
    require(std::isfinite(v.mTime) && std::isfinite(norm) && norm > 1e-12, what,
            "a rotation key is not finite or zero", "fix the animation and export again");
  }
  for (unsigned k = 0; k < ch->mNumScalingKeys; ++k) {
    const auto& v = ch->mScalingKeys[k];
    require(std::isfinite(v.mTime) && std::isfinite(v.mValue.x) && std::isfinite(v.mValue.y) &&
                std::isfinite(v.mValue.z),
            what, "a scale key is not finite", "fix the animation and export again");
  }
}

double last_key_time(const aiNodeAnim* ch) {
  double t = 0;
  if (ch->mNumPositionKeys) t = std::max(t, ch->mPositionKeys[ch->mNumPositionKeys - 1].mTime);
  if (ch->mNumRotationKeys) t = std::max(t, ch->mRotationKeys[ch->mNumRotationKeys - 1].mTime);
  if (ch->mNumScalingKeys) t = std::max(t, ch->mScalingKeys[ch->mNumScalingKeys - 1].mTime);
  return t;
}

// ---------------------------------------------------------------------------------------------

struct MeshUse {
  int node{-1};
  const aiMesh* mesh{nullptr};
  std::string name;                  ///< for messages
  Affine to_scene;                   ///< file vertex -> rig rest (bind pose, scene space)
  std::vector<int> bone_joint_node;  ///< per aiBone: node index
};

/// The selected meshes merged, before welding: the file's vertices (in rig rest space), their
/// weights and the triangles.
struct FileMesh {
  std::vector<Eigen::Vector3f> pos;
  std::vector<std::vector<std::pair<int, float>>> w;
  std::vector<Eigen::Vector3i> tris;
  std::vector<float> mask;  ///< relaxation mask per vertex (1 where a mesh has none)
  std::string mask_source;  ///< where the first mesh with a mask had it ("" = none)
};

class Loader {
 public:
  Loader(const std::string& path, const LoadOptions& options, LoadReport& report)
      : path_(path), options_(options), report_(report), budget_(path, 0) {}

  Rig load();

 private:
  void read_with_assimp();
  int node_named(const std::string& name, const std::string& what) const;
  Rig load_skeleton();
  void select_meshes();
  void bind_pose();
  void bind_pose_unskinned();
  std::vector<int> unskinned_skeleton() const;
  void bind_mesh(MeshUse& m, std::map<int, std::string>& bind_source);
  void build_joints();
  void build_mesh();
  void check_orientation();
  void append_mesh(const MeshUse& m, bool weights, FileMesh& file);
  std::vector<int> append_triangles(const MeshUse& m, FileMesh& file) const;
  void append_weights(const MeshUse& m, const std::vector<int>& local_to_out, FileMesh& file) const;
  void append_mask(const MeshUse& m, const std::vector<int>& local_to_out, FileMesh& file) const;
  void weld_mask(const FileMesh& file);
  std::vector<int> weld_file_mesh(const FileMesh& file);
  void weld_weights(const FileMesh& file, const std::vector<int>& first);
  void build_clips();
  std::vector<char> animated_nodes() const;
  ClipKeys clip_keys(const std::vector<const aiNodeAnim*>& channel, const std::vector<char>& relevant,
                     double last, double tps) const;

  const std::string& path_;
  const LoadOptions& options_;
  LoadReport& report_;
  LoadBudget budget_;  ///< glTF: what the readers decode from the file's declared sizes
  GltfInfo gltf_;
  Assimp::Importer importer_;
  std::unique_ptr<aiScene> own_scene_;  ///< glTF: the scene built from the tinygltf model
  const aiScene* scene_{nullptr};
  Nodes nodes_;
  std::vector<MeshUse> meshes_;
  bool skinned_{false};
  std::map<int, Affine> bind_world_;  ///< node -> world transform at the bind pose (bones)
  std::vector<int> joint_node_;       ///< joint -> node
  std::vector<int> node_joint_;       ///< node -> joint or -1
  Rig rig_;
};

int Loader::node_named(const std::string& name, const std::string& what) const {
  const auto it = nodes_.by_name.find(name);
  require(it != nodes_.by_name.end(), what, "names no node of the scene",
          "fix the skeleton (every bone must be a node) and export again");
  require(it->second.size() == 1, what, "name is shared by " + std::to_string(it->second.size()) + " nodes",
          "give every joint a unique name and export again");
  return it->second.front();
}

void Loader::select_meshes() {
  std::set<const aiMesh*> seen;
  std::vector<std::string> all_names;
  std::vector<MeshUse> candidates;
  for (std::size_t n = 0; n < nodes_.list.size(); ++n) {
    const aiNode* ai = nodes_.list[n].ai;
    for (unsigned k = 0; k < ai->mNumMeshes; ++k) {
      const unsigned mi = ai->mMeshes[k];
      require(mi < scene_->mNumMeshes, path_ + ": node " + quote(nodes_.list[n].name), "names a missing mesh",
              "fix the file");
      const aiMesh* mesh = scene_->mMeshes[mi];
      std::string name = mesh->mName.length ? mesh->mName.C_Str() : "mesh " + std::to_string(mi);
      all_names.push_back(name);
      if (!seen.insert(mesh).second) {
        report_.warnings.push_back("mesh " + quote(name) +
                                   " is used by several nodes; only its first use is loaded");
        continue;
      }
      if (!options_.mesh.empty() && options_.mesh != name && options_.mesh != nodes_.list[n].name) continue;
      bool triangles = false;
      for (unsigned f = 0; f < mesh->mNumFaces && !triangles; ++f)
        triangles = mesh->mFaces[f].mNumIndices == 3;
      if (!triangles) {
        report_.warnings.push_back("mesh " + quote(name) + " has no triangles (points or lines); skipped");
        continue;
      }
      MeshUse use;
      use.node = static_cast<int>(n);
      use.mesh = mesh;
      use.name = name;
      candidates.push_back(std::move(use));
    }
  }
  if (!options_.mesh.empty()) {
    std::string list;
    for (const std::string& s : all_names) list += (list.empty() ? "" : ", ") + quote(s);
    require(!candidates.empty(), path_ + ": LoadOptions::mesh",
            "no triangle mesh is named " + quote(options_.mesh),
            "choose one of: " + (list.empty() ? std::string("(no meshes)") : list));
  }
  require(!candidates.empty(), path_, "has no triangle mesh",
          "no skin: isokit-skin needs a mesh with a skeleton; export the character's mesh with its armature");
  for (const MeshUse& m : candidates) skinned_ = skinned_ || m.mesh->mNumBones > 0;
  for (MeshUse& m : candidates) {
    if (skinned_ && m.mesh->mNumBones == 0) {
      report_.warnings.push_back("mesh " + quote(m.name) +
                                 " has no skin; skipped (only skinned meshes deform)");
      continue;
    }
    meshes_.push_back(std::move(m));
  }
}

/// An animation-only file: the skeleton (its animated nodes and the nodes between them) at the
/// file's node pose, and its clips; no mesh.
Rig Loader::load_skeleton() {
  std::set<std::string> animated;
  for (unsigned a = 0; a < scene_->mNumAnimations; ++a)
    for (unsigned c = 0; c < scene_->mAnimations[a]->mNumChannels; ++c)
      animated.insert(scene_->mAnimations[a]->mChannels[c]->mNodeName.C_Str());
  for (std::size_t i = 0; i < nodes_.list.size(); ++i)
    if (animated.count(nodes_.list[i].name)) bind_world_[static_cast<int>(i)] = nodes_.list[i].world;
  require(!bind_world_.empty(), path_, "has no animated node (no clip)",
          "give a file with a skeleton and its animation");
  build_joints();
  build_clips();
  require(!rig_.clips.empty(), path_, "has no animation that moves its skeleton",
          "give a file with an animation (a clip of the skeleton)");
  return std::move(rig_);
}

void Loader::bind_pose() {
  if (!skinned_) {
    bind_pose_unskinned();
    return;
  }
  std::map<int, std::string> bind_source;
  for (MeshUse& m : meshes_) bind_mesh(m, bind_source);
}

void Loader::bind_pose_unskinned() {
  // A mesh and a skeleton without weights: the skeleton is the glTF skins' joints, or else
  // unskinned_skeleton().
  std::vector<int> skeleton;
  for (const std::string& name : gltf_.skin_joint_names) {
    const auto it = nodes_.by_name.find(name);
    if (it != nodes_.by_name.end() && it->second.size() == 1) skeleton.push_back(it->second.front());
  }
  if (skeleton.empty()) skeleton = unskinned_skeleton();
  require(!skeleton.empty(), path_, "no skin: isokit-skin needs a mesh with a skeleton",
          "export the character with its armature and skin weights (glTF: a skin on the mesh node)");
  for (int node : skeleton) bind_world_[node] = nodes_.list[static_cast<std::size_t>(node)].world;
  for (MeshUse& m : meshes_) m.to_scene = nodes_.list[static_cast<std::size_t>(m.node)].world;
  report_.warnings.push_back(
      "the file has no skin weights: loaded with empty weights (heat weights will be computed)");
}

/// The nodes that are neither meshes, cameras, lights, roots nor ancestors of meshes, and that are
/// animated or chained to another such node.
std::vector<int> Loader::unskinned_skeleton() const {
  std::vector<int> skeleton;
  const std::size_t n = nodes_.list.size();
  std::vector<char> excluded(n, 0);
  std::set<std::string> special;
  for (unsigned c = 0; c < scene_->mNumCameras; ++c) special.insert(scene_->mCameras[c]->mName.C_Str());
  for (unsigned l = 0; l < scene_->mNumLights; ++l) special.insert(scene_->mLights[l]->mName.C_Str());
  for (std::size_t i = 0; i < n; ++i) {
    const Node& nd = nodes_.list[i];
    if (nd.ai->mNumMeshes > 0)
      for (int p = static_cast<int>(i); p >= 0; p = nodes_.list[static_cast<std::size_t>(p)].parent)
        excluded[static_cast<std::size_t>(p)] = 1;
    if (special.count(nd.name) || nd.parent < 0) excluded[i] = 1;
  }
  std::set<std::string> animated;
  for (unsigned a = 0; a < scene_->mNumAnimations; ++a)
    for (unsigned c = 0; c < scene_->mAnimations[a]->mNumChannels; ++c)
      animated.insert(scene_->mAnimations[a]->mChannels[c]->mNodeName.C_Str());
  std::vector<char> chained(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const int p = nodes_.list[i].parent;
    if (!excluded[i] && p >= 0 && !excluded[static_cast<std::size_t>(p)])
      chained[i] = chained[static_cast<std::size_t>(p)] = 1;
  }
  for (std::size_t i = 0; i < n; ++i)
    if (!excluded[i] && (chained[i] || animated.count(nodes_.list[i].name)))
      skeleton.push_back(static_cast<int>(i));
  return skeleton;
}

/// The bind pose of one skinned mesh: its bones' nodes, its bind-shape transform and the bones'
/// bind world transforms (which must agree between meshes; `bind_source` names the first mesh).
void Loader::bind_mesh(MeshUse& m, std::map<int, std::string>& bind_source) {
  const aiMesh* mesh = m.mesh;
  std::vector<Affine> offsets(mesh->mNumBones);
  int top = -1;
  for (unsigned b = 0; b < mesh->mNumBones; ++b) {
    const aiBone* bone = mesh->mBones[b];
    const std::string what = path_ + ": mesh " + quote(m.name) + " bone " + quote(bone->mName.C_Str());
    const int node = node_named(bone->mName.C_Str(), what);
    m.bone_joint_node.push_back(node);
    require(is_affine(bone->mOffsetMatrix), what, "inverse bind matrix is projective", "fix the bind pose");
    offsets[b] = to_affine(bone->mOffsetMatrix);
    require(offsets[b].matrix().allFinite(), what, "inverse bind matrix is not finite", "fix the bind pose");
    require(std::abs(offsets[b].linear().determinant()) > 1e-12, what, "inverse bind matrix is singular",
            "fix the bind pose");
    if (top < 0 ||
        nodes_.list[static_cast<std::size_t>(node)].depth <
            nodes_.list[static_cast<std::size_t>(m.bone_joint_node[static_cast<std::size_t>(top)])].depth)
      top = static_cast<int>(b);
  }
  // The mesh's bind-shape transform: where its top bone's node is now, times its inverse bind.
  const int top_node = m.bone_joint_node[static_cast<std::size_t>(top)];
  m.to_scene = nodes_.list[static_cast<std::size_t>(top_node)].world * offsets[static_cast<std::size_t>(top)];
  // World times inverse bind is the identity up to the file's float rounding in the usual case
  // (glTF, and FBX/COLLADA meshes at the scene origin): keep the file's positions bit-exact then.
  const double length = nodes_.list[static_cast<std::size_t>(top_node)].world.translation().norm();
  if (nearly_identity(m.to_scene, length)) m.to_scene = Affine::Identity();
  for (unsigned b = 0; b < mesh->mNumBones; ++b) {
    const int node = m.bone_joint_node[b];
    const Affine world = m.to_scene * offsets[b].inverse(Eigen::Affine);
    const auto it = bind_world_.find(node);
    if (it == bind_world_.end()) {
      bind_world_[node] = world;
      bind_source[node] = m.name;
    } else {
      require(nearly_equal(it->second, world),
              path_ + ": joint " + quote(nodes_.list[static_cast<std::size_t>(node)].name),
              "meshes " + quote(bind_source[node]) + " and " + quote(m.name) + " bind it at different poses",
              "load one mesh (LoadOptions::mesh) or re-export the meshes with one bind pose");
    }
  }
}

void Loader::build_joints() {
  const std::size_t n = nodes_.list.size();
  std::vector<char> is_joint(n, 0);
  for (const auto& [node, world] : bind_world_) is_joint[static_cast<std::size_t>(node)] = 1;
  // Nodes between two bones join the skeleton; nodes above the top bones do not (their
  // transform is folded into the root joints).
  for (const auto& [node, world] : bind_world_) {
    std::vector<int> between;
    int p = nodes_.list[static_cast<std::size_t>(node)].parent;
    while (p >= 0 && !bind_world_.count(p)) {
      between.push_back(p);
      p = nodes_.list[static_cast<std::size_t>(p)].parent;
    }
    if (p >= 0)
      for (int b : between) is_joint[static_cast<std::size_t>(b)] = 1;
  }
  node_joint_.assign(n, -1);
  std::vector<Affine> world_bind;
  int pose_differs = 0;
  std::string first_differs;
  for (std::size_t i = 0; i < n; ++i) {
    if (!is_joint[i]) continue;
    const Node& nd = nodes_.list[i];
    int parent = -1;
    for (int p = nd.parent; p >= 0 && parent < 0; p = nodes_.list[static_cast<std::size_t>(p)].parent)
      parent = node_joint_[static_cast<std::size_t>(p)];
    Joint joint;
    joint.name = nd.name;
    const auto file_name = gltf_.file_names.find(nd.name);
    if (file_name != gltf_.file_names.end()) joint.file_name = file_name->second;
    joint.parent = parent;
    Affine wb;
    const auto it = bind_world_.find(static_cast<int>(i));
    if (it != bind_world_.end()) {
      wb = it->second;
    } else {  // a node between bones: rigidly attached to its parent joint as in the node pose
      const int pn = joint_node_[static_cast<std::size_t>(parent)];
      wb = world_bind[static_cast<std::size_t>(parent)] *
           (nodes_.list[static_cast<std::size_t>(pn)].world.inverse(Eigen::Affine) * nd.world);
    }
    if (!nearly_equal(wb, nd.world)) {
      if (pose_differs++ == 0) first_differs = nd.name;
    }
    joint.rest_local =
        parent < 0 ? wb : Affine(world_bind[static_cast<std::size_t>(parent)].inverse(Eigen::Affine) * wb);
    joint.inverse_bind = wb.inverse(Eigen::Affine);
    const std::string what = path_ + ": joint " + quote(nd.name);
    require(joint.rest_local.matrix().allFinite() && joint.inverse_bind.matrix().allFinite(), what,
            "bind transform is not finite", "fix the bind pose and export again");
    require(!has_shear(joint.rest_local), what, "rest transform has shear (non-uniform scale under rotation)",
            "apply the scale of the armature and its bones in the DCC tool and export again");
    node_joint_[i] = static_cast<int>(rig_.joints.size());
    joint_node_.push_back(static_cast<int>(i));
    world_bind.push_back(wb);
    rig_.joints.push_back(std::move(joint));
  }
  if (pose_differs > 0)
    report_.warnings.push_back(
        std::to_string(pose_differs) + " joint(s) (first " + quote(first_differs) +
        ") are posed away from the bind pose in the file; the rest pose is the bind pose, "
        "clips use the file's node transforms");
}

/// Reports (never refuses) faces whose orientation disagrees with a neighbour's, and a closed
/// mesh that is inside out; separate parts, open borders and non-manifold edges are `info`'s.
void Loader::check_orientation() {
  const SurfaceReport s = inspect_surface(rig_.rest, rig_.triangles);
  if (s.inconsistent_edges > 0)
    report_.warnings.push_back(std::to_string(s.inconsistent_edges) +
                               " edge(s) are traversed in the same direction by both their triangles: face "
                               "orientation is not consistent (flip those faces in the DCC tool)");
  else if (s.boundary_edges == 0 && s.nonmanifold_edges == 0 && s.volume < 0)
    report_.warnings.push_back(
        "the closed mesh is inside out (negative volume): flip its faces in the DCC tool");
}

void Loader::build_mesh() {
  const bool weights = skinned_ && !options_.ignore_weights;
  FileMesh file;
  rig_.output.primitive_offsets = {0};
  for (const MeshUse& m : meshes_) append_mesh(m, weights, file);
  const std::size_t nout = file.pos.size();
  const std::vector<int> first = weld_file_mesh(file);
  const int nw = static_cast<int>(first.size());
  if (weights) weld_weights(file, first);
  weld_mask(file);
  report_.meshes = static_cast<int>(meshes_.size());
  report_.file_vertices = static_cast<int>(nout);
  report_.welded_vertices = nw;
  report_.weights_from_file = weights;
}

/// Appends one mesh's triangles, used vertices and (when `weights`) their weights to `file`.
void Loader::append_mesh(const MeshUse& m, bool weights, FileMesh& file) {
  const std::vector<int> local_to_out = append_triangles(m, file);
  const int unused = static_cast<int>(std::count(local_to_out.begin(), local_to_out.end(), -1));
  if (unused > 0)
    report_.warnings.push_back("mesh " + quote(m.name) + ": " + std::to_string(unused) +
                               " vertices used by no triangle were dropped");
  rig_.output.primitive_offsets.push_back(static_cast<int>(file.tris.size()));
  file.w.resize(file.pos.size());
  if (weights) append_weights(m, local_to_out, file);
  append_mask(m, local_to_out, file);
}

/// Appends the relaxation mask of `m`'s used vertices (LoadOptions::mask_color_set, else the glTF
/// mask attribute carried in colour set gltf::kMaskColorSet; 1 where the mesh has neither).
void Loader::append_mask(const MeshUse& m, const std::vector<int>& local_to_out, FileMesh& file) const {
  const aiMesh* mesh = m.mesh;
  const bool chosen = options_.mask.color_set >= 0;
  const unsigned set = chosen ? static_cast<unsigned>(options_.mask.color_set) : gltf::kMaskColorSet;
  const bool has =
      set < AI_MAX_NUMBER_OF_COLOR_SETS && mesh->HasVertexColors(set) && (chosen || own_scene_ != nullptr);
  file.mask.resize(file.pos.size(), 1.f);
  if (!has) return;
  if (file.mask_source.empty())
    file.mask_source =
        chosen ? "vertex colour set " + std::to_string(set) + " channel " + "rgba"[options_.mask.channel]
               : "attribute " + options_.mask.attribute;
  for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
    const int o = local_to_out[v];
    if (o < 0) continue;
    const aiColor4D& c = mesh->mColors[set][v];
    const float x = options_.mask.channel == 0   ? c.r
                    : options_.mask.channel == 1 ? c.g
                    : options_.mask.channel == 2 ? c.b
                                                 : c.a;
    require(std::isfinite(x), path_ + ": mesh " + quote(m.name) + " vertex " + std::to_string(v),
            "relaxation mask (" + file.mask_source + ") is not finite",
            "paint values in [0, 1] and export again");
    file.mask[static_cast<std::size_t>(o)] = std::clamp(x, 0.f, 1.f);
  }
}

/// The welded relaxation mask: the smallest value of the merged copies (a seam painted rigid on
/// one side stays rigid); none when no mesh had one.
void Loader::weld_mask(const FileMesh& file) {
  report_.mask_source = file.mask_source;
  if (file.mask_source.empty()) return;
  rig_.relax_mask.assign(static_cast<std::size_t>(rig_.rest.rows()), 1.f);
  for (std::size_t i = 0; i < file.mask.size(); ++i) {
    float& m = rig_.relax_mask[static_cast<std::size_t>(rig_.output.to_welded[i])];
    m = std::min(m, file.mask[i]);
  }
}

/// Appends the triangles of `m` and the vertices they use (in rig rest space, in the file's
/// vertex order: a point cache of the output vertices fits the file); returns the mesh's
/// vertex -> output vertex map (-1: unused).
std::vector<int> Loader::append_triangles(const MeshUse& m, FileMesh& file) const {
  const aiMesh* mesh = m.mesh;
  std::vector<int> local_to_out(mesh->mNumVertices, -1);
  for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
    const aiFace& face = mesh->mFaces[f];
    if (face.mNumIndices != 3) continue;
    for (int k = 0; k < 3; ++k) {
      const unsigned v = face.mIndices[k];
      require(v < mesh->mNumVertices, path_ + ": mesh " + quote(m.name) + " face " + std::to_string(f),
              "vertex index out of range", "fix the mesh");
      local_to_out[v] = 0;  // used
    }
  }
  for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
    if (local_to_out[v] < 0) continue;
    const Eigen::Vector3d p =
        m.to_scene * Eigen::Vector3d(mesh->mVertices[v].x, mesh->mVertices[v].y, mesh->mVertices[v].z);
    require(p.allFinite(), path_ + ": mesh " + quote(m.name) + " vertex " + std::to_string(v),
            "position is not finite", "fix the mesh and export again");
    local_to_out[v] = static_cast<int>(file.pos.size());
    file.pos.push_back(p.cast<float>());
  }
  for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
    const aiFace& face = mesh->mFaces[f];
    if (face.mNumIndices == 3)
      file.tris.emplace_back(local_to_out[face.mIndices[0]], local_to_out[face.mIndices[1]],
                             local_to_out[face.mIndices[2]]);
  }
  return local_to_out;
}

/// Appends the bone weights of `m` to its output vertices; every used vertex needs one.
void Loader::append_weights(const MeshUse& m, const std::vector<int>& local_to_out, FileMesh& file) const {
  const aiMesh* mesh = m.mesh;
  for (unsigned b = 0; b < mesh->mNumBones; ++b) {
    const aiBone* bone = mesh->mBones[b];
    const int joint = node_joint_[static_cast<std::size_t>(m.bone_joint_node[b])];
    for (unsigned k = 0; k < bone->mNumWeights; ++k) {
      const aiVertexWeight& vw = bone->mWeights[k];
      const std::string what = path_ + ": mesh " + quote(m.name) + " vertex " + std::to_string(vw.mVertexId);
      require(vw.mVertexId < mesh->mNumVertices, what,
              "bone " + quote(bone->mName.C_Str()) + " weights a missing vertex",
              "fix the skin and export again");
      require(std::isfinite(vw.mWeight) && vw.mWeight >= 0, what,
              "weight of bone " + quote(bone->mName.C_Str()) + " is negative or not finite",
              "fix the skin weights and export again");
      const int o = local_to_out[vw.mVertexId];
      if (o >= 0 && vw.mWeight > 0) file.w[static_cast<std::size_t>(o)].push_back({joint, vw.mWeight});
    }
  }
  for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
    const int o = local_to_out[v];
    require(
        o < 0 || !file.w[static_cast<std::size_t>(o)].empty(),
        path_ + ": mesh " + quote(m.name) + " vertex " + std::to_string(v), "has no skin weight",
        "weight every vertex in the DCC tool, or set LoadOptions::ignore_weights to compute heat weights");
  }
}

/// Welds the output vertices into the deformation mesh (`rig_.rest`, `rig_.triangles`, the
/// output map); returns each welded vertex's first output vertex.
std::vector<int> Loader::weld_file_mesh(const FileMesh& file) {
  const std::size_t nout = file.pos.size();
  double tolerance = 0;
  if (options_.weld_tolerance > 0) {
    Eigen::AlignedBox3f box;
    for (const auto& p : file.pos) box.extend(p);
    tolerance = options_.weld_tolerance * static_cast<double>(box.diagonal().norm());
  }
  rig_.output.to_welded = weld(file.pos, tolerance);
  int nw = 0;
  for (int id : rig_.output.to_welded) nw = std::max(nw, id + 1);
  rig_.rest.resize(nw, 3);
  std::vector<int> first(static_cast<std::size_t>(nw), -1);
  for (std::size_t i = 0; i < nout; ++i) {
    const auto w = static_cast<std::size_t>(rig_.output.to_welded[i]);
    if (first[w] < 0) {
      first[w] = static_cast<int>(i);
      rig_.rest.row(static_cast<Eigen::Index>(w)) = file.pos[i].transpose();
    }
  }
  rig_.output.triangles.resize(static_cast<Eigen::Index>(file.tris.size()), 3);
  std::vector<Eigen::Vector3i> welded_tris;
  for (std::size_t f = 0; f < file.tris.size(); ++f) {
    rig_.output.triangles.row(static_cast<Eigen::Index>(f)) = file.tris[f].transpose();
    Eigen::Vector3i t;
    for (int k = 0; k < 3; ++k) t[k] = rig_.output.to_welded[static_cast<std::size_t>(file.tris[f][k])];
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
      ++report_.dropped_triangles;
    else
      welded_tris.push_back(t);
  }
  rig_.triangles.resize(static_cast<Eigen::Index>(welded_tris.size()), 3);
  for (std::size_t f = 0; f < welded_tris.size(); ++f)
    rig_.triangles.row(static_cast<Eigen::Index>(f)) = welded_tris[f].transpose();
  if (report_.dropped_triangles > 0)
    report_.warnings.push_back(std::to_string(report_.dropped_triangles) +
                               " triangle(s) collapse when welded; left out of the deformation mesh");
  return first;
}

/// Welded weights: the mean of the merged vertices' weights, normalised (`first`: see
/// weld_file_mesh).
void Loader::weld_weights(const FileMesh& file, const std::vector<int>& first) {
  const std::size_t nout = file.pos.size();
  const int nw = static_cast<int>(first.size());
  std::vector<std::map<int, double>> acc(static_cast<std::size_t>(nw));
  std::vector<int> members(static_cast<std::size_t>(nw), 0);
  int disagree = 0;
  auto as_map = [&](std::size_t i) {
    std::map<int, double> m;
    double sum = 0;
    for (const auto& [j, x] : file.w[i]) sum += x;
    for (const auto& [j, x] : file.w[i]) m[j] += x / sum;
    return m;
  };
  for (std::size_t i = 0; i < nout; ++i) {
    const auto w = static_cast<std::size_t>(rig_.output.to_welded[i]);
    const std::map<int, double> m = as_map(i);
    if (members[w] > 0) {
      const std::map<int, double> ref = as_map(static_cast<std::size_t>(first[w]));
      bool same = ref.size() == m.size();
      for (auto a = ref.begin(), b = m.begin(); same && a != ref.end(); ++a, ++b)
        same = a->first == b->first && std::abs(a->second - b->second) <= 1e-5;
      if (!same) ++disagree;
    }
    for (const auto& [j, x] : m) acc[w][j] += x;
    ++members[w];
  }
  if (disagree > 0)
    report_.warnings.push_back(std::to_string(disagree) +
                               " welded vertex copies had different weights; their mean is used");
  SkinWeights& sw = rig_.weights;
  sw.offsets.assign(1, 0);
  for (std::size_t w = 0; w < static_cast<std::size_t>(nw); ++w) {
    for (const auto& [j, x] : acc[w]) {
      sw.joints.push_back(j);
      sw.weights.push_back(static_cast<float>(x / members[w]));
    }
    sw.offsets.push_back(static_cast<int>(sw.joints.size()));
  }
  normalize_weights(sw, nw, options_.min_weight, path_);
  for (int v = 0; v < nw; ++v) report_.max_influences = std::max(report_.max_influences, sw.count(v));
}

void Loader::build_clips() {
  if (!options_.clips) return;
  const std::size_t n = nodes_.list.size();
  const std::vector<char> relevant = animated_nodes();
  std::set<std::string> used_names;
  for (unsigned a = 0; a < scene_->mNumAnimations; ++a) {
    const aiAnimation* anim = scene_->mAnimations[a];
    std::string name = anim->mName.length ? anim->mName.C_Str() : "animation_" + std::to_string(a);
    if (used_names.count(name)) name += "_" + std::to_string(a);
    used_names.insert(name);
    const double tps = anim->mTicksPerSecond > 0 ? anim->mTicksPerSecond : 25.0;
    std::vector<const aiNodeAnim*> channel(n, nullptr);
    double last = 0;
    bool any = false;
    for (unsigned c = 0; c < anim->mNumChannels; ++c) {
      const aiNodeAnim* ch = anim->mChannels[c];
      const auto it = nodes_.by_name.find(ch->mNodeName.C_Str());
      if (it == nodes_.by_name.end()) continue;
      for (int node : it->second) {
        if (!relevant[static_cast<std::size_t>(node)]) continue;
        check_keys(ch, path_ + ": animation " + quote(name) + " channel " + quote(ch->mNodeName.C_Str()));
        if (channel[static_cast<std::size_t>(node)] == nullptr) channel[static_cast<std::size_t>(node)] = ch;
        last = std::max(last, last_key_time(ch) / tps);
        any = true;
      }
    }
    if (!any) {
      report_.warnings.push_back("animation " + quote(name) + " moves no joint; skipped");
      continue;
    }
    // A key time far beyond any animation (found by fuzzing: 1.4e32 s) would overflow the frame
    // count and allocate without bound.
    require(std::isfinite(last) && last * options_.fps <= kMaxClipFrames,
            path_ + ": animation " + quote(name),
            "lasts " + format_number(last) + " s, more than " + std::to_string(kMaxClipFrames) +
                " frames at " + format_number(options_.fps) + " fps",
            "fix the key times in the file (or sample it at a lower --fps)");
    // The clip keeps its keys; frames are sampled when a command needs them (clip_frames). A
    // valid clip of hours (found by fuzzing: a 3.5 KB file whose two keys lie 14 hours apart) is
    // listed at once and refused, with the fix, only by a command that samples it.
    Clip clip;
    clip.name = name;
    clip.fps = options_.fps;
    auto keys = std::make_shared<ClipKeys>(clip_keys(channel, relevant, last, tps));
    budget_.charge(keys->bytes(), "animation " + quote(name) + " keys");
    clip.keys = std::move(keys);
    const double samples =
        static_cast<double>(clip.frame_count()) * double(std::max<std::size_t>(rig_.joints.size(), 1));
    if (samples > static_cast<double>(kMaxClipSamples))
      report_.warnings.push_back("animation " + quote(name) + " lasts " + format_number(last) +
                                 " s: " + format_number(samples) + " joint transforms at " +
                                 format_number(options_.fps) + " fps, more than the " +
                                 std::to_string(kMaxClipSamples) +
                                 " a clip may be sampled into (512 MiB); commands that need its frames "
                                 "refuse it (sample it at a lower --fps or cut it)");
    rig_.clips.push_back(std::move(clip));
  }
}

/// Nodes whose animated transform matters: the joints and every ancestor of a root joint.
std::vector<char> Loader::animated_nodes() const {
  std::vector<char> relevant(nodes_.list.size(), 0);
  for (std::size_t j = 0; j < joint_node_.size(); ++j) {
    int p = joint_node_[j];
    relevant[static_cast<std::size_t>(p)] = 1;
    if (rig_.joints[j].parent < 0)
      for (p = nodes_.list[static_cast<std::size_t>(p)].parent; p >= 0;
           p = nodes_.list[static_cast<std::size_t>(p)].parent)
        relevant[static_cast<std::size_t>(p)] = 1;
  }
  return relevant;
}

/// The key tracks of one animation over the relevant nodes (`channel`: per node, its channel or
/// null for the node's own transform; `last`: the last key in seconds; `tps`: ticks per second).
ClipKeys Loader::clip_keys(const std::vector<const aiNodeAnim*>& channel, const std::vector<char>& relevant,
                           double last, double tps) const {
  ClipKeys keys;
  keys.ticks_per_second = tps;
  keys.last_seconds = last;
  // Only the relevant nodes are kept, in the same (parents-first) order.
  std::vector<int> compact(nodes_.list.size(), -1);
  for (std::size_t i = 0; i < nodes_.list.size(); ++i) {
    if (!relevant[i]) continue;
    compact[i] = static_cast<int>(keys.nodes.size());
    ClipKeys::Node node;
    node.relevant = true;
    const int p = nodes_.list[i].parent;
    node.parent = p >= 0 ? compact[static_cast<std::size_t>(p)] : -1;
    node.local = nodes_.list[i].local;
    node.rest = decompose(node.local);
    if (const aiNodeAnim* ch = channel[i]) {
      node.keyed = true;
      node.translation = key_track(ch->mPositionKeys, ch->mNumPositionKeys);
      node.rotation = key_track(ch->mRotationKeys, ch->mNumRotationKeys);
      node.scale = key_track(ch->mScalingKeys, ch->mNumScalingKeys);
    }
    keys.nodes.push_back(std::move(node));
  }
  for (std::size_t j = 0; j < joint_node_.size(); ++j) {
    keys.joint_node.push_back(compact[static_cast<std::size_t>(joint_node_[j])]);
    keys.joint_parent.push_back(rig_.joints[j].parent);
  }
  return keys;
}

/// FBX, COLLADA and the other formats: assimp's scene.
void Loader::read_with_assimp() {
  importer_.SetPropertyBool(AI_CONFIG_IMPORT_FBX_PRESERVE_PIVOTS, false);
  try {
    scene_ = importer_.ReadFile(path_, aiProcess_Triangulate | aiProcess_ValidateDataStructure);
    const std::string error = importer_.GetErrorString();
    if (scene_ == nullptr && error.rfind("Validation failed", 0) == 0) {
      // assimp's own consistency check is stricter than the rig needs (e.g. key times past the
      // animation's declared duration); the loader checks what it uses itself.
      scene_ = importer_.ReadFile(path_, aiProcess_Triangulate);
      if (scene_ != nullptr) report_.warnings.push_back("assimp: " + error + " (loaded without that check)");
    }
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(path_ + ": assimp failed: " + e.what() +
                     "; check that it is a valid glTF 2.0, FBX or COLLADA file");
  }
  require(scene_ != nullptr && scene_->mRootNode != nullptr, path_,
          std::string("assimp cannot read it: ") + importer_.GetErrorString(),
          "check that it is a valid glTF 2.0, FBX or COLLADA file (export it again)");
}

Rig Loader::load() {
  rig_.name = path_;
  require(options_.fps > 0 && std::isfinite(options_.fps), path_ + ": LoadOptions::fps",
          "must be > 0 (got " + format_number(options_.fps) + ")", "pass a positive frame rate such as 30");
  require(options_.weld_tolerance >= 0 && std::isfinite(options_.weld_tolerance),
          path_ + ": LoadOptions::weld_tolerance",
          "must be >= 0 (got " + format_number(options_.weld_tolerance) + ")", "pass 0 for exact welding");
  require(options_.mask.color_set >= -1 && options_.mask.color_set < int(AI_MAX_NUMBER_OF_COLOR_SETS),
          path_ + ": LoadOptions::mask.color_set",
          "must be -1 .. 7 (got " + std::to_string(options_.mask.color_set) + ")",
          "pass the vertex-colour set of the mask, or -1 for none");
  require(options_.mask.channel >= 0 && options_.mask.channel <= 3, path_ + ": LoadOptions::mask.channel",
          "must be 0 .. 3 (got " + std::to_string(options_.mask.channel) + ")",
          "0 = red, 1 = green, 2 = blue, 3 = alpha");
  std::error_code ec;
  require(fs::exists(path_, ec), path_, "file does not exist", "check the path");
  require(fs::is_regular_file(path_, ec), path_, "is not a regular file", "give the path of a rig file");
  const std::string ext = gltf::extension(path_);
  report_.format = ext.empty() ? std::string() : ext.substr(1);
  if (ext == ".gltf" || ext == ".glb") {
    const tinygltf::Model model = gltf::read_model(path_, &report_.warnings, &budget_);
    gltf_ = check_gltf(model, path_, report_, budget_);
    own_scene_ = gltf::to_ai_scene(model, gltf_.node_names, path_, &budget_, options_.mask.attribute,
                                   &report_.warnings);
    scene_ = own_scene_.get();
  } else {
    const auto bytes = fs::file_size(path_, ec);
    budget_.add_input(ec ? 0 : bytes);
    read_with_assimp();
  }
  nodes_ = collect_nodes(scene_, path_);
  if (options_.skeleton_only) return load_skeleton();
  require(!(scene_->mFlags & AI_SCENE_FLAGS_INCOMPLETE), path_, "the scene is incomplete (no mesh)",
          "export the file again with its meshes (or read it as a clip file: --clip-file)");
  select_meshes();
  bind_pose();
  build_joints();
  build_mesh();
  check_orientation();
  build_clips();
  validate(rig_);
  return std::move(rig_);
}

}  // namespace

Rig load_rig(const std::string& path, const LoadOptions& options, LoadReport* report) {
  LoadReport local;
  LoadReport& r = report ? *report : local;
  r = LoadReport{};
  const std::string ext = gltf::extension(path);
  if (ext == ".gltf" || ext == ".glb" || !options.isolate_importer || !io::isolation_available()) {
    Loader loader(path, options, r);
    return loader.load();
  }
  // assimp in a child process: its aborts and crashes on malformed files end the child only.
  LoadOptions in_child = options;
  in_child.isolate_importer = false;
  const std::string bytes = io::run_isolated(
      [&] {
        LoadReport child_report;
        Loader loader(path, in_child, child_report);
        const Rig rig = loader.load();
        return io::encode_rig(rig, child_report);
      },
      io::IsolationLimits{options.importer_timeout_seconds, options.importer_memory_mib},
      path + ": assimp reading the file",
      "the file is malformed or uses something assimp 5.2 cannot read: export it again (glTF 2.0 .glb "
      "is read without assimp), or raise LoadOptions::importer_timeout_seconds / importer_memory_mib "
      "if it is only large");
  Rig rig;
  io::decode_rig(bytes, path, rig, r);
  return rig;
}

}  // namespace isokit::skinning
