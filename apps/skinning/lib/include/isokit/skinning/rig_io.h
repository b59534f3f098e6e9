// SPDX-License-Identifier: MIT
/// \file
/// Rig files: `load_rig` reads a skinned character (glTF 2.0 .gltf/.glb through tinygltf, FBX and
/// COLLADA .dae through assimp); `save_rig` writes a rig as glTF 2.0 (through tinygltf) that
/// `load_rig` reads back with the same skinning; `write_baked_glb` writes a baked deformation (one
/// morph target per frame) that any glTF viewer plays; `write_pc2` writes it as a point cache
/// (Blender, 3ds Max); `write_ply` writes one posed mesh. Format details and limits:
/// docs/skinning-io.md.
///
/// Loading, in short: every skinned mesh (each glTF primitive is one) is merged into one mesh;
/// vertices with equal positions are welded for the deformation and `Rig::output` maps the
/// file's vertices back; all weight sets are read (any number of influences, JOINTS_1/WEIGHTS_1…
/// included); joints are the skin's joints plus the nodes that connect them, parents first, with
/// the bind pose (from the inverse bind matrices) as rest pose; clips are sampled at
/// `LoadOptions::fps` (linear / slerp). The mesh node's own transform is ignored for skinned
/// meshes (glTF rule, applied to every format): the skinned mesh lies in scene space.
///
/// Writers write atomically (isokit::write_file_atomically): no half-written file is left.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "isokit/skinning/rig.h"
#include "isokit/track/mesh.h"

