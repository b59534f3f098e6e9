// SPDX-License-Identifier: MIT
// Writers of the rig I/O: save_rig (skinned glTF 2.0), write_baked_glb (morph-target animation),
// write_pc2 (point cache) and write_ply. glTF documents are tinygltf models (gltf_io.h); every
// file goes through a temporary file.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <ostream>
#include <set>

#include "io/gltf_io.h"
#include "isokit/core/atomic_file.h"
#include "isokit/core/error.h"
#include "isokit/skinning/rig_io.h"

namespace isokit::skinning {

namespace {

/// glTF attribute name -> accessor index.
using Attributes = std::map<std::string, int>;

// Output (unwelded) vertices and their primitives, resolved from `Rig::output`.
struct OutputView {
  std::vector<int> to_welded;
  track::Triangles triangles;
  std::vector<int> primitive_offsets;
};

OutputView output_view(const Rig& rig, const std::string& path) {
  OutputView v;
  const int nw = static_cast<int>(rig.rest.rows());
  if (rig.output.to_welded.empty()) {
    v.to_welded.resize(static_cast<std::size_t>(nw));
    for (int i = 0; i < nw; ++i) v.to_welded[static_cast<std::size_t>(i)] = i;
    v.triangles = rig.triangles;
    v.primitive_offsets = {0, static_cast<int>(rig.triangles.rows())};
    return v;
  }
  const std::string what = path + ": rig " + rig.name + " output mesh";
  v.to_welded = rig.output.to_welded;
  v.triangles = rig.output.triangles;
  const int nout = static_cast<int>(v.to_welded.size());
  for (int w : v.to_welded)
    require(w >= 0 && w < nw, what, "maps a vertex outside the welded mesh", "fix Rig::output.to_welded");
  for (Eigen::Index f = 0; f < v.triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      require(v.triangles(f, k) >= 0 && v.triangles(f, k) < nout, what,
              "triangle " + std::to_string(f) + " has an index out of range", "fix Rig::output.triangles");
  const int nf = static_cast<int>(v.triangles.rows());
  v.primitive_offsets = rig.output.primitive_offsets;
  if (v.primitive_offsets.empty() || v.primitive_offsets.back() != nf) {
    const bool only_start = v.primitive_offsets.size() <= 1;
    require(only_start, what, "primitive_offsets do not end at the triangle count",
            "fix Rig::output.primitive_offsets");
    v.primitive_offsets = {0, nf};
  }
  require(v.primitive_offsets.front() == 0 &&
              std::is_sorted(v.primitive_offsets.begin(), v.primitive_offsets.end()),
          what, "primitive_offsets must rise from 0", "fix Rig::output.primitive_offsets");
  return v;
}

// Area-weighted unit vertex normals (+Y where a vertex has no area).
std::vector<float> vertex_normals(const std::vector<float>& pos, const track::Triangles& tris) {
  const std::size_t n = pos.size() / 3;
  std::vector<Eigen::Vector3d> acc(n, Eigen::Vector3d::Zero());
  auto p = [&](int i) {
    const auto k = static_cast<std::size_t>(i) * 3;
    return Eigen::Vector3d(pos[k], pos[k + 1], pos[k + 2]);
  };
  for (Eigen::Index f = 0; f < tris.rows(); ++f) {
    const Eigen::Vector3d a = p(tris(f, 0));
    const Eigen::Vector3d fn = (p(tris(f, 1)) - a).cross(p(tris(f, 2)) - a);
    for (int k = 0; k < 3; ++k) acc[static_cast<std::size_t>(tris(f, k))] += fn;
  }
  std::vector<float> out(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const double len = acc[i].norm();
    const Eigen::Vector3d u =
        len > 0 && std::isfinite(len) ? Eigen::Vector3d(acc[i] / len) : Eigen::Vector3d::UnitY();
    for (int k = 0; k < 3; ++k) out[3 * i + static_cast<std::size_t>(k)] = static_cast<float>(u[k]);
  }
  return out;
}

std::vector<float> output_positions(const track::Positions& welded, const std::vector<int>& to_welded) {
  std::vector<float> out(3 * to_welded.size());
  for (std::size_t i = 0; i < to_welded.size(); ++i)
    for (int k = 0; k < 3; ++k) out[3 * i + static_cast<std::size_t>(k)] = welded(to_welded[i], k);
  return out;
}

struct Trs {
  Eigen::Vector3d t;
  Eigen::Quaterniond r;
  Eigen::Vector3d s;
};

// TRS of an affine transform; \throw InputError when it has shear (glTF nodes are TRS).
Trs to_trs(const Affine& a, const std::string& what) {
  Eigen::Matrix3d rot;
  Eigen::Matrix3d scale;
  a.computeRotationScaling(&rot, &scale);
  Trs x{a.translation(), Eigen::Quaterniond(rot).normalized(), scale.diagonal()};
  const Eigen::Matrix3d back = x.r.toRotationMatrix() * x.s.asDiagonal();
  const double err = (back - a.linear()).cwiseAbs().maxCoeff();
  require(err <= 1e-6 * std::max(1.0, a.linear().cwiseAbs().maxCoeff()), what,
          "transform has shear and cannot be written as a glTF node (translation, rotation, scale)",
          "use rigid or scale-aligned joint transforms");
  return x;
}

bool same_vec(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return (a - b).cwiseAbs().maxCoeff() <=
         1e-7 * std::max({1.0, a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff()});
}

bool same_rot(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return std::min((a.coeffs() - b.coeffs()).norm(), (a.coeffs() + b.coeffs()).norm()) <= 1e-7;
}

std::vector<float> flat(const std::vector<Eigen::Vector3d>& v) {
  std::vector<float> out;
  out.reserve(3 * v.size());
  for (const auto& x : v)
    for (int k = 0; k < 3; ++k) out.push_back(static_cast<float>(x[k]));
  return out;
}

// Index accessor of a triangle list (u16 when every index is below 65535, else u32).
int add_indices(gltf::Builder& b, const std::vector<std::uint32_t>& idx, std::size_t vertices) {
  if (vertices < 0xFFFF) {
    std::vector<std::uint16_t> s(idx.begin(), idx.end());
    return b.add_u16(s.data(), s.size(), "SCALAR", gltf::kElementArrayBuffer);
  }
  return b.add_u32(idx.data(), idx.size(), "SCALAR", gltf::kElementArrayBuffer);
}

void write_animation(gltf::Builder& b, const Rig& rig, const Clip& clip, const std::vector<Trs>& rest,
                     const std::string& path) {
  const std::vector<std::vector<Affine>> frames = clip_frames(clip);
  const std::size_t nf = frames.size();
  const std::size_t nj = rig.joints.size();
  std::vector<float> times(nf);
  for (std::size_t f = 0; f < nf; ++f) times[f] = static_cast<float>(static_cast<double>(f) / clip.fps);
  const int input = b.add_floats(times.data(), nf, "SCALAR", true);
  tinygltf::Animation anim;
  anim.name = clip.name;
  auto add = [&](std::size_t joint, const char* target_path, const std::vector<float>& values,
                 const char* type) {
    tinygltf::AnimationSampler sampler;
    sampler.input = input;
    sampler.output = b.add_floats(values.data(), nf, type, false);
    sampler.interpolation = "LINEAR";
    anim.samplers.push_back(sampler);
    tinygltf::AnimationChannel channel;
    channel.sampler = static_cast<int>(anim.samplers.size()) - 1;
    channel.target_node = static_cast<int>(joint);
    channel.target_path = target_path;
    anim.channels.push_back(channel);
  };
  for (std::size_t j = 0; j < nj; ++j) {
    std::vector<Eigen::Vector3d> t(nf);
    std::vector<Eigen::Vector3d> s(nf);
    std::vector<Eigen::Quaterniond> r(nf);
    bool t_const = true;
    bool r_const = true;
    bool s_const = true;
    for (std::size_t f = 0; f < nf; ++f) {
      const Trs x = to_trs(frames[f][j], path + ": clip '" + clip.name + "' frame " + std::to_string(f) +
                                             " joint '" + rig.joints[j].name + "'");
      t[f] = x.t;
      s[f] = x.s;
      r[f] = x.r;
      // Keep consecutive quaternions in one hemisphere so that interpolation takes the short way.
      const Eigen::Quaterniond& prev = f > 0 ? r[f - 1] : rest[j].r;
      if (prev.dot(r[f]) < 0) r[f].coeffs() = -r[f].coeffs();
      t_const = t_const && same_vec(t[f], rest[j].t);
      s_const = s_const && same_vec(s[f], rest[j].s);
      r_const = r_const && same_rot(r[f], rest[j].r);
    }
    if (!t_const) add(j, "translation", flat(t), "VEC3");
    if (!r_const || (j + 1 == nj && anim.channels.empty())) {  // an animation needs one channel
      std::vector<float> q;
      for (const auto& x : r)
        q.insert(q.end(), {static_cast<float>(x.x()), static_cast<float>(x.y()), static_cast<float>(x.z()),
                           static_cast<float>(x.w())});
      add(j, "rotation", q, "VEC4");
    }
    if (!s_const) add(j, "scale", flat(s), "VEC3");
  }
  b.model().animations.push_back(anim);
}

/// Every joint needs a unique, non-empty name: files bind bones by name.
void check_joint_names(const Rig& rig, const std::string& path) {
  std::set<std::string> names;
  for (const Joint& j : rig.joints)
    require(!j.name.empty() && names.insert(j.name).second, path + ": joint '" + j.name + "'",
            j.name.empty() ? "has no name" : "name is not unique",
            "give every joint a unique name (files bind bones by name)");
}

/// The joints as glTF nodes: their rest transforms as TRS and the scene's root nodes.
struct JointNodes {
  std::vector<Trs> rest;
  std::vector<int> roots;
};

/// Writes the scene: joint nodes 0..nj-1, then the mesh node.
JointNodes add_joint_nodes(tinygltf::Model& d, const Rig& rig, const std::string& path) {
  const std::size_t nj = rig.joints.size();
  JointNodes jn;
  std::vector<Trs>& rest = jn.rest;
  std::vector<int>& roots = jn.roots;
  rest.resize(nj);
  std::vector<tinygltf::Node>& nodes = d.nodes;
  for (std::size_t j = 0; j < nj; ++j) {
    rest[j] = to_trs(rig.joints[j].rest_local, path + ": joint '" + rig.joints[j].name + "' rest transform");
    tinygltf::Node node;
    node.name = rig.joints[j].name;
    node.translation = {rest[j].t.x(), rest[j].t.y(), rest[j].t.z()};
    node.rotation = {rest[j].r.x(), rest[j].r.y(), rest[j].r.z(), rest[j].r.w()};
    node.scale = {rest[j].s.x(), rest[j].s.y(), rest[j].s.z()};
    nodes.push_back(node);
    if (rig.joints[j].parent < 0) roots.push_back(static_cast<int>(j));
  }
  for (std::size_t j = 0; j < nj; ++j)
    if (rig.joints[j].parent >= 0)
      nodes[static_cast<std::size_t>(rig.joints[j].parent)].children.push_back(static_cast<int>(j));
  tinygltf::Node mesh_node;
  mesh_node.name = "isokit_mesh";
  mesh_node.mesh = 0;
  mesh_node.skin = 0;
  nodes.push_back(mesh_node);
  roots.push_back(static_cast<int>(nj));
  d.defaultScene = 0;
  d.scenes.resize(1);
  d.scenes[0].nodes = roots;
  return jn;
}

/// Per welded vertex, its positive influences (weight, joint), heaviest first.
using Influences = std::vector<std::vector<std::pair<float, int>>>;

/// The influences of every welded vertex and the number of JOINTS_n / WEIGHTS_n sets of 4
/// the largest one needs (`sets`).
Influences sorted_influences(const Rig& rig, int& sets) {
  Influences infl;
  const int nw = static_cast<int>(rig.rest.rows());
  infl.resize(static_cast<std::size_t>(nw));
  for (int v = 0; v < nw; ++v) {
    auto& list = infl[static_cast<std::size_t>(v)];
    for (int k = rig.weights.offsets[v]; k < rig.weights.offsets[v + 1]; ++k)
      if (rig.weights.weights[k] > 0) list.push_back({rig.weights.weights[k], rig.weights.joints[k]});
    std::stable_sort(list.begin(), list.end(),
                     [](const auto& x, const auto& y) { return x.first > y.first; });
    sets = std::max(sets, (static_cast<int>(list.size()) + 3) / 4);
  }
  return infl;
}

/// The output mesh's vertex data, from which each glTF primitive takes its vertices.
struct SkinnedVertices {
  const OutputView& out;
  const std::vector<float>& pos;
  const std::vector<float>& nrm;
  const Influences& infl;
  int sets;
  std::size_t joints;
  const std::vector<float>& mask;  ///< Rig::relax_mask (per welded vertex; empty: none)
};

/// The relaxation mask as the glTF custom attribute `_RELAX_MASK` (a float per output vertex
/// `verts[i]`; Rig::relax_mask), so that it survives a round trip; nothing without a mask.
void add_mask(gltf::Builder& b, const std::vector<float>& mask, const std::vector<int>& to_welded,
              const std::vector<int>& verts, Attributes& attrs) {
  if (mask.empty()) return;
  std::vector<float> m(verts.size());
  for (std::size_t i = 0; i < verts.size(); ++i)
    m[i] = mask[static_cast<std::size_t>(to_welded[static_cast<std::size_t>(verts[i])])];
  attrs["_RELAX_MASK"] = b.add_floats(m.data(), m.size(), "SCALAR", false, gltf::kArrayBuffer);
}

/// Adds JOINTS_s / WEIGHTS_s for the primitive's vertices `verts` (u8 joints up to 256 joints).
void add_weight_sets(gltf::Builder& b, const SkinnedVertices& sv, const std::vector<int>& verts,
                     Attributes& attrs) {
  const std::size_t n = verts.size();
  for (int s = 0; s < sv.sets; ++s) {
    std::vector<std::uint16_t> jv(4 * n, 0);
    std::vector<float> wv(4 * n, 0.0f);
    for (std::size_t i = 0; i < n; ++i) {
      const auto& list =
          sv.infl[static_cast<std::size_t>(sv.out.to_welded[static_cast<std::size_t>(verts[i])])];
      for (std::size_t k = 0; k < 4; ++k) {
        const std::size_t at = 4 * static_cast<std::size_t>(s) + k;
        if (at >= list.size()) break;
        jv[4 * i + k] = static_cast<std::uint16_t>(list[at].second);
        wv[4 * i + k] = list[at].first;
      }
    }
    const std::string sfx = std::to_string(s);
    if (sv.joints <= 256) {
      std::vector<std::uint8_t> j8(jv.begin(), jv.end());
      attrs["JOINTS_" + sfx] = b.add_u8(j8.data(), n, "VEC4", gltf::kArrayBuffer);
    } else {
      attrs["JOINTS_" + sfx] = b.add_u16(jv.data(), n, "VEC4", gltf::kArrayBuffer);
    }
    attrs["WEIGHTS_" + sfx] = b.add_floats(wv.data(), n, "VEC4", false, gltf::kArrayBuffer);
  }
}

/// The primitive of triangles [f0, f1): its own vertices (POSITION, NORMAL, weight sets) and
/// indices.
tinygltf::Primitive skinned_primitive(gltf::Builder& b, const SkinnedVertices& sv, int f0, int f1) {
  const OutputView& out = sv.out;
  std::vector<int> verts;
  for (int f = f0; f < f1; ++f)
    for (int k = 0; k < 3; ++k) verts.push_back(out.triangles(f, k));
  std::sort(verts.begin(), verts.end());
  verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
  std::vector<std::uint32_t> local(out.to_welded.size(), 0);
  for (std::size_t i = 0; i < verts.size(); ++i)
    local[static_cast<std::size_t>(verts[i])] = static_cast<std::uint32_t>(i);
  const std::size_t n = verts.size();
  std::vector<float> ppos(3 * n);
  std::vector<float> pnrm(3 * n);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t k = 0; k < 3; ++k) {
      ppos[3 * i + k] = sv.pos[3 * static_cast<std::size_t>(verts[i]) + k];
      pnrm[3 * i + k] = sv.nrm[3 * static_cast<std::size_t>(verts[i]) + k];
    }
  tinygltf::Primitive prim;
  Attributes& attrs = prim.attributes;
  attrs["POSITION"] = b.add_floats(ppos.data(), n, "VEC3", true, gltf::kArrayBuffer);
  attrs["NORMAL"] = b.add_floats(pnrm.data(), n, "VEC3", false, gltf::kArrayBuffer);
  add_weight_sets(b, sv, verts, attrs);
  add_mask(b, sv.mask, out.to_welded, verts, attrs);
  std::vector<std::uint32_t> idx;
  idx.reserve(3 * static_cast<std::size_t>(f1 - f0));
  for (int f = f0; f < f1; ++f)
    for (int k = 0; k < 3; ++k) idx.push_back(local[static_cast<std::size_t>(out.triangles(f, k))]);
  prim.indices = add_indices(b, idx, n);
  prim.mode = TINYGLTF_MODE_TRIANGLES;
  return prim;
}

/// The skin: inverse bind matrices (column-major), the joint nodes and, with one root joint,
/// the skeleton root.
void add_skin(gltf::Builder& b, const Rig& rig, const std::vector<int>& roots) {
  const std::size_t nj = rig.joints.size();
  std::vector<float> ibm(16 * nj);
  for (std::size_t j = 0; j < nj; ++j) {
    const Eigen::Matrix4d m = rig.joints[j].inverse_bind.matrix();
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r)
        ibm[16 * j + static_cast<std::size_t>(4 * c + r)] = static_cast<float>(m(r, c));
  }
  tinygltf::Skin skin;
  skin.inverseBindMatrices = b.add_floats(ibm.data(), nj, "MAT4", false);
  for (std::size_t j = 0; j < nj; ++j) skin.joints.push_back(static_cast<int>(j));
  if (roots.size() == 2) skin.skeleton = roots.front();
  b.model().skins = {skin};
}

/// Checks baked frames: at least one, each finite with the rig's welded vertex count.
void check_frames(const Rig& rig, const std::vector<track::Positions>& frames, const std::string& path) {
  require(!frames.empty(), path + ": frames", "none given", "bake at least one frame");
  validate(rig);
  const Eigen::Index nw = rig.rest.rows();
  for (std::size_t k = 0; k < frames.size(); ++k) {
    require(frames[k].rows() == nw, path + ": frame " + std::to_string(k),
            "has " + std::to_string(frames[k].rows()) + " vertices, the rig " + std::to_string(nw),
            "pass welded positions (Rig::rest order) for every frame");
    require(frames[k].allFinite(), path + ": frame " + std::to_string(k), "has non-finite positions",
            "fix the deformation before baking");
  }
}

/// Checks the arguments of write_baked_glb.
void check_bake(const Rig& rig, const std::vector<track::Positions>& frames, double fps,
                const std::string& path) {
  require(gltf::extension(path) == ".glb", path, "extension must be .glb", "name the file *.glb");
  require(fps > 0 && std::isfinite(fps), path + ": fps", "must be > 0 (got " + format_number(fps) + ")",
          "pass the frame rate of the frames");
  check_frames(rig, frames, path);
}

/// Appends `u` to `buf` as 4 little-endian bytes.
void put_u32(std::vector<char>& buf, std::uint32_t u) {
  for (int b = 0; b < 4; ++b) buf.push_back(static_cast<char>((u >> (8 * b)) & 0xFF));
}

void put_f32(std::vector<char>& buf, float x) {
  std::uint32_t u;
  std::memcpy(&u, &x, 4);
  put_u32(buf, u);
}

/// Adds morph-target delta accessors of `nout` VEC3: sparse when that is smaller than the dense
/// array (and `sparse` is on); deltas no longer than `eps` count as zero (exact zeros when 0).
struct DeltaWriter {
  gltf::Builder& b;
  std::size_t nout;
  bool sparse;

