// SPDX-License-Identifier: MIT
/// \file
/// The rig every part of isokit-skin works on: a welded triangle mesh at its bind (rest) pose,
/// a joint hierarchy with bind matrices, sparse skin weights and animation clips. Loaders
/// (rig_io.h) and the procedural rigs (procedural.h) produce it; the pipeline consumes it.
///
/// Conventions: joints are stored parents first (`joints[j].parent < j`, one or more roots with
/// parent -1). A joint's world transform at a pose is `world[parent] * local[j]`; its skinning
/// matrix is `world[j] * inverse_bind[j]`, the identity at the rest pose. Transforms are affine
/// 4x4 (rigid in practice; loaders reject shear and warn nothing silently). Triangles are
/// counter-clockwise seen from outside.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "isokit/track/mesh.h"

namespace isokit::skinning {

using Affine = Eigen::Transform<double, 3, Eigen::Affine>;

struct Joint {
  Joint(std::string name_ = {}, int parent_ = -1, const Affine& rest_local_ = Affine::Identity(),
        const Affine& inverse_bind_ = Affine::Identity(), std::string file_name_ = {})
      : name(std::move(name_)),
        parent(parent_),
        rest_local(rest_local_),
        inverse_bind(inverse_bind_),
        file_name(std::move(file_name_)) {}

  std::string name;  ///< unique in the rig: selects the joint (`--bend`, setup files, clips)
  int parent{-1};
  Affine rest_local{Affine::Identity()};    ///< local transform (relative to the parent) at rest
  Affine inverse_bind{Affine::Identity()};  ///< mesh space -> joint space at the bind pose
  /// The file's name when it differs from `name` (a name shared by several nodes: `name` is then
  /// `FILE_NAME#k`, docs/skinning-io.md); empty otherwise. For display only.
  std::string file_name;

  const std::string& display_name() const { return file_name.empty() ? name : file_name; }
};

/// Per-vertex sparse skin weights in CSR form: vertex `v` has influences
/// `joints[offsets[v] .. offsets[v+1])` with `weights[...]`; any number per vertex; each
/// vertex's weights are ≥ 0 and sum to 1 (see `validate`). Empty `offsets` = no weights.
struct SkinWeights {
  std::vector<int> offsets;
  std::vector<int> joints;
  std::vector<float> weights;

  bool empty() const { return offsets.empty(); }
  int count(int v) const { return offsets[v + 1] - offsets[v]; }
};

struct ClipKeys;

/// An animation clip at `fps`: either sampled frames, `local[frame][joint]` local joint transforms
/// (procedural clips, clips made in code), or a file's key tracks (`keys`, loaded clips), sampled
/// by `clip_frames` when a command needs the frames. Copies share the keys.
struct Clip {
  std::string name;
  double fps{30};
  std::vector<std::vector<Affine>> local;  ///< the frames; empty while the clip is only keyed
  std::shared_ptr<const ClipKeys> keys;    ///< a file's key tracks (rig/clip_keys.h); may be null

  /// Frames of the clip (`local.size()`, or the keys' span at `fps`, both ends included).
  std::size_t frame_count() const;
  /// Length in seconds, `(frame_count() - 1) / fps`.
  double seconds() const;
};

/// Most joint transforms (frames x joints) `clip_frames` samples one clip into: 2^22 (512 MiB of
/// transforms; an hour of 30 fps motion capture on 38 joints).
constexpr std::size_t kMaxClipSamples = std::size_t{1} << 22;

/// The frames of `clip`: `local` when it has frames, else its keys sampled at `fps`.
/// \throw InputError naming the clip when frames x joints pass `kMaxClipSamples` (with the fix: a
/// lower --fps) or a sampled transform is not finite.
std::vector<std::vector<Affine>> clip_frames(const Clip& clip);

/// How output (unwelded) vertices map to the welded deformation mesh: loaders weld duplicate
/// positions (split normals / UVs) for the deformation and write the original vertices back.
struct OutputMesh {
  std::vector<int> to_welded;             ///< per output vertex: index into `Rig::rest`
  track::Triangles triangles;             ///< triangles over output vertices
  std::vector<int> primitive_offsets{0};  ///< triangle ranges of the source mesh primitives
};

struct Rig {
  std::string name;            ///< file path or `procedural:...`, used in messages
  track::Positions rest;       ///< welded vertices, bind pose, mesh space
  track::Triangles triangles;  ///< over welded vertices
  SkinWeights weights;         ///< may be empty: the pipeline computes heat weights
  std::vector<Joint> joints;
  std::vector<Clip> clips;
  OutputMesh output;  ///< empty `to_welded`: output = welded mesh
  /// Painted relaxation mask per welded vertex, in [0, 1] (2014 Fig. 11; docs/skinning.md,
  /// "Rigid parts and the relaxation mask"): 0 = moved rigidly with its nearest bone, 1 = tracked,
  /// between = pulled toward the rigid position with weight 1 − m. Empty (the default): all 1.
  /// Read from the file (LoadOptions::mask), written to baked .glb files.
  std::vector<float> relax_mask;

  int joint_index(const std::string& name) const;  ///< -1 if absent
};

/// Samples every clip of `rig` that has only keys into its `local` frames (each as `clip_frames`),
/// for code that reads or edits frames directly. \throw InputError as `clip_frames`.
void sample_clips(Rig& rig);

/// Rest local transforms of every joint (the bind pose as a pose).
std::vector<Affine> rest_pose(const Rig& rig);
/// World transforms `world[j] = world[parent] * local[j]`.
std::vector<Affine> world_transforms(const Rig& rig, const std::vector<Affine>& local);
/// Skinning matrices `world[j] * inverse_bind[j]` (identity at rest).
std::vector<Affine> skinning_matrices(const Rig& rig, const std::vector<Affine>& local);
/// Joint positions (world origin of each joint) at the rest pose.
std::vector<Eigen::Vector3d> rest_joint_positions(const Rig& rig);

/// Checks every invariant above (sizes, finite values, indices, parent order, weights ≥ 0
/// summing to 1 within 1e-3, triangle indices, non-degenerate bind matrices, clip sizes).
/// \throw InputError naming `rig.name`, the item and the fix.
void validate(const Rig& rig);

/// Normalises each vertex's weights to sum 1, drops weights below `min_weight` (relative) and
/// merges repeated joints. Vertices with no positive weight throw InputError naming the vertex.
void normalize_weights(SkinWeights& w, int num_vertices, float min_weight = 0.0f,
                       const std::string& rig_name = "rig");

/// Index of the largest weight's joint per vertex (ties: the lower joint index).
std::vector<int> dominant_joint(const SkinWeights& w, int num_vertices);

}  // namespace isokit::skinning
