// SPDX-License-Identifier: MIT
// The scene of a tinygltf model as an aiScene, so that the loader reads glTF through tinygltf and
// FBX / COLLADA through assimp into the same structure. Built as assimp's glTF importer builds it
// where the loader depends on it: one root (a node "ROOT" above several scene roots), one aiMesh
// per primitive ("NAME-p" when a mesh has several), one bone per skin joint on every primitive of
// a skinned node (offset = the inverse bind matrix), animations as key tracks (one channel per
// animated node; CUBICSPLINE keys keep their values). Differences, all on purpose: every weight
// set is read (JOINTS_n / WEIGHTS_n), node names are the loader's unique names, a skin without
// inverse bind matrices gets identities, key times are in seconds (1 tick per second).
#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <assimp/scene.h>

#include "io/gltf_io.h"
#include "isokit/core/error.h"

namespace isokit::skinning::gltf {

namespace {

aiMatrix4x4 column_major(const std::vector<double>& m) {
  aiMatrix4x4 a;
  for (unsigned r = 0; r < 4; ++r)
    for (unsigned c = 0; c < 4; ++c) a[r][c] = static_cast<ai_real>(m[4 * c + r]);
  return a;
}

// A node's local transform: its matrix, or translation * rotation * scale.
aiMatrix4x4 node_transform(const tinygltf::Node& n) {
  if (n.matrix.size() == 16) return column_major(n.matrix);
  aiMatrix4x4 m;
  if (n.translation.size() == 3) {
    aiMatrix4x4 t;
    aiMatrix4x4::Translation(
        aiVector3D(static_cast<ai_real>(n.translation[0]), static_cast<ai_real>(n.translation[1]),
                   static_cast<ai_real>(n.translation[2])),
        t);
    m = m * t;
  }
  if (n.rotation.size() == 4) {
    const aiQuaternion q(static_cast<ai_real>(n.rotation[3]), static_cast<ai_real>(n.rotation[0]),
                         static_cast<ai_real>(n.rotation[1]), static_cast<ai_real>(n.rotation[2]));
    m = m * aiMatrix4x4(q.GetMatrix());
  }
  if (n.scale.size() == 3) {
    aiMatrix4x4 s;
    aiMatrix4x4::Scaling(aiVector3D(static_cast<ai_real>(n.scale[0]), static_cast<ai_real>(n.scale[1]),
                                    static_cast<ai_real>(n.scale[2])),
                         s);
    m = m * s;
  }
  return m;
}

/// A new[] array of the released pointers (null when empty), as aiScene's destructor frees it.
template <typename T>
T** release_all(std::vector<std::unique_ptr<T>>& items, unsigned* count) {
  *count = static_cast<unsigned>(items.size());
  if (items.empty()) return nullptr;
  T** out = new T*[items.size()];
  for (std::size_t i = 0; i < items.size(); ++i) out[i] = items[i].release();
  return out;
}

// Bytes charged to the load budget per vertex and per triangle of a primitive: the aiMesh's copy
// (12 B a vertex; an aiFace and its heap index array, 64 B with the allocator's overhead) and the
// rig's mesh built from it (positions, the welding tables, output mapping, weights: measured under
// 200 B a vertex on the real rigs). An upper bound, so that the budget bounds the resident memory.
constexpr std::uint64_t kSceneBytesPerVertex = 256;
constexpr std::uint64_t kSceneBytesPerTriangle = 96;

/// Builds the aiScene of one glTF model; `node_names` are the nodes' unique names.
class SceneBuilder {
 public:
  SceneBuilder(const tinygltf::Model& model, const std::vector<std::string>& node_names,
               const std::string& path, LoadBudget* budget, const std::string& mask_attribute,
               std::vector<std::string>* warnings)
      : m_(model),
        names_(node_names),
        path_(path),
        budget_(budget),
        mask_attribute_(mask_attribute),
        warnings_(warnings) {}

  std::unique_ptr<aiScene> build();