  int add(const std::vector<float>& delta, float eps) const {
    const std::size_t index_bytes = nout <= 0x100 ? 1 : nout <= 0x10000 ? 2 : 4;
    std::vector<std::uint32_t> nz;
    std::vector<float> values;
    for (std::size_t i = 0; i < nout; ++i) {
      const float* x = &delta[3 * i];
      const bool moved = eps > 0 ? std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) > eps
                                 : (x[0] != 0.0f || x[1] != 0.0f || x[2] != 0.0f);
      if (!moved) continue;
      nz.push_back(static_cast<std::uint32_t>(i));
      values.insert(values.end(), x, x + 3);
    }
    if (sparse && nz.size() * (index_bytes + 12) < nout * 12) return b.add_sparse_vec3(nout, nz, values);
    return b.add_floats(delta.data(), nout, "VEC3", true, gltf::kArrayBuffer);
  }
};

/// The morph weights' animation: one-hot at frame k, time k / fps.
void add_morph_animation(gltf::Builder& b, std::size_t nk, double fps, const BakedGlbOptions& options) {
  std::vector<float> times(nk);
  std::vector<float> weights(nk * nk, 0.0f);
  for (std::size_t k = 0; k < nk; ++k) {
    times[k] = static_cast<float>(static_cast<double>(k) / fps);
    weights[k * nk + k] = 1.0f;
  }
  const int input = b.add_floats(times.data(), nk, "SCALAR", true);
  const int output = b.add_floats(weights.data(), nk * nk, "SCALAR", false);
  const char* interp = options.interpolation == MorphInterpolation::kStep ? "STEP" : "LINEAR";
  tinygltf::Animation anim;
  anim.name = options.clip_name;
  anim.samplers.resize(1);
  anim.samplers[0].input = input;
  anim.samplers[0].output = output;
  anim.samplers[0].interpolation = interp;
  anim.channels.resize(1);
  anim.channels[0].sampler = 0;
  anim.channels[0].target_node = 0;
  anim.channels[0].target_path = "weights";
  b.model().animations = {anim};
}

}  // namespace

