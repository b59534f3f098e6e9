// SPDX-License-Identifier: MIT
/// \file
/// Geometric skin-quality metrics of docs/QUALITY.md: self-intersections (exact predicates),
/// enclosed volume, edge distortion, displacement. The field-based metrics (inverted triangles,
/// iso residual, contact vertices) need the implicit field and are computed by the pipeline;
/// `FrameMetrics` has slots for them so that one struct carries a frame's numbers.
///
/// Meshes are plain arrays: `#V by 3` positions, `#F by 3` vertex indices (counter-clockwise seen
/// from outside). Every function throws `isokit::InputError` for an index out of range or
/// mismatched vertex counts, naming the item.
#pragma once

#include <array>
#include <cstddef>
#include <limits>
#include <memory>
#include <mutex>
#include <vector>

#include <Eigen/Geometry>

#include "isokit/skinning/folds.h"
#include "isokit/skinning/mesh_closure.h"
#include "isokit/skinning/self_overlap.h"
#include "isokit/track/mesh.h"

namespace isokit::skinning {

/// What `count_self_intersections` found besides the count.
struct SelfIntersectionDetails {
  /// Intersecting pairs `{f, g}` with `f < g`, in lexicographic order; at most `max_pairs`.
  std::vector<std::array<int, 2>> pairs;
  /// Degenerate triangles (three collinear corners, repeated indices included), ascending; at
  /// most `max_pairs`. They take no part in the pair tests.
  std::vector<int> degenerate_faces;
  int degenerate_count{0};       ///< all degenerate triangles (not capped)
  long long candidate_pairs{0};  ///< pairs whose bounding boxes overlap (broad phase)
};

struct SelfIntersectionOptions {
  int max_pairs{1000};  ///< cap on the lists in `SelfIntersectionDetails`
  /// Triangles per parallel task (space is cut into slabs of about this many); 0 = one serial
  /// pass. The result does not depend on it.
  std::size_t grain{16384};
};

/// Number of pairs of distinct, non-degenerate triangles that intersect beyond what they share
/// (CGAL `Polygon_mesh_processing::self_intersections` semantics, exact predicates):
/// - no shared vertex: counted if the closed triangles intersect at all (touching counts);
/// - one shared vertex: counted if they meet anywhere other than that vertex;
/// - two shared vertices (an edge): counted if they are coplanar and lie on the same side of it
///   (folded over each other);
/// - three shared vertices (a duplicated triangle, either orientation): counted.
/// Sharing is by vertex *index*: weld coincident vertices first. Degenerate triangles are left
/// out and reported in `details` (CGAL reports each as a pair `(f, f)`; its output size is
/// `count + degenerate_count`).
/// \throw InputError naming the triangle or vertex for an index out of range or a non-finite
/// coordinate.
int count_self_intersections(const track::Positions& positions, const track::Triangles& triangles,
                             SelfIntersectionDetails* details = nullptr,
                             const SelfIntersectionOptions& options = {});

/// Signed enclosed volume by the divergence theorem, `Σ_f (p0 · (p1 × p2)) / 6` with corners taken
/// relative to the bounding-box centre, in double. Positive for a closed mesh with outward
/// (counter-clockwise) triangles, negative when flipped; meaningful for closed meshes only.
double enclosed_volume(const track::Positions& positions, const track::Triangles& triangles);

struct EdgeDistortion {
  double mean{0};  ///< mean of `|len / len_rest - 1|` over unique undirected edges
  double max{0};
  std::array<int, 2> worst_edge{-1, -1};  ///< vertices of the edge reaching `max`
  int edges{0};                           ///< unique edges measured
  int zero_rest_edges{0};                 ///< edges of zero rest length, skipped
};

/// Length distortion of the unique edges of `triangles` from `rest` to `posed`.
EdgeDistortion edge_distortion(const track::Positions& rest, const track::Positions& posed,
                               const track::Triangles& triangles);

/// Largest vertex distance `max_i |a_i - b_i|` (0 for empty arrays).
double max_displacement(const track::Positions& a, const track::Positions& b);

/// Axis-aligned bounding box of the positions (an empty box for no vertices).
Eigen::AlignedBox3d bounding_box(const track::Positions& positions);

/// Length of the bounding-box diagonal (0 for fewer than two distinct points).
double bbox_diagonal(const track::Positions& positions);

/// One frame's numbers (docs/QUALITY.md). Integer fields are -1 and doubles NaN when not computed.
struct FrameMetrics {
  static constexpr double kNotComputed = std::numeric_limits<double>::quiet_NaN();