 private:
  aiNode* node(int index, std::vector<char>& built);
  std::vector<unsigned> meshes_of(int node_index);
  std::unique_ptr<aiMesh> primitive_mesh(const tinygltf::Mesh& mesh, std::size_t mesh_index, std::size_t p);
  void add_bones(aiMesh* mesh, const tinygltf::Primitive& prim, const tinygltf::Skin& skin);
  void add_colors(aiMesh* mesh, const tinygltf::Primitive& prim, const std::string& what);
  aiAnimation* animation(const tinygltf::Animation& a, std::size_t index);

  const tinygltf::Model& m_;
  const std::vector<std::string>& names_;
  const std::string& path_;
  LoadBudget* budget_;
  const std::string& mask_attribute_;
  std::vector<std::string>* warnings_;
  std::vector<std::unique_ptr<aiMesh>> meshes_;
  std::map<int, std::vector<unsigned>> mesh_ids_;  ///< glTF mesh -> its aiMesh indices
  std::vector<std::unique_ptr<aiCamera>> cameras_;
  std::vector<std::unique_ptr<aiLight>> lights_;
};

std::vector<float> floats(const tinygltf::Model& m, int accessor, int want, const std::string& what,
                          LoadBudget* budget) {
  int comps = 0;
  const std::vector<double> v = read_accessor(m, accessor, &comps, what, budget);
  require(comps == want, what, "has " + std::to_string(comps) + " components, not " + std::to_string(want),
          "fix the file or export it again");
  return std::vector<float>(v.begin(), v.end());
}

/// The values of an index accessor (a primitive's indices, JOINTS_n): glTF 2.0 allows unsigned
/// byte, short or int components only. A float accessor here used to be converted to unsigned
/// with undefined behaviour (1e35; found by fuzzing, docs/fuzzing.md).
std::vector<std::uint32_t> index_values(const tinygltf::Model& m, int accessor, int* comps,
                                        const std::string& what, LoadBudget* budget) {
  const std::vector<double> v = read_accessor(m, accessor, comps, what, budget);
  const int type = m.accessors[static_cast<std::size_t>(accessor)].componentType;  // index checked
  require(type == kUnsignedByte || type == kUnsignedShort || type == kUnsignedInt,
          what + " (accessor " + std::to_string(accessor) + ")",
          "must have unsigned byte, short or int components (componentType " + std::to_string(type) + ")",
          "fix the file or export it again");
  std::vector<std::uint32_t> out(v.size());
  std::transform(v.begin(), v.end(), out.begin(), [](double x) { return static_cast<std::uint32_t>(x); });
  return out;
}

std::unique_ptr<aiMesh> SceneBuilder::primitive_mesh(const tinygltf::Mesh& mesh, std::size_t mesh_index,
                                                     std::size_t p) {
  const tinygltf::Primitive& prim = mesh.primitives[p];
  std::string name = mesh.name;
  if (mesh.primitives.size() > 1) name += "-" + std::to_string(p);
  const std::string what =
      path_ + ": mesh " +
      (mesh.name.empty() ? "meshes[" + std::to_string(mesh_index) + "]" : "'" + mesh.name + "'") +
      " primitive " + std::to_string(p);
  auto mesh_out = std::make_unique<aiMesh>();
  mesh_out->mName = name;
  const auto pos_it = prim.attributes.find("POSITION");
  const std::vector<float> pos = pos_it == prim.attributes.end()
                                     ? std::vector<float>{}
                                     : floats(m_, pos_it->second, 3, what + " POSITION", budget_);
  const auto nv = static_cast<unsigned>(pos.size() / 3);
  mesh_out->mNumVertices = nv;
  mesh_out->mVertices = new aiVector3D[std::max(nv, 1u)];
  for (unsigned v = 0; v < nv; ++v)
    mesh_out->mVertices[v] = aiVector3D(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]);
  std::vector<unsigned> idx;
  if (prim.indices >= 0) {
    int comps = 0;
    for (std::uint32_t x : index_values(m_, prim.indices, &comps, what + " indices", budget_))
      idx.push_back(x);
  } else {
    for (unsigned v = 0; v < nv; ++v) idx.push_back(v);
  }
  std::vector<std::array<unsigned, 3>> tris;
  const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
  if (mode == TINYGLTF_MODE_TRIANGLES)
    for (std::size_t i = 0; i + 2 < idx.size(); i += 3) tris.push_back({idx[i], idx[i + 1], idx[i + 2]});
  else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP)
    for (std::size_t i = 0; i + 2 < idx.size(); ++i)
      tris.push_back(i % 2 ? std::array<unsigned, 3>{idx[i + 1], idx[i], idx[i + 2]}
                           : std::array<unsigned, 3>{idx[i], idx[i + 1], idx[i + 2]});
  else if (mode == TINYGLTF_MODE_TRIANGLE_FAN)
    for (std::size_t i = 1; i + 1 < idx.size(); ++i) tris.push_back({idx[0], idx[i], idx[i + 1]});
  // What the scene keeps of the primitive (vertices, faces with their index arrays, allocator
  // overhead included) and what the rig derives from it later (loader.cpp: merged, welded).
  if (budget_ != nullptr)
    budget_->charge(
        std::uint64_t{nv} * kSceneBytesPerVertex + tris.size() * kSceneBytesPerTriangle,
        what + " (" + std::to_string(nv) + " vertices, " + std::to_string(tris.size()) + " triangles)");
  mesh_out->mPrimitiveTypes = tris.empty() ? aiPrimitiveType_POINT : aiPrimitiveType_TRIANGLE;
  mesh_out->mNumFaces = static_cast<unsigned>(tris.size());
  mesh_out->mFaces = tris.empty() ? nullptr : new aiFace[tris.size()];
  for (std::size_t f = 0; f < tris.size(); ++f) {
    mesh_out->mFaces[f].mNumIndices = 3;
    mesh_out->mFaces[f].mIndices = new unsigned[3]{tris[f][0], tris[f][1], tris[f][2]};
  }
  add_colors(mesh_out.get(), prim, what);
  return mesh_out;
}

