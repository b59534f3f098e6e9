// SPDX-License-Identifier: MIT
/// \file
/// Mesh-part fitting (2013 §4.1): a triangle sub-mesh and its bone segment give a compact HRBF
/// primitive in the bone's local frame, optionally sampled into a 32³ grid.
///
/// Pipeline: area-weighted random candidates on the triangles (seeded) → culling planes at `h`
/// (fraction of the bone length, the paper's eq. 2) from both bone ends → Poisson-disk selection
/// (greedy dart throwing over the candidates, radius bisected until `target_samples` to
/// `target_samples + 2` are kept) → one
/// closure point per joint end on the bone axis, `s` beyond the joint (`s` = joint to nearest
/// vertex), normal along the bone pointing outward → HRBF fit → `r` = largest distance from the
/// bone segment to a sample → `t_r`.
///
/// \note Field convention: values in [0, 1], inside > 0.5, gradients inward, compact support.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "isokit/implicit/field.h"
#include "isokit/implicit/grid_field.h"
#include "isokit/implicit/hrbf.h"

namespace isokit::implicit {

/// A bone's triangle sub-mesh in world (rest) coordinates. `triangles` index `vertices`.
struct MeshPart {
  std::string name = "part";
  std::vector<Vec3d> vertices;
  std::vector<std::array<int, 3>> triangles;
  Vec3d bone_start{};  ///< joint with the parent (b⁰)
  Vec3d bone_end{};    ///< joint with the child (b¹)
  /// More openings to close (world coordinates), e.g. the child joints of a branching part
  /// (hips, chest): each gets a closure point `PartFitOptions::opening_offset × s` beyond
  /// `joint` along `direction` (unit, pointing out of the part), `s` = joint to nearest vertex,
  /// normal `direction`.
  struct Opening {
    Vec3d joint{};
    Vec3d direction{};
  };
  std::vector<Opening> openings;
};

/// Options of the distance field of a part (`PartFitOptions::Field::distance`; not in the papers:
/// docs/decisions/part-fields-from-the-mesh.md). The part's triangles, closed by a dome over each
/// border loop, give a signed distance `d` (negative inside) sampled on a grid in the bone frame;
/// the field is `t_r(d)` (the 2013 remap) with the gradient `t_r'(d) ∇d` (∇d by central
/// differences of the sampled `d`), so its 0.5 iso-surface is the part's own skin.
struct DistanceFitOptions {
  /// Grid cells across the part's thinnest feature, in [1, 16]: the grid spacing is the
  /// `feature_percentile` thickness of the part (inward ray from a vertex along its normal to
  /// the far side) divided by this. Default 3.
  double cells_per_feature = 3.0;
  /// Percentile of the per-vertex thicknesses taken as the part's thinnest feature, in (0, 1).
  /// Default 0.25 (a quarter of the sampled vertices lie on thinner features: a few rays that
  /// hit a neighbouring fold early do not set the grid).
  double feature_percentile = 0.25;
  /// Grid nodes per axis, at least (the 2013 paper's 32) and at most: the memory is
  /// 16 bytes × n³ (32: 0.5 MiB, 64: 4 MiB, 96: 13.5 MiB, 128: 32 MiB). Defaults 32 and 64; both in
  /// [8, GridField::kMaxResolution] with min <= max.
  int min_resolution = 32;
  int max_resolution = 64;
  /// Height of the dome closing each border loop, as a fraction of the loop's radius times the
  /// cosine between the loop's outward normal and the bone (a hole at a bone end gets a half
  /// sphere, tangent to a tube's wall; a hole in the side a flat cap), in [0, 2]. Default 1.
  double cap_height = 1.0;
  /// The `r` of `t_r` (how far the field reaches out of the surface, and the depth at which it
  /// saturates at 1) is half the `width_percentile` thickness, in (0, 1]. Default 0.9 (about the
  /// part's radius on a limb: the field grades its whole inside).
  double width_percentile = 0.9;
  /// Rings of the neighbouring parts' triangles a part takes beyond its border before it is
  /// closed, in [0, 8] (read by the caller that cuts a mesh into parts: isokit-skin's FittedRig).
  /// With 0 the dome starts at the part's border and bends away from the skin there; with 1 or
  /// more the field follows the skin across the border and neighbouring fields agree there.
  /// Default 1.
  int overlap_rings = 1;
  /// How far the k-th overlap ring sinks below the skin: k × this × the vertex's mean edge
  /// length, along its inward normal, in [0, 1] (so that across the border the neighbour's own
  /// field holds its vertices, and the two surfaces do not meet in a crease). Default 0.2.
  double overlap_sink = 0.2;
  /// Passes of a [1 2 1] / 4 filter over the sampled signed distance along each axis, in [0, 8]:
  /// each rounds the field's creases (a coarse mesh's corners, the medial surface) over about a
  /// cell, at the cost of moving the 0.5 level off sharp corners. Default 0.
  int smoothing_passes = 0;
};

struct PartFitOptions {
  /// Poisson-disk samples wanted, in [4, 10000] (2013 §4.1: "50 ... always sufficient").
  int target_samples = 50;
  std::uint64_t seed = 1;          ///< seed of the candidates' generator: same seed, same samples
  int candidates_per_sample = 10;  ///< random surface candidates per wanted sample (>= 1; not in the papers)
  /// Culling planes at this fraction of the bone length from both ends, in [0, 0.5) (2013 eq. 2:
  /// h = 0.05).
  double cull_h = 0.05;
  bool close_start = true;  ///< closure point beyond bone_start (2013 §4.1, Fig. 3)
  bool close_end = true;    ///< closure point beyond bone_end (2013 §4.1, Fig. 3)
  /// Closure points of `MeshPart::openings` lie this fraction of `s` beyond their joint (not in
  /// the papers, which close bone ends at `s`: a branching part's cap at `s` reaches into its
  /// children and makes contact with them at rest; docs/skinning.md, "fitting").
  double opening_offset = 0.1;
  /// How the fit closes the part where its mesh is open (at its joints, or an open border):
  /// - `joints` (default; 2013 §4.1, Fig. 3): one point on the bone axis `s` beyond each closed
  ///   bone end (`close_start`, `close_end`) and one per `MeshPart::openings`;
  /// - `border_caps` (not in the papers): a dome of samples over each open border loop of the
  ///   part's triangles (`cap_height`), so the surface closes where the part's mesh ends,
  ///   whatever the joints' places; a part without a border gets no closure; `close_start`,
  ///   `close_end` and `openings` are not used;
  /// - `best` (not in the papers): both fits, and the one with the smaller `FittedPart::error`
  ///   is kept; where one of them throws, the other.
  /// docs/skinning.md, "Decision: closing a part at its borders" (why `joints` stays the default:
  /// `best` fits the parts closer, but the real-rig evaluation's tracking got worse).
  enum class Closure { joints, border_caps, best };
  Closure closure = Closure::joints;
  /// Height of a border cap's dome over its loop, as a fraction of the loop's radius, in [0, 2]
  /// (not in the papers; 1, a half sphere, like the paper's closure point `s` beyond a joint:
  /// the cap reaches into the neighbour, so the blend at the joint does not dent; measured in
  /// docs/skinning.md, "Decision: closing a part at its borders"). Default 1.
  double cap_height = 1.0;
  /// Support box = the samples' box grown by `support_margin × r` (> 0; grown further, up to 8×,
  /// until the field vanishes on its faces). Not in the papers.
  double support_margin = 1.0;
  bool sample_grid = true;   ///< also sample the field into a grid (2013 §6: 32³ textures)
  int grid_resolution = 32;  ///< grid nodes per axis, in [2, GridField::kMaxResolution] (2013 §6: 32)
  /// How every grid of the fit stores its nodes (grid_field.h): fixed16 (default, not in the
  /// papers: half the memory, error bounded by `GridField::quantisation_bound`) or float32.
  GridStorage grid_storage = GridStorage::fixed16;
  HrbfOptions hrbf{};  ///< the HRBF fit's options (hrbf.h)
  /// The kind of field a part gets:
  /// - `hrbf` (default; 2013 §4.1): an HRBF through ~`target_samples` Poisson-disk samples;
  /// - `distance` (not in the papers): the signed distance to the part's own closed surface
  ///   (`distance`); the HRBF options above are not used, `sample_grid` neither (always a grid).
  enum class FieldKind { hrbf, distance };
  FieldKind field = FieldKind::hrbf;
  DistanceFitOptions distance{};  ///< the distance field's options (FieldKind::distance)
};

/// The fitted primitive. `local` is in the bone frame: origin `bone_start`, +z along the bone
/// (x, y completed deterministically, `bone_frame`); `local_to_world` places it at rest.
struct FittedPart {
  std::shared_ptr<const HrbfField> local;
  std::shared_ptr<const GridField> grid;  ///< null unless `sample_grid`
  Rigid3d local_to_world{};
  double r{0};                      ///< t_r width: bone-to-farthest-sample distance
  std::vector<HrbfSample> samples;  ///< local frame, closure points last
  int closure_points{0};
  /// How far the primitive is from its part (world units): vertex → surface p95 plus surface →
  /// part p95 (fit_quality.h, 24³ lattice), the part closed by a flat fan over each border loop.
  /// What `Closure::best` compares. 0 for a distance field (its 0.5 level is the part's own
  /// surface; `field_agreement` measures it).
  double error{0};
  /// The grid if sampled, else the HRBF field.
  FieldPtr field() const;
};

/// Bone frame used by `fit_part`: origin at `a`, z along `b − a`, x along the world axis least
/// aligned with the bone (made orthogonal).
Rigid3d bone_frame(const Vec3d& a, const Vec3d& b);

/// The distance field of one part (`PartFitOptions::FieldKind::distance`, whatever `field`
/// says): the part's triangles closed by a dome over each border loop, their signed distance
/// sampled on a grid whose resolution follows the part's thinnest feature, remapped by `t_r`.
/// `r` is half the part's `width_percentile` thickness; `samples` stays empty and
/// `closure_points` counts the domes. \throw InputError naming `part.name`: zero-length bone,
/// empty part, indices out of range, non-finite vertices, options out of range, or a closed
/// surface with no inside.
FittedPart fit_part_distance(const MeshPart& part, const PartFitOptions& options = {});

/// Checks the distance field's options against their ranges. \throw InputError naming
/// `where + ".key"` (e.g. a setup file's "s.json.fit.distance", or "part: distance").
void check_distance_options(const DistanceFitOptions& options, const std::string& where);

/// Fits one part (`options.field`: HRBF or distance field). \throw InputError naming `part.name`: zero-length
/// bone, empty part, indices out of range, non-finite vertices, fewer than 4 usable samples, inward-oriented
/// triangles (the samples' normals point towards the bone on average), or a failed HRBF fit.
FittedPart fit_part(const MeshPart& part, const PartFitOptions& options = {});

/// Fallback primitive for a part whose HRBF cannot be bounded (docs/skinning.md, "No vertex
/// without a field"; not in the papers): a capsule field (`t_r` of the distance to a segment
/// minus a radius, `r` = the radius: 1 on the segment) sampled into a `grid_resolution`³ grid
/// (always, whatever `sample_grid` says; `local` stays null). Two capsules are tried, one on the
/// bone segment and one on the vertices' principal axis (through their centroid, spanning their
/// extent less the radius at each end), each with the median distance of the vertices to its
/// segment as radius; the one with the smaller vertex → surface plus surface → vertices p95
/// (fit_quality.h) is kept. \throw InputError naming `part.name`: empty part, non-finite
/// vertices, all vertices on one point.
FittedPart fit_capsule(const MeshPart& part, const PartFitOptions& options = {});

/// Fits every part; a part that throws is reported in `errors` (same index, empty when it
/// fitted) and its result is left empty, so the rest of a rig still fits.
std::vector<FittedPart> fit_parts(const std::vector<MeshPart>& parts, const PartFitOptions& options,
                                  std::vector<std::string>* errors);

}  // namespace isokit::implicit