namespace isokit::skinning {

/// How `load_rig` reads a file. File handling only: none of these comes from the papers.
/// Where a file keeps the painted relaxation mask (Rig::relax_mask; setup key `mask`,
/// docs/skinning.md "Rigid parts and the relaxation mask"). Values outside [0, 1] are clamped.
struct MaskSource {
  /// glTF: the custom vertex attribute read as the mask (a scalar per vertex: float, or normalized
  /// unsigned byte / short). Default "_RELAX_MASK"; empty: none.
  std::string attribute{"_RELAX_MASK"};
  /// Any format: the vertex-colour set (0 – 7: glTF COLOR_n, an FBX colour layer, a COLLADA set,
  /// in the order assimp reads them; assimp 5.2 does not read the layers' names) whose `channel`
  /// is the mask, instead of the attribute; -1 (default): none.
  int color_set{-1};
  /// Channel of that set: 0 = red (default), 1 = green, 2 = blue, 3 = alpha.
  int channel{0};
};

struct LoadOptions {
  /// Clip sampling rate in frames per second, > 0 (keys are sampled linearly / by slerp).
  /// Default 30.
  double fps{30};
  /// Welding distance as a fraction of the bounding-box diagonal (unitless, ≥ 0). Default 0:
  /// only exactly equal positions are welded.
  double weld_tolerance{0};
  /// Load only the skinned meshes whose mesh or node name equals this. Default empty: all.
  std::string mesh;
  /// Read the animations as clips. Default true; false skips them.
  bool clips{true};
  /// Load with empty weights, so that the pipeline computes heat-diffusion weights (Baran &
  /// Popović 2007). Default false: the file's weights.
  bool ignore_weights{false};
  /// Influences below this fraction of a vertex's total weight are dropped before
  /// renormalising (unitless, in [0, 1)). Default 0: all kept.
  float min_weight{0.0f};
  /// Read only the skeleton (the animated nodes and the nodes between them) at the file's node
  /// pose, and its clips: an animation-only file (no mesh needed). The rig has no vertices.
  /// Default false.
  bool skeleton_only{false};
  /// Read FBX, COLLADA and the other formats that go through assimp in a child process (POSIX
  /// fork), so that assimp's aborts, crashes, hangs and runaway allocations on malformed files
  /// (docs/fuzzing.md, "Known limits") end as an InputError naming the file instead of ending
  /// the caller's process. Default true; false reads in the calling process (the fuzz targets,
  /// which need coverage feedback from the loader). glTF is always read in process (tinygltf,
  /// fuzzed and fixed in isokit). Where fork() is unavailable the read is in process.
  bool isolate_importer{true};
  /// Wall-clock limit of that child process in seconds, > 0. Default 600 (the FBX rigs of
  /// docs/skinning-real-rigs.md load in about a second).
  double importer_timeout_seconds{600};
  /// Address-space limit of that child process in MiB; 0 = none. Default 8192 (the real rigs
  /// load in tens of MiB; a malformed COLLADA file grows past 4 GiB within a minute).
  std::size_t importer_memory_mib{8192};
  /// Where the file keeps the painted relaxation mask (Rig::relax_mask).
  MaskSource mask;
};

/// What `load_rig` found (for the CLI's summary); `warnings` lists everything it changed or
/// skipped (unskinned meshes, welded vertices with different weights, node pose ≠ bind pose…).
struct LoadReport {
  std::string format;        ///< the file's extension ("gltf", "glb", "fbx", "dae")
  int meshes{0};             ///< source meshes (glTF primitives) merged
  int file_vertices{0};      ///< output (unwelded) vertices kept
  int welded_vertices{0};    ///< `Rig::rest.rows()`
  int max_influences{0};     ///< most influences on one vertex (after `min_weight`)
  int dropped_triangles{0};  ///< triangles degenerate after welding (kept in the output mesh)
  bool weights_from_file{false};
  std::string mask_source;  ///< where Rig::relax_mask came from ("" = none)
  std::vector<std::string> warnings;
};

/// Reads a rigged mesh. Files with meshes and a skeleton but no skin weights load with empty
/// weights (glTF: a skin without JOINTS_0; other formats: unweighted bone nodes).
/// \throw InputError naming the file, the item and the fix: missing or unreadable file
/// (assimp's message included), malformed glTF container or JSON, no skinned mesh ("no skin"),
/// non-finite values, weights naming missing joints, zero-weight vertices, shear in a rest
/// transform, inconsistent bind poses between meshes.
Rig load_rig(const std::string& path, const LoadOptions& options = {}, LoadReport* report = nullptr);

/// Writes `rig` as glTF 2.0: `.glb` (binary) or `.gltf` (JSON with an embedded base64 buffer).
/// Output vertices (`Rig::output`), one primitive per source primitive, normals, JOINTS_n /
/// WEIGHTS_n sets of 4 (as many as the largest vertex needs), inverse bind matrices, the joint
/// hierarchy (rest_local as TRS) and the clips as LINEAR animations at each clip's fps.
/// \throw InputError for an invalid rig (`validate`), duplicate or empty joint names, another
/// extension, or an unwritable path.
void save_rig(const Rig& rig, const std::string& path);

/// glTF animation sampler interpolation of the morph weights ("LINEAR", "STEP").
enum class MorphInterpolation { kLinear, kStep };

/// How `write_baked_glb` encodes a bake. File encoding only: none of these comes from the papers.
struct BakedGlbOptions {
  /// Write per-frame vertex normals as NORMAL morph deltas. Default true.
  bool normals{true};
  /// Interpolation of the morph weights between frames. Default kLinear (blends neighbouring
  /// frames); kStep shows each frame as baked.
  MorphInterpolation interpolation{MorphInterpolation::kLinear};
  /// Use sparse delta accessors for frames where they are smaller than dense ones. Default true.
  bool sparse{true};
  /// Sparse only: position deltas shorter than this fraction of the bounding-box diagonal, and
  /// normal deltas shorter than this (unit normals), count as zero (unitless, ≥ 0). Default 0:
  /// only exact zeros.
  double sparse_epsilon{0};
  /// Name of the mesh, node and animation in the file. Default "baked".
  std::string clip_name{"baked"};
  /// Largest file written, in bytes; larger bakes are refused. Default 2 GiB (GLB's own cap is
  /// 4 GiB).
  std::uint64_t max_bytes{std::uint64_t{1} << 31};
};

/// Writes a baked deformation as a `.glb`: the rest mesh (`Rig::output` vertices at `rig.rest`),
/// one morph target per frame (position deltas of frame k; plus normal deltas) and an animation
/// of the morph weights, one-hot at frame k at time k / fps. `frames[k]` holds the welded
/// positions of frame k (`#V by 3`, V = `rig.rest.rows()`).
/// \throw InputError for empty or mis-sized frames, non-finite positions, fps ≤ 0, a file over
/// `max_bytes`, a path not ending in .glb, or an unwritable path.
void write_baked_glb(const Rig& rig, const std::vector<track::Positions>& frames, double fps,
                     const std::string& path, const BakedGlbOptions& options = {});

/// Writes a baked deformation as a PC2 point cache, the format Blender's Mesh Cache modifier and
/// 3ds Max's Point Cache read: a 32-byte header ("POINTCACHE2\0", version 1, number of points,
/// start frame 0, sample rate 1 frame, number of samples), then per frame the output vertices
/// (`Rig::output`: the file's vertex order, unwelded) as float32 x y z, little endian. Positions
/// are in the rig's own space and units, as in `write_baked_glb`. `frames[k]` holds the welded
/// positions of frame k (`#V by 3`, V = `rig.rest.rows()`).
/// \throw InputError for empty or mis-sized frames, non-finite positions, a path not ending in
/// .pc2, or an unwritable path (no file is left behind).
void write_pc2(const Rig& rig, const std::vector<track::Positions>& frames, const std::string& path);

/// Binary little-endian PLY (float x y z; uchar-count int vertex_indices).
/// \throw InputError for a triangle index out of range or an unwritable path.
void write_ply(const std::string& path, const track::Positions& positions, const track::Triangles& triangles);

}  // namespace isokit::skinning
