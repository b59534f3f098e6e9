// SPDX-License-Identifier: MIT
/// \file
/// The 2014 iso-surface tracker (Robust Iso-Surface Tracking, §5) over a triangle mesh.
///
/// Pipeline of one `track()` call, starting from the caller's initial positions (2014 stage 1:
/// the previous result moved by the bones' rigid deltas):
/// 1. up to `initial_newton_steps` Newton projections `p <- p + σ (iso - f(p)) ∇f / |∇f|²`
///    (step length clamped, see Options);
/// 2. iterations of one Jacobi step of the ARAP energy
///    `E = Σi Σj wij ||(p̂i - p̂j) - Ri (pi - pj)||²` (cotangent weights at rest, prescribed Ri)
///    restricted to the tangent plane of the last evaluated gradient, scaled by the vertex's
///    relaxation mask, followed by one Newton projection — until the largest move is below
///    `tolerance` or `max_iterations`. The Jacobi steps are Chebyshev-accelerated
///    (`chebyshev_rho`; 0 = plain Jacobi as in 2014);
/// 3. localised Laplacian smoothing with diffused β at contact vertices (2013 §5, eq. 7), then
///    (`fold_repair`) more smoothing around the triangles still inverted, then
///    (`orientation_repair`) single-vertex moves that turn the last ones the right way.
/// Contacts: flagged by the field, or (rule on) the gradient turned by more than
/// `contact_angle` between two consecutive evaluations, or (`fold_contacts`) a vertex of a
/// triangle left inverted by the relaxation. Every turn halves the vertex's Newton and tangential
/// steps for the rest of the call (floor `min_contact_damping`), and a vertex flagged by the
/// angle rule takes unrestricted (3D) Jacobi steps: on a contact valley the gradient direction
/// says nothing about the surface (a deviation from 2013, which stops the vertex).
/// All updates are double-buffered (Jacobi); results do not depend on `grain`.
/// See docs/tracking.md for the equations and every deviation from the papers.
#pragma once

#include <vector>

#include "isokit/track/field.h"
#include "isokit/track/mesh.h"