void save_rig(const Rig& rig, const std::string& path) {
  const std::string ext = gltf::extension(path);
  require(ext == ".glb" || ext == ".gltf", path, "extension must be .glb or .gltf",
          "name the file *.glb (binary) or *.gltf (JSON)");
  validate(rig);
  const std::size_t nj = rig.joints.size();
  check_joint_names(rig, path);
  const OutputView out = output_view(rig, path);

  gltf::Builder b;
  tinygltf::Model& d = b.model();
  const JointNodes joint_nodes = add_joint_nodes(d, rig, path);

  // Vertex data over output vertices.
  const std::vector<float> pos = output_positions(rig.rest, out.to_welded);
  const std::vector<float> nrm = vertex_normals(pos, out.triangles);
  const bool weighted = !rig.weights.empty();
  int sets = 0;
  Influences infl;
  if (weighted) infl = sorted_influences(rig, sets);
  require(nj <= 65536, path, "has more than 65536 joints", "glTF joints are 16-bit indices");
  const SkinnedVertices sv{out, pos, nrm, infl, sets, nj, rig.relax_mask};
  d.meshes.resize(1);
  d.meshes[0].name = "isokit_mesh";
  for (std::size_t p = 0; p + 1 < out.primitive_offsets.size(); ++p) {
    const int f0 = out.primitive_offsets[p];
    const int f1 = out.primitive_offsets[p + 1];
    if (f0 != f1) d.meshes[0].primitives.push_back(skinned_primitive(b, sv, f0, f1));
  }

  add_skin(b, rig, joint_nodes.roots);
  for (const Clip& clip : rig.clips)
    if (clip.frame_count() > 0) write_animation(b, rig, clip, joint_nodes.rest, path);
  b.write(path, ext == ".glb");
}