  int self_intersections{-1};      ///< `count_self_intersections`
  int self_intersections_new{-1};  ///< pairs that are not a rest pair (by identity, not by count)
  int degenerate_faces{-1};        ///< `SelfIntersectionDetails::degenerate_count`
  /// Interpenetration by volume (self_overlap.h): the volume the skin encloses twice (|winding
  /// number| >= 2), mesh units³.
  double self_overlap{kNotComputed};
  /// max(0, `self_overlap` − the rest frame's) / the rest mesh's enclosed volume (|w| >= 1): the
  /// share of the body that interpenetrates and did not at rest. The contact criterion
  /// (docs/skinning-metrics.md).
  double self_overlap_new{kNotComputed};
  /// The same volume for the deforming skin alone: the triangles of the rig's rigid pieces
  /// (rigid_pieces.h; they move with their bones in every method, and their overlap is the rig's
  /// own) are left out. Equal to `self_overlap` on a rig without rigid pieces. Mesh units³.
  double skin_overlap{kNotComputed};
  /// max(0, `skin_overlap` − the rest frame's) / the rest skin's enclosed volume (|w| >= 1): as
  /// `self_overlap_new`, for the skin alone. The contact criterion where it is present.
  double skin_overlap_new{kNotComputed};
  /// Triangles whose normal has turned by more than 90° from their rest normal carried by the
  /// skinning blend's rotation (folds.h): the skin folded onto itself. No field involved.
  int folded_triangles{-1};
  int folded_new{-1};           ///< `folded_triangles` that were not folded at rest. The fold criterion.
  double volume{kNotComputed};  ///< `enclosed_volume` of the closed components, mesh units³
  double volume_ratio{kNotComputed};          ///< volume / rest volume (NaN when no component is closed)
  double edge_distortion_mean{kNotComputed};  ///< `EdgeDistortion::mean` from rest, no unit
  double edge_distortion_max{kNotComputed};   ///< `EdgeDistortion::max` from rest, no unit
  double max_displacement{kNotComputed};      ///< from the rest positions, mesh units
  double rest_distance{kNotComputed};         ///< max_displacement / rest bounding-box diagonal
  // Field-based, filled by the pipeline:
  int inverted_triangles{-1};  ///< triangles whose normal points along +∇f (QUALITY.md "inverted")
  /// Inverted triangles that were not inverted at the rest pose (in concave regions the
  /// composed field can disagree with the rest mesh already; docs/skinning.md "Inverted triangles
  /// at rest").
  int new_inverted_triangles{-1};
  /// `|f(x_i) − iso_i|` over the vertices not in contact (field units; iso_i = the vertex's
  /// rest field value): largest and mean.
  double iso_residual_max{kNotComputed};
  double iso_residual_mean{kNotComputed};
  int contact_vertices{-1};  ///< vertices flagged in contact (field, tracker or projector)
};

/// Worst of two frames, field by field (largest counts and errors, volume ratio farthest from 1;
/// a field not computed in one frame takes the other's value).
FrameMetrics worst_of(const FrameMetrics& a, const FrameMetrics& b);

/// What the skin-only metrics need of the rig besides its mesh (all optional).
struct SkinReference {
  /// Skin weights (one entry per vertex) and the skinning matrices at the rest pose: with both,
  /// `evaluate` counts folds (folds.h) when given the pose's skinning matrices.
  SkinWeights weights;
  std::vector<Affine> rest_skin;
  /// Vertices of the rig's rigid pieces (find_rigid_pieces): every triangle with a corner among
  /// them is left out of `skin_overlap`. Empty: the skin is the whole mesh.
  std::vector<int> rigid_vertices;
};

/// Computes the geometric fields of `FrameMetrics` for many poses of one mesh: the constructor
/// stores the rest positions, the unique edges and their rest lengths, the closed components and
/// their rest volume; the rest mesh's intersecting pairs are found on the first `evaluate` that
/// counts self-intersections.
class FrameMetricsEvaluator {
 public:
  /// \throw InputError for an index out of range, or weights that do not fit the mesh.
  FrameMetricsEvaluator(track::Positions rest, track::Triangles triangles,
                        SelfIntersectionOptions options = {}, SkinReference skin = {});
  ~FrameMetricsEvaluator();

  /// Without `self_intersections` the exact pass (the slowest) is skipped: both counts stay -1;
  /// without `self_overlap` the overlap volumes are skipped (they stay NaN). With `skin` (the
  /// pose's skinning matrices) and weights in the `SkinReference`, folds are counted (else -1).
  /// \throw InputError if `posed` has a different vertex count from the rest mesh.
  FrameMetrics evaluate(const track::Positions& posed, bool self_intersections = true,
                        bool self_overlap = true, const std::vector<Affine>* skin = nullptr) const;

  /// The fold counter (null without weights in the `SkinReference`).
  const FoldCounter* folds() const { return folds_.get(); }
  /// The triangles of the deforming skin (all but the rigid pieces').
  const track::Triangles& skin_triangles() const { return skin_triangles_; }

  /// The rest mesh's volume enclosed twice and once (`self_overlap` at rest).
  const SelfOverlap& rest_overlap() const { return rest_overlap_; }

  const MeshClosure& closure() const { return closure_; }
  /// Rest volume of the closed components (0 when none is closed).
  double rest_volume() const { return rest_volume_; }
  double rest_diagonal() const { return rest_diagonal_; }
  /// The intersecting pairs of the rest mesh (all of them, sorted).
  const std::vector<std::array<int, 2>>& rest_pairs() const;

 private:
  track::Positions rest_;
  track::Triangles triangles_;
  track::Triangles closed_triangles_;  ///< of the closed components
  MeshClosure closure_;
  SelfIntersectionOptions options_;
  mutable std::once_flag rest_pairs_once_;
  mutable std::vector<std::array<int, 2>> rest_pairs_;
  std::vector<std::array<int, 2>> edges_;
  std::vector<double> rest_lengths_;
  double rest_volume_{0};
  double rest_diagonal_{0};
  SelfOverlap rest_overlap_;
  track::Triangles skin_triangles_;  ///< without the rigid pieces' triangles
  bool has_rigid_{false};            ///< some triangle was left out of `skin_triangles_`
  SelfOverlap rest_skin_overlap_;    ///< `self_overlap` of the skin alone at rest
  std::unique_ptr<FoldCounter> folds_;
};

}  // namespace isokit::skinning