namespace isokit::track {

/// β-diffused Laplacian smoothing at contacts (2013 §5 eq. 7; "a few steps", no values given).
struct SmoothingOptions {
  int beta_diffusion_steps{2};  ///< β <- mean of β over the closed one-ring, repeated
  int smoothing_steps{3};       ///< v <- (1 - β) v + β centroid(one-ring), repeated
};

/// Fold repair after the contact smoothing (not in the papers; docs/tracking.md, "Fold repair"):
/// the triangles still inverted are found again (QUALITY.md's test, at their centroids), and
/// their vertices with `rings` rings of neighbours around them take `steps` more Laplacian steps
/// (β = 1); repeated until none is left or `rounds` times. A fold the contact smoothing did not
/// untangle is a few edges wide; the rings reach past it.
struct FoldRepairOptions {
  int rounds{8};  ///< 0 = off
  int steps{5};   ///< Laplacian steps per round
  int rings{2};   ///< neighbour rings added around the inverted triangles' vertices
  /// No repair in a call whose inverted triangles' vertices exceed this fraction of the mesh: the
  /// field then disagrees with the mesh broadly (an under-resolved rig: 37 % on the 290-vertex
  /// Fox sample, at most 3.8 % on the folds of the procedural rigs) and smoothing would erase the
  /// shape instead of untangling a fold.
  double max_fraction{0.1};
};

/// Orientation repair after the fold repair (not in the papers; docs/tracking.md, "Orientation
/// repair"): a triangle still inverted lies across a contact valley's floor or the apex of a
/// contact slit, where the gradient turns within a fraction of an edge, with its centroid a hair
/// on the wrong side. Each vertex of such a triangle, one at a time, moves to the best of a few
/// candidate positions along its normal, the field's inward direction at it and the normals of
/// its inverted triangles: fewest inverted triangles around it, then the least
/// `Σ max(0, n̂·∇f/|∇f| + margin)` over them; a candidate whose triangles would cross any other
/// triangle of the mesh is refused. Repeated up to `rounds` times while a vertex moves.
struct OrientationRepairOptions {
  int rounds{8};   ///< 0 = off
  int samples{8};  ///< candidate steps inward per direction, evenly up to `max_move`
  /// Longest move into the skin (against the vertex normal and along the field's inward
  /// direction), times the mean length of the vertex's edges.
  float max_move{0.5f};
  /// Longest move out of the skin, times the same length: outward is where the skin facing it
  /// across a contact lies (without the crossing test, moves of half an edge made the 13k knee
  /// intersect itself; with it, 1/16, 1/8, 1/4 and 1/2 all leave 0 pairs, and 1/8 the fewest
  /// inverted triangles without stretching edges: docs/tracking.md).
  float max_outward_move{0.125f};
  float margin{0.05f};  ///< makes near-perpendicular triangles count in the energy
  /// No repair in a call whose inverted triangles' vertices exceed this fraction of the mesh (as
  /// FoldRepairOptions::max_fraction).
  double max_fraction{0.1};
};

/// How the tangential ARAP energy is minimised between Newton projections (2014 §5.2).
enum class Relaxation {
  kJacobi,            ///< one Jacobi sweep per iteration (2014), Chebyshev-accelerated
  kConjugateGradient  ///< the active vertices' tangent-plane system solved by CG per iteration
};

struct TrackerOptions {
  float sigma{1.0f};             ///< Newton step scale (2014 uses plain Newton iterations: 1)
  int initial_newton_steps{10};  ///< stage-2 projection steps before the relaxation
  int max_iterations{100};       ///< Jacobi + Newton iterations (2014 Table 1: 10..600)
  /// Stop when the largest move of an iteration is below `tolerance * rest bbox diagonal`.
  float tolerance{1e-5f};
  /// A Newton step is at most `max_step * (mean rest length of the vertex's edges)` long.
  float max_step{0.5f};
  /// Cotangents are clamped to [0, max_cotangent] per triangle corner (see docs).
  float max_cotangent{10.0f};
  float min_gradient{1e-6f};       ///< |∇f| below this: vertex lost, left in place
  bool angle_contacts{true};       ///< detect contacts by the 2013 gradient-angle rule
  float contact_angle_deg{55.0f};  ///< 2013 §5
  /// 3 β-diffusion and 5 smoothing steps (the 2013 projector keeps 2 and 3): the deeper 2014
  /// contact folds need the wider smoothing (docs/tracking.md, deviations).
  SmoothingOptions smoothing{3, 5};
  std::size_t grain{1024};  ///< parallel_for grain (0 = serial)
  /// Each gradient turn by more than `contact_angle_deg` halves the vertex's Newton and tangential
  /// steps for the rest of the call, down to this factor (in (0, 1]; not in the papers).
  float min_contact_damping{0.25f};
  /// Chebyshev semi-iterative acceleration of the Jacobi relaxation (Wang 2015, not in 2014):
  /// the assumed spectral radius of the Jacobi iteration, in [0, 1). 0 = plain Jacobi (2014).
  float chebyshev_rho{0.995f};
  /// Vertices of triangles still inverted after the relaxation (a crease the angle rule missed)
  /// are contact vertices too, so that the contact smoothing sees them (not in the papers).
  bool fold_contacts{true};
  /// Rounds of extra smoothing of the triangles still inverted after the contact smoothing.
  FoldRepairOptions fold_repair{};
  /// Vertex moves that turn the triangles left inverted after the fold repair the right way.
  OrientationRepairOptions orientation_repair{};
  /// Fold test and inverted-triangle statistics: false = only the triangles whose normal deviates
  /// by more than 45° from -∇f at one of their vertices (or with a contact or lost vertex, or
  /// inverted at rest or in the last call) are tested at their centroid — about 5 % of them on a
  /// bent humanoid; a triangle inverted only at its centroid (rare: a few per 10⁴ calls on the
  /// humanoid) is then missed. true = every triangle (exact, two field evaluations per vertex more).
  bool test_all_triangles{false};
  /// Relaxation solver. 2014 runs one Jacobi sweep per Newton projection and names CG as the
  /// faster alternative (§5.2); see docs/tracking.md for the measured trade-off.
  Relaxation relaxation{Relaxation::kJacobi};
  int cg_max_iterations{200};  ///< CG iterations per relaxation iteration (kConjugateGradient)
  /// The CG system covers the vertices that moved by more than the tolerance grown by this many
  /// rings (≥ 1; kConjugateGradient).
  int cg_rings{2};
  /// Lazy field evaluation (not in the papers): a vertex whose last evaluated Newton step was
  /// short, on a smooth part of the field (no contact, gradient turned by < 10°), takes its next
  /// Newton steps on the field linearised at that evaluation, without evaluating it, while it stays
  /// within a trust radius of it. The radius starts at twice the tolerance and follows the error
  /// the linearisation made the last time (half the tolerance per move), at most
  /// sqrt(2 · tolerance · ℓ) (ℓ: the mean rest edge length; the curvature bound of a surface the
  /// mesh resolves). Before a call counts as converged every vertex so moved is evaluated again;
  /// at the iteration cap they take one evaluated Newton step. false = one field evaluation per
  /// active vertex and iteration (2014). See docs/tracking.md.
  bool lazy_evaluation{true};
  /// Work on the vertices in a spatial (Morton) order internally, so that the neighbours a Jacobi
  /// step reads share cache lines (inputs and outputs stay in the caller's order; results equal
  /// the unordered run up to floating-point rounding: neighbour sums run in another order).
  /// 1.4x faster on the procedural humanoid, whose mesher emits vertices in random order.
  bool reorder_vertices{true};
};

/// Stateful tracker: precomputes weights and adjacency, then tracks many times.
class IsoSurfaceTracker {
 public:
  /// \param rest `#V by 3` rest positions; \param triangles `#F by 3`;
  /// \param iso `#V` target iso-values (e.g. `sample_iso_values` at rest).
  /// \throw InputError naming the item for mismatched sizes, non-finite values, bad indices,
  /// or invalid options.
  IsoSurfaceTracker(const Positions& rest, const Triangles& triangles, std::vector<float> iso,
                    TrackerOptions options = {});