void write_baked_glb(const Rig& rig, const std::vector<track::Positions>& frames, double fps,
                     const std::string& path, const BakedGlbOptions& options) {
  check_bake(rig, frames, fps, path);
  const Eigen::Index nw = rig.rest.rows();
  const OutputView out = output_view(rig, path);
  const std::size_t nout = out.to_welded.size();
  const std::size_t nk = frames.size();
  const std::uint64_t limit =
      std::min<std::uint64_t>(options.max_bytes, std::numeric_limits<std::uint32_t>::max());

  gltf::Builder b;
  tinygltf::Model& d = b.model();
  const std::vector<float> rest = output_positions(rig.rest, out.to_welded);
  const std::vector<float> rest_n = vertex_normals(rest, out.triangles);
  tinygltf::Primitive primitive;
  Attributes& attrs = primitive.attributes;
  attrs["POSITION"] = b.add_floats(rest.data(), nout, "VEC3", true, gltf::kArrayBuffer);
  if (options.normals) attrs["NORMAL"] = b.add_floats(rest_n.data(), nout, "VEC3", false, gltf::kArrayBuffer);
  std::vector<int> all(nout);
  for (std::size_t i = 0; i < nout; ++i) all[i] = static_cast<int>(i);
  add_mask(b, rig.relax_mask, out.to_welded, all, attrs);
  std::vector<std::uint32_t> idx;
  for (Eigen::Index f = 0; f < out.triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k) idx.push_back(static_cast<std::uint32_t>(out.triangles(f, k)));
  const int indices = add_indices(b, idx, nout);

  Eigen::AlignedBox3f box;
  for (Eigen::Index v = 0; v < nw; ++v) box.extend(rig.rest.row(v).transpose());
  const float pos_eps =
      options.sparse ? static_cast<float>(options.sparse_epsilon * box.diagonal().norm()) : 0.0f;
  const float nrm_eps = options.sparse ? static_cast<float>(options.sparse_epsilon) : 0.0f;
  const DeltaWriter deltas{b, nout, options.sparse};
  tinygltf::Value::Array target_names;
  std::vector<float> delta(3 * nout);
  std::vector<float> posed(3 * nout);
  for (std::size_t k = 0; k < nk; ++k) {
    for (std::size_t i = 0; i < nout; ++i)
      for (int c = 0; c < 3; ++c) {
        const std::size_t at = 3 * i + static_cast<std::size_t>(c);
        posed[at] = frames[k](out.to_welded[i], c);
        delta[at] = posed[at] - rest[at];
      }
    Attributes target;
    target["POSITION"] = deltas.add(delta, pos_eps);
    if (options.normals) {
      const std::vector<float> n = vertex_normals(posed, out.triangles);
      for (std::size_t i = 0; i < 3 * nout; ++i) delta[i] = n[i] - rest_n[i];
      target["NORMAL"] = deltas.add(delta, nrm_eps);
    }
    primitive.targets.push_back(target);
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05zu", k);
    target_names.emplace_back(std::string(name));
    require(
        b.binary_size() <= limit, path,
        "the baked file passes " + std::to_string(limit) + " bytes at frame " + std::to_string(k) + " of " +
            std::to_string(nk),
        "bake fewer frames, turn normals off, raise BakedGlbOptions::max_bytes (GLB cap 4 GiB), or write PLY "
        "frames");
  }
  primitive.indices = indices;
  primitive.mode = TINYGLTF_MODE_TRIANGLES;
  d.meshes.resize(1);
  d.meshes[0].name = options.clip_name;
  d.meshes[0].primitives = {primitive};
  d.meshes[0].weights.assign(nk, 0.0);
  d.meshes[0].weights[0] = 1.0;
  d.meshes[0].extras =
      tinygltf::Value(tinygltf::Value::Object{{"targetNames", tinygltf::Value(target_names)}});
  d.nodes.resize(1);
  d.nodes[0].name = options.clip_name;
  d.nodes[0].mesh = 0;
  d.defaultScene = 0;
  d.scenes.resize(1);
  d.scenes[0].nodes = {0};
  add_morph_animation(b, nk, fps, options);
  require(b.binary_size() <= limit, path, "the baked file passes " + std::to_string(limit) + " bytes",
          "bake fewer frames or raise BakedGlbOptions::max_bytes");
  b.write(path, true);
}