/// The primitive's COLOR_n (RGB or RGBA) as colour sets n < kMaskColorSet, and its mask attribute
/// (a scalar per vertex) as set kMaskColorSet.
void SceneBuilder::add_colors(aiMesh* mesh, const tinygltf::Primitive& prim, const std::string& what) {
  const unsigned nv = mesh->mNumVertices;
  auto set = [&](unsigned k, const std::vector<double>& v, int comps) {
    mesh->mColors[k] = new aiColor4D[std::max(nv, 1u)];
    for (unsigned i = 0; i < nv; ++i) {
      const double* c = v.data() + std::size_t(i) * std::size_t(comps);
      mesh->mColors[k][i] =
          comps == 1 ? aiColor4D(float(c[0]), float(c[0]), float(c[0]), 1.f)
                     : aiColor4D(float(c[0]), float(c[1]), float(c[2]), comps == 4 ? float(c[3]) : 1.f);
    }
  };
  // Colours are optional data: one of an unexpected shape is skipped, not the file refused.
  auto usable = [&](const std::string& w, int comps, bool ok_comps, std::size_t values) {
    const bool ok = ok_comps && values == std::size_t(nv) * std::size_t(comps);
    if (!ok && warnings_ != nullptr)
      warnings_->push_back(w + ": " + std::to_string(comps) + " component(s) per vertex and " +
                           std::to_string(values) + " values for " + std::to_string(nv) +
                           " vertices; not read");
    return ok;
  };
  for (unsigned k = 0; k < kMaskColorSet; ++k) {
    const auto it = prim.attributes.find("COLOR_" + std::to_string(k));
    if (it == prim.attributes.end()) continue;
    int comps = 0;
    const std::string w = what + " COLOR_" + std::to_string(k);
    const std::vector<double> v = read_accessor(m_, it->second, &comps, w, budget_);
    if (usable(w, comps, comps == 3 || comps == 4, v.size())) set(k, v, comps);
  }
  if (mask_attribute_.empty()) return;
  const auto it = prim.attributes.find(mask_attribute_);
  if (it == prim.attributes.end()) return;
  int comps = 0;
  const std::string w = what + " " + mask_attribute_ + " (the relaxation mask: a scalar per vertex)";
  const std::vector<double> v = read_accessor(m_, it->second, &comps, w, budget_);
  if (usable(w, comps, comps == 1, v.size())) set(kMaskColorSet, v, 1);
}