  /// Per-vertex relaxation mask in [0, 1] (0 = no tangential move; default all 1).
  /// \throw InputError for a wrong size or a value outside [0, 1].
  void set_relaxation_mask(std::vector<float> mask);

  /// Vertices the fold and orientation repairs may move (1) or must leave in place (0); empty (the
  /// default): all.
  /// For callers that know where the mesh under-resolves the field (e.g. limbs of a few dozen
  /// vertices, where smoothing would erase the shape). \throw InputError for a wrong size.
  void set_fold_repair_mask(std::vector<std::uint8_t> mask);

  /// Records the triangles that are inverted at rest with respect to `rest_field` (the field at
  /// the rest pose: a composed field can disagree with the rest mesh in concave creases). With
  /// `fold_contacts`, those triangles are not treated as folds (their vertices are not smoothed
  /// in every call). \throw InputError for an empty field.
  void mark_rest_inversions(const FieldFunction& rest_field);

  /// Tracks the field from `positions` (in: initial guess, out: result).
  /// \param rotations `#V` target rotations Ri, or empty for identity.
  /// \throw InputError for wrong sizes or non-finite positions / rotations.
  TrackStats track(const FieldFunction& field, const std::vector<Mat3f>& rotations, Positions& positions);

  /// Per-vertex flags of the last call, in the caller's vertex order.
  const VertexFlags& flags() const { return flags_; }
  /// One-ring adjacency in the caller's vertex order (built on each call).
  Adjacency adjacency() const;
  /// Cotangent weights aligned with `adjacency().neighbors` (symmetric, ≥ 0; built on each call).
  std::vector<float> weights() const;
  const TrackerOptions& options() const { return options_; }

 private:
  // Everything per vertex below is in the internal order: internal vertex k is the caller's
  // vertex order_[k] (empty: the same order), rank_ the inverse.
  std::vector<int> order_, rank_;
  Triangles triangles_;
  std::vector<Vec3f> rest_pts_;
  std::vector<float> iso_;
  TrackerOptions options_;
  Adjacency adj_;
  std::vector<float> weights_, weight_sum_, max_step_, mask_;
  std::vector<std::uint8_t> repair_mask_;  // fold repair: may move (empty: all)
  std::vector<float> lazy_r2_;             // squared lazy evaluation radius per vertex
  float diagonal_{0};
  VertexFlags flags_;                        // caller's order
  Adjacency vertex_faces_;                   // CSR: the triangles around each vertex
  std::vector<std::uint8_t> rest_inverted_;  // per triangle (empty: none recorded)
  std::vector<std::uint8_t> last_inverted_;  // per triangle, at the end of the last call
};

}  // namespace isokit::track