void write_pc2(const Rig& rig, const std::vector<track::Positions>& frames, const std::string& path) {
  require(gltf::extension(path) == ".pc2", path, "extension must be .pc2", "name the file *.pc2");
  check_frames(rig, frames, path);
  const OutputView out = output_view(rig, path);
  const std::size_t nout = out.to_welded.size();
  constexpr auto kMax = static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max());
  require(nout <= kMax && frames.size() <= kMax, path, "has more points or frames than PC2's int32 counts",
          "bake fewer frames");
  write_stream_atomically(path, [&](std::ostream& stream) {
    std::vector<char> buf;
    const char signature[12] = "POINTCACHE2";  // 11 characters and the terminating zero
    buf.insert(buf.end(), signature, signature + 12);
    put_u32(buf, 1);                                          // version
    put_u32(buf, static_cast<std::uint32_t>(nout));           // numPoints
    put_f32(buf, 0.0f);                                       // startFrame
    put_f32(buf, 1.0f);                                       // sampleRate: one sample per frame
    put_u32(buf, static_cast<std::uint32_t>(frames.size()));  // numSamples
    stream.write(buf.data(), static_cast<std::streamsize>(buf.size()));
    for (const track::Positions& frame : frames) {
      buf.clear();
      for (const int w : out.to_welded)
        for (int k = 0; k < 3; ++k) put_f32(buf, frame(w, k));
      stream.write(buf.data(), static_cast<std::streamsize>(buf.size()));
    }
  });
}