/// One bone per joint of `skin` (named by the joint node, offset = its inverse bind matrix or the
/// identity), with the positive weights of every JOINTS_n / WEIGHTS_n set.
void SceneBuilder::add_bones(aiMesh* mesh, const tinygltf::Primitive& prim, const tinygltf::Skin& skin) {
  const std::size_t nj = skin.joints.size();
  std::vector<std::vector<aiVertexWeight>> weights(nj);
  for (int set = 0;; ++set) {
    const auto jt = prim.attributes.find("JOINTS_" + std::to_string(set));
    const auto wt = prim.attributes.find("WEIGHTS_" + std::to_string(set));
    if (jt == prim.attributes.end() || wt == prim.attributes.end()) break;
    int jc = 0;
    int wc = 0;
    const std::vector<std::uint32_t> jv = index_values(m_, jt->second, &jc, path_ + ": JOINTS", budget_);
    const std::vector<double> wv = read_accessor(m_, wt->second, &wc, path_ + ": WEIGHTS", budget_);
    for (std::size_t i = 0; i < wv.size() && i < jv.size(); ++i) {
      const std::size_t j = jv[i];
      if (wv[i] > 0 && j < nj)
        weights[j].emplace_back(static_cast<unsigned>(i / 4), static_cast<ai_real>(wv[i]));
    }
  }
  std::vector<double> ibm;
  if (skin.inverseBindMatrices >= 0) {
    int comps = 0;
    ibm = read_accessor(m_, skin.inverseBindMatrices, &comps, path_ + ": inverseBindMatrices", budget_);
  }
  std::vector<std::unique_ptr<aiBone>> bones;
  for (std::size_t j = 0; j < nj; ++j) {
    bones.push_back(std::make_unique<aiBone>());
    aiBone* bone = bones.back().get();
    bone->mName = names_[static_cast<std::size_t>(skin.joints[j])];
    if (ibm.size() >= 16 * (j + 1))
      bone->mOffsetMatrix = column_major({ibm.begin() + 16 * j, ibm.begin() + 16 * (j + 1)});
    bone->mNumWeights = static_cast<unsigned>(weights[j].size());
    bone->mWeights = weights[j].empty() ? nullptr : new aiVertexWeight[weights[j].size()];
    std::copy(weights[j].begin(), weights[j].end(), bone->mWeights);
  }
  mesh->mBones = release_all(bones, &mesh->mNumBones);
}

/// The aiMesh indices of a node's mesh (created on its first use, with the node's skin).
std::vector<unsigned> SceneBuilder::meshes_of(int node_index) {
  const tinygltf::Node& n = m_.nodes[static_cast<std::size_t>(node_index)];
  if (n.mesh < 0 || static_cast<std::size_t>(n.mesh) >= m_.meshes.size()) return {};
  const auto found = mesh_ids_.find(n.mesh);
  if (found != mesh_ids_.end()) return found->second;
  const tinygltf::Mesh& mesh = m_.meshes[static_cast<std::size_t>(n.mesh)];
  std::vector<unsigned>& ids = mesh_ids_[n.mesh];
  for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
    ids.push_back(static_cast<unsigned>(meshes_.size()));
    meshes_.push_back(primitive_mesh(mesh, static_cast<std::size_t>(n.mesh), p));
    if (n.skin >= 0 && static_cast<std::size_t>(n.skin) < m_.skins.size())
      add_bones(meshes_.back().get(), mesh.primitives[p], m_.skins[static_cast<std::size_t>(n.skin)]);
  }
  return ids;
}

