// SPDX-License-Identifier: MIT
/// \file
/// Options of the 2014 iso-surface tracker (`IsoSurfaceTracker`, tracker.h). Each option states
/// its meaning, unit, default and source: a paper section, or "not in the papers" with the section
/// of docs/tracking.md that explains and measures it. Lengths relative to the mesh are in units
/// of a vertex's mean rest edge length ("edges") or of the rest bounding-box diagonal.
#pragma once

#include <cstddef>

#include "isokit/track/energy_tracker.h"

namespace isokit::track {

/// β-diffused Laplacian smoothing at contacts (2013 §5 eq. 7; the papers say "a few steps").
struct SmoothingOptions {
  /// Steps of β <- mean of β over the closed one-ring (count; default 2, the tracker uses 3).
  int beta_diffusion_steps{2};
  /// Steps of v <- (1 - β) v + β centroid(one-ring) (count; default 3, the tracker uses 5).
  int smoothing_steps{3};
  /// Smooth toward the one-ring centroid plus the vertex's rest Laplacian coordinate turned by
  /// the ARAP target rotations (`mean_j ½ (Ri + Rj)(pi - pj)`), so that a rigidly moved rest
  /// shape is left in place (true; 2014 tracker only, which has the target rotations), or toward
  /// the centroid alone (false, the default: 2013 eq. 7, which moves a vertex of a coarse mesh by
  /// up to an edge even at rest). Not in the papers; off by default because it keeps skin in real
  /// contacts from flattening (measured on the real rigs: docs/tracking.md, step 4 "Keeping the
  /// rest detail").
  bool keep_detail{false};
  /// Newton sweeps (one field evaluation each) over the smoothed vertices that are not in contact
  /// (the ring around the contacts) after the smoothing, back onto their iso-values, so that the
  /// smoothing does not leave skin shrunk inside the body; the contact vertices stay where the
  /// smoothing flattened the crease (count; default 0 here: none, as in 2013 §5; the tracker's
  /// default is 2; 2014 tracker only).
  /// Not in the papers; decided on the real rigs (docs/decisions/contacts-judged-by-overlap.md).
  int reproject_steps{0};
  /// Move each smoothed vertex within its tangent plane only: the step toward the centroid loses
  /// its component along the field's normal at the vertex (∇f/|∇f| at its last evaluation), and
  /// vertices on an open border are left alone, so that the smoothing takes the oscillation out
  /// of a crease without moving skin into the body or off its iso-value (true; 2014 tracker only,
  /// which has the normals), or the full step (false, the default: 2013 eq. 7, which on a coarse
  /// mesh moves contact vertices inward by up to an edge per call). Not in the papers; issue 42
  /// "contacts without shrinking", measured in docs/skinning-real-rigs.md.
  bool tangential{false};
};

/// Fold repair after the contact smoothing (not in the papers; docs/tracking.md, step 5 "Fold
/// repair"): the triangles still inverted are found again (QUALITY.md's test, at their
/// centroids), and their vertices with `rings` rings of neighbours take `steps` more Laplacian
/// steps (β = 1); repeated until none is left or `rounds` times.
struct FoldRepairOptions {
  int rounds{8};  ///< Repair rounds (count; default 8; 0 = off).
  int steps{5};   ///< Uniform Laplacian steps per round (count; default 5).
  int rings{2};   ///< Neighbour rings added around the inverted triangles' vertices (count; default 2).
  /// No repair in a call whose inverted triangles' vertices exceed this fraction of the mesh's
  /// vertices: the field then disagrees with the mesh broadly and smoothing would erase the shape
  /// (fraction in [0, 1]; default 0.1; measurements in docs/tracking.md, step 5).
  double max_fraction{0.1};
};

/// Orientation repair after the final statistics (not in the papers; docs/tracking.md, step 6
/// "Orientation repair"): each vertex of a triangle still inverted moves, one at a time, to the
/// best of a few candidate positions along its normal, the field's inward direction and the
/// normals of its inverted triangles — fewest inverted triangles around it, then the least
/// `Σ max(0, n̂·∇f/|∇f| + margin)` — unless one of its triangles would cross another triangle.
struct OrientationRepairOptions {
  int rounds{8};   ///< Rounds while a vertex moves (count; default 8; 0 = off).
  int samples{8};  ///< Candidate steps inward per direction, evenly up to `max_move` (count; default 8).
  /// Longest move into the skin (against the vertex normal, along the field's inward direction)
  /// (edges of the vertex at its current position; in (0, 4]; default 0.5).
  float max_move{0.5f};
  /// Longest move out of the skin, toward the skin facing it across a contact (edges; in
  /// [0, max_move]; default 0.125; the choice is measured in docs/tracking.md, step 6).
  float max_outward_move{0.125f};
  /// Added to each triangle's `n̂·∇f/|∇f|` in the energy, so that near-perpendicular triangles
  /// count (dimensionless, in [0, 1]; default 0.05).
  float margin{0.05f};
  /// No repair in a call whose inverted triangles' vertices exceed this fraction of the mesh's
  /// vertices, as FoldRepairOptions::max_fraction (fraction in [0, 1]; default 0.1).
  double max_fraction{0.1};
};

/// How the tangential ARAP energy is minimised between Newton projections (2014 §5.2).
enum class Relaxation {
  kJacobi,             ///< One Jacobi sweep per iteration (2014), Chebyshev-accelerated.
  kConjugateGradient,  ///< The active vertices' tangent-plane system solved by CG per iteration.
  /// The whole tangent-plane problem of 2014 eq. 3 – 4 (`Tᵀ L T u = Tᵀ g` over every vertex, L
  /// the rest cotangent Laplacian, T the tangent bases) solved exactly at each iteration — its
  /// factorisation, analysed once per tracker, serves as the preconditioner of the next solves —
  /// alternated with safeguarded Newton projections. Not in the papers (they solve by Jacobi
  /// sweeps); docs/tracking.md, "The global solve"; docs/decisions/global-tangent-solve.md.
  kGlobal,
  /// One energy, the ARAP energy of the rest mesh (rotations fitted per vertex) plus soft
  /// constraints toward each vertex's iso-value, its contact crease or its anchor, minimised by
  /// local–global iterations (EnergyTracker, energy_tracker.h; Projective Dynamics, Bouaziz et al.
  /// 2014). Replaces every stage of the call: no Newton projection, no contact smoothing, no fold
  /// or orientation repair; the prescribed rotations are not used. Not in the papers;
  /// docs/tracking.md, "The energy solve"; docs/decisions/tracker-one-energy.md.
  kEnergy
};

struct TrackerOptions {
  /// Newton step scale σ in `p <- p + σ (iso - f) ∇f / |∇f|²` (dimensionless, in (0, 1];
  /// default 1: 2014 §5 "standard Newton iterations"; 2013 §5 uses 0.35).
  float sigma{1.0f};
  /// Newton steps of the projection stage before the relaxation (count; default 10; 2014 §5
  /// stage 2 gives no count).
  int initial_newton_steps{10};
  /// Cap on the relaxation iterations, each one tangential step + one Newton step (count;
  /// default 100; 2014 Table 1 reports 10 – 600). With kGlobal an iteration is one exact
  /// tangential solve, a line search and up to 4 projection steps, and a call also stops (capped)
  /// when its tangential residual has not fallen by 10 % in 8 iterations.
  int max_iterations{100};
  /// Tangential tolerance: × the rest bounding-box diagonal (dimensionless; default 1e-5; the
  /// papers give none). **Converged** (TrackStats::converged) means, with kGlobal: the largest iso
  /// residual `|f(v) - iso_v|` of the vertices held to their iso-value and not in contact is ≤
  /// `iso_tolerance` and the tangential residual — the smaller of the largest move the next
  /// solve asks for and the largest move of the last iteration — is ≤ `tolerance` × diagonal; a
  /// call stopped by stagnation or the cap is capped.
  /// With kJacobi / kConjugateGradient (2014's test): the largest move of an iteration fell below
  /// `tolerance` × diagonal.
  float tolerance{1e-5f};
  /// Iso tolerance of the convergence test (field units; default 1e-3, QUALITY.md's iso residual).
  float iso_tolerance{1e-3f};
  /// kGlobal: Levenberg–Marquardt regularisation of the tangential solve, `eps Σj wij |d_i|²` per
  /// vertex: keeps the system positive definite where sliding costs no energy (a translation along
  /// a cylinder's axis) and anchors every connected component; it leaves the solution of a
  /// converged call unchanged, since d = 0 there (dimensionless, > 0; default 1e-4; not in the
  /// papers).
  float global_regularization{1e-4f};
  /// Longest Newton step (edges: the vertex's mean rest edge length; default 0.5; not in the
  /// papers; docs/tracking.md, "Deviations", Newton step length).
  float max_step{0.5f};
  /// Per-corner clamp of the cotangent weights to [0, max_cotangent] (dimensionless; default 10,
  /// an angle of ≈ 5.7°; not in the papers; docs/tracking.md, "Cotangent weights").
  float max_cotangent{10.0f};
  /// A vertex whose |∇f| is below this is lost and left in place (field units per length unit;
  /// default 1e-6; docs/tracking.md, "Bad input").
  float min_gradient{1e-6f};
  /// Detect contacts by the gradient-angle rule (2013 §5) (default true).
  bool angle_contacts{true};
  /// The gradient-angle rule's threshold between two consecutive evaluations (degrees, in
  /// (0, 180]; default 55: 2013 §5).
  float contact_angle_deg{55.0f};
  /// Contact smoothing (2013 §5 eq. 7): 3 β-diffusion and 5 smoothing steps (the 2013 projector
  /// keeps 2 and 3: docs/tracking.md, "Deviations", smoothing step counts), then 2 Newton sweeps
  /// of the smoothed vertices not in contact back onto their iso-values (`reproject_steps`; the
  /// paper preset: 2, 3, 0).
  SmoothingOptions smoothing{3, 5, false, 2};
  /// Free vertices: a vertex where the field at rest disagrees with the rest mesh — the field's
  /// inward direction ∇f/|∇f| at its rest position is more than this angle away from the inward
  /// vertex normal, or ∇f is not usable there — is not held to its iso-value: no Newton step, a
  /// plain Jacobi relaxation step in 3D instead of the tangent plane, no gradient-angle contact;
  /// the ARAP relaxation carries it with its neighbours (degrees, in (0, 180]; default 180 = off,
  /// every vertex tracked as in 2014; 60 is the value measured in docs/tracking.md, "Free
  /// vertices"; not in the papers). Takes effect once the tracker knows the rest field
  /// (IsoSurfaceTracker::set_rest_field).
  float free_vertex_angle_deg{180.0f};
  /// Largest task of the parallel loops (vertices; default 1024; 0 = serial). Results do not
  /// depend on it.
  std::size_t grain{1024};
  /// Each gradient turn by more than `contact_angle_deg` halves the vertex's Newton and tangential
  /// steps for the rest of the call, down to this factor (in (0, 1]; default 0.25; not in the
  /// papers; docs/tracking.md, "Deviations", angle rule in the 2014 tracker).
  float min_contact_damping{0.25f};
  /// Chebyshev acceleration of the Jacobi relaxation (Wang 2015; not in 2014): the assumed
  /// spectral radius of the Jacobi iteration (in [0, 1); default 0.995; 0 = plain Jacobi as in
  /// 2014; docs/tracking.md, step 2 and "Deviations", Jacobi iterations).
  float chebyshev_rho{0.995f};
  /// The vertices of triangles still inverted after the relaxation are contact vertices too, so
  /// that the contact smoothing sees them (default true; not in the papers; docs/tracking.md,
  /// step 3 and "Deviations", fold contacts).
  bool fold_contacts{true};
  /// Extra smoothing of the triangles still inverted after the contact smoothing (step 5).
  FoldRepairOptions fold_repair{};
  /// Vertex moves that turn the triangles left inverted after the fold repair (step 6).
  OrientationRepairOptions orientation_repair{};
  /// Fold test and inverted-triangle statistics over every triangle (true: exact, two field
  /// evaluations per vertex more) or only over the triangles whose normal deviates by more than
  /// 45° from -∇f at one of their vertices, or with a contact or lost vertex, or inverted at rest
  /// or in the last call (false; may miss a triangle inverted only at its centroid). Default
  /// false; not in the papers; docs/tracking.md, step 3 "Which triangles are tested".
  bool test_all_triangles{false};
  /// Relaxation solver (default kJacobi, 2014 §5.2; kGlobal converges on analytic fields in a
  /// number of iterations that does not grow with the mesh but loses to Jacobi on the real rigs'
  /// evaluation score, so it is not the default: docs/decisions/global-tangent-solve.md).
  Relaxation relaxation{Relaxation::kJacobi};
  /// CG iterations per relaxation iteration, with kConjugateGradient (count, ≥ 1; default 200).
  int cg_max_iterations{200};
  /// With kConjugateGradient, the CG system covers the vertices that moved by more than the
  /// tolerance grown by this many rings (count, ≥ 1; default 2).
  int cg_rings{2};
  /// Lazy field evaluation: a vertex on a smooth part of the field takes its next Newton steps on
  /// the field linearised at its last evaluation while it stays within a measured trust radius;
  /// every such vertex is evaluated again before a call converges (default true; false = one
  /// evaluation per active vertex and iteration, as in 2014; not in the papers;
  /// docs/tracking.md, step 2 "Lazy field evaluation").
  bool lazy_evaluation{true};
  /// Active set: each relaxation iteration updates only the vertices that moved by more than the
  /// tolerance in the previous one and their one-ring neighbours (default true; false = every
  /// vertex in every iteration while any moved, as in 2014; not in the papers; docs/tracking.md,
  /// step 2 "Active set"). Both stop on the same test (no vertex moved by more than the tolerance).
  bool active_set{true};
  /// Work on the vertices in a spatial (Morton) order internally; inputs and outputs stay in the
  /// caller's order, and results equal the unordered run up to rounding (neighbour sums in
  /// another order). Default true; not in the papers; docs/tracking.md, step 2 "Internal vertex
  /// order".
  bool reorder_vertices{true};
  /// With `relaxation = kEnergy`: the local–global solve's own options (weights, search, contact
  /// set-back, Anderson window, energy test; EnergySolveOptions). Its iteration cap, tolerances,
  /// contact rule, cotangent clamp, lost-gradient bound and grain are this struct's fields of the
  /// same names.
  EnergySolveOptions energy{};
};

}  // namespace isokit::track