void write_ply(const std::string& path, const track::Positions& positions,
               const track::Triangles& triangles) {
  const Eigen::Index nv = positions.rows();
  for (Eigen::Index f = 0; f < triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      require(triangles(f, k) >= 0 && triangles(f, k) < nv, path + ": triangle " + std::to_string(f),
              "vertex index out of range", "indices must lie in [0, " + std::to_string(nv) + ")");
  write_stream_atomically(path, [&](std::ostream& out) {
    out << "ply\nformat binary_little_endian 1.0\ncomment isokit\nelement vertex " << nv
        << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << triangles.rows()
        << "\nproperty list uchar int vertex_indices\nend_header\n";
    std::vector<char> buf;
    buf.reserve(static_cast<std::size_t>(std::max<Eigen::Index>(nv * 12, triangles.rows() * 13)));
    for (Eigen::Index v = 0; v < nv; ++v)
      for (int k = 0; k < 3; ++k) put_f32(buf, positions(v, k));
    out.write(buf.data(), static_cast<std::streamsize>(buf.size()));
    buf.clear();
    for (Eigen::Index f = 0; f < triangles.rows(); ++f) {
      buf.push_back(3);
      for (int k = 0; k < 3; ++k) put_u32(buf, static_cast<std::uint32_t>(triangles(f, k)));
    }
    out.write(buf.data(), static_cast<std::streamsize>(buf.size()));
  });
}

}  // namespace isokit::skinning