/// Builds node `index` and its subtree. A node reached twice — a cycle, a node with two parents, a
/// root listed twice — is refused: glTF's hierarchy is a forest, and a shared subtree would be
/// copied once per path (2^depth copies from a chain of shared children).
aiNode* SceneBuilder::node(int index, std::vector<char>& built) {
  require(index >= 0 && static_cast<std::size_t>(index) < m_.nodes.size(),
          path_ + ": node " + std::to_string(index), "does not exist", "fix the file or export it again");
  char& seen = built[static_cast<std::size_t>(index)];
  require(!seen, path_ + ": node '" + names_[static_cast<std::size_t>(index)] + "'",
          "is reached twice in the node hierarchy (a cycle, or a node with two parents)",
          "fix the file or export it again (glTF nodes form trees)");
  seen = 1;
  const tinygltf::Node& n = m_.nodes[static_cast<std::size_t>(index)];
  auto out = std::make_unique<aiNode>(names_[static_cast<std::size_t>(index)]);
  out->mTransformation = node_transform(n);
  const std::vector<unsigned> ids = meshes_of(index);
  out->mNumMeshes = static_cast<unsigned>(ids.size());
  out->mMeshes = ids.empty() ? nullptr : new unsigned[ids.size()];
  std::copy(ids.begin(), ids.end(), out->mMeshes);
  if (n.camera >= 0) {
    cameras_.push_back(std::make_unique<aiCamera>());
    cameras_.back()->mName = out->mName;
  }
  if (n.extensions.count("KHR_lights_punctual")) {
    lights_.push_back(std::make_unique<aiLight>());
    lights_.back()->mName = out->mName;
  }
  // Children are attached as they are built, so that the node frees them if a later one throws.
  out->mChildren = n.children.empty() ? nullptr : new aiNode*[n.children.size()];
  for (int c : n.children) {
    aiNode* child = node(c, built);
    child->mParent = out.get();
    out->mChildren[out->mNumChildren++] = child;
  }
  return out.release();
}

/// Key track of one sampler: times (seconds) and values of `comps` components (the middle value of
/// each CUBICSPLINE triple).
struct Track {
  std::vector<float> times;
  std::vector<float> values;
};

Track read_track(const tinygltf::Model& m, const tinygltf::AnimationSampler& s, int comps,
                 const std::string& what, LoadBudget* budget) {
  Track t;
  t.times = floats(m, s.input, 1, what + " input", budget);
  const std::vector<float> out = floats(m, s.output, comps, what + " output", budget);
  const bool cubic = s.interpolation == "CUBICSPLINE";
  const std::size_t per_key = cubic ? 3 : 1;
  const auto c = static_cast<std::size_t>(comps);
  require(out.size() >= t.times.size() * per_key * c, what, "has fewer output values than keys",
          "fix the file or export it again");
  for (std::size_t k = 0; k < t.times.size(); ++k) {
    const std::size_t at = (k * per_key + (cubic ? 1 : 0)) * c;
    t.values.insert(t.values.end(), out.begin() + static_cast<std::ptrdiff_t>(at),
                    out.begin() + static_cast<std::ptrdiff_t>(at + c));
  }
  return t;
}

aiAnimation* SceneBuilder::animation(const tinygltf::Animation& a, std::size_t index) {
  auto anim = std::make_unique<aiAnimation>();
  anim->mName = a.name;
  anim->mTicksPerSecond = 1;                            // key times in seconds
  std::map<int, std::unique_ptr<aiNodeAnim>> channels;  // by node, in node order
  for (std::size_t c = 0; c < a.channels.size(); ++c) {
    const tinygltf::AnimationChannel& ch = a.channels[c];
    const std::string& target = ch.target_path;
    if (target != "translation" && target != "rotation" && target != "scale") continue;
    if (ch.sampler < 0 || static_cast<std::size_t>(ch.sampler) >= a.samplers.size() || ch.target_node < 0 ||
        static_cast<std::size_t>(ch.target_node) >= m_.nodes.size())
      continue;
    const std::string what =
        path_ + ": animations[" + std::to_string(index) + "] channel " + std::to_string(c);
    const Track t = read_track(m_, a.samplers[static_cast<std::size_t>(ch.sampler)],
                               target == "rotation" ? 4 : 3, what, budget_);
    std::unique_ptr<aiNodeAnim>& na = channels[ch.target_node];
    if (!na) {
      na = std::make_unique<aiNodeAnim>();
      na->mNodeName = names_[static_cast<std::size_t>(ch.target_node)];
    }
    const auto n = static_cast<unsigned>(t.times.size());
    for (float time : t.times) anim->mDuration = std::max(anim->mDuration, static_cast<double>(time));
    if (target == "rotation") {
      delete[] na->mRotationKeys;
      na->mNumRotationKeys = n;
      na->mRotationKeys = new aiQuatKey[n];
      for (unsigned k = 0; k < n; ++k)
        na->mRotationKeys[k] = aiQuatKey(t.times[k], aiQuaternion(t.values[4 * k + 3], t.values[4 * k],
                                                                  t.values[4 * k + 1], t.values[4 * k + 2]));
    } else {
      aiVectorKey* keys = new aiVectorKey[n];
      for (unsigned k = 0; k < n; ++k)
        keys[k] =
            aiVectorKey(t.times[k], aiVector3D(t.values[3 * k], t.values[3 * k + 1], t.values[3 * k + 2]));
      if (target == "translation") {
        delete[] na->mPositionKeys;
        na->mNumPositionKeys = n;
        na->mPositionKeys = keys;
      } else {
        delete[] na->mScalingKeys;
        na->mNumScalingKeys = n;
        na->mScalingKeys = keys;
      }
    }
  }
  std::vector<std::unique_ptr<aiNodeAnim>> list;
  for (auto& [node_index, na] : channels) list.push_back(std::move(na));
  anim->mChannels = release_all(list, &anim->mNumChannels);
  return anim.release();
}

std::unique_ptr<aiScene> SceneBuilder::build() {
  auto scene = std::make_unique<aiScene>();
  std::vector<int> roots;
  if (!m_.scenes.empty()) {
    const std::size_t s = m_.defaultScene >= 0 && static_cast<std::size_t>(m_.defaultScene) < m_.scenes.size()
                              ? static_cast<std::size_t>(m_.defaultScene)
                              : 0;
    roots = m_.scenes[s].nodes;
  } else {  // no scene: every node without a parent
    std::vector<char> child(m_.nodes.size(), 0);
    for (const tinygltf::Node& n : m_.nodes)
      for (int c : n.children)
        if (c >= 0 && static_cast<std::size_t>(c) < child.size()) child[static_cast<std::size_t>(c)] = 1;
    for (std::size_t i = 0; i < m_.nodes.size(); ++i)
      if (!child[i]) roots.push_back(static_cast<int>(i));
  }
  std::vector<char> built(m_.nodes.size(), 0);
  if (roots.size() == 1) {
    scene->mRootNode = node(roots.front(), built);
  } else {  // several roots (or none) under one "ROOT", as assimp does
    scene->mRootNode = new aiNode("ROOT");
    scene->mRootNode->mChildren = roots.empty() ? nullptr : new aiNode*[roots.size()];
    for (int r : roots) {
      aiNode* child = node(r, built);
      child->mParent = scene->mRootNode;
      scene->mRootNode->mChildren[scene->mRootNode->mNumChildren++] = child;
    }
  }
  std::vector<std::unique_ptr<aiAnimation>> animations;
  for (std::size_t a = 0; a < m_.animations.size(); ++a)
    animations.emplace_back(animation(m_.animations[a], a));
  scene->mMeshes = release_all(meshes_, &scene->mNumMeshes);
  if (scene->mNumMeshes == 0) scene->mFlags |= AI_SCENE_FLAGS_INCOMPLETE;  // as assimp marks it
  scene->mCameras = release_all(cameras_, &scene->mNumCameras);
  scene->mLights = release_all(lights_, &scene->mNumLights);
  scene->mAnimations = release_all(animations, &scene->mNumAnimations);
  return scene;
}

}  // namespace

std::unique_ptr<aiScene> to_ai_scene(const tinygltf::Model& model, const std::vector<std::string>& node_names,
                                     const std::string& path, LoadBudget* budget,
                                     const std::string& mask_attribute, std::vector<std::string>* warnings) {
  return SceneBuilder(model, node_names, path, budget, mask_attribute, warnings).build();
}

}  // namespace isokit::skinning::gltf
