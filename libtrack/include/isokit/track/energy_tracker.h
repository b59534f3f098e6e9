// SPDX-License-Identifier: MIT
/// \file
/// An iso-surface tracker that minimises one energy by local–global iterations (Projective
/// Dynamics, Bouaziz et al. 2014; Projective Skinning, Komaritzan & Botsch 2018):
///
///   E(x, R, P, n) = Σi Σj∈N(i) wij ‖(xi − xj) − Ri (pi − pj)‖²  +  Σi (xi − Pi)ᵀ Bi (xi − Pi)  +  Σi Ki ‖xi
///   − ai‖²
///
/// with Bi = Wi (ε I + (1 − ε) ni niᵀ): the target term holds vertex i on the plane through its
/// target Pi with normal ni at full weight and along that plane at the fraction ε
/// (`tangent_weight`; ε = 1 is a point target, Bi = Wi I).
///
/// p: rest positions; wij: cotangent weights of the rest mesh (each corner's cotangent clamped to
/// [0, max_cotangent], halved); Ri: per-vertex rotations (one-ring ARAP, Sorkine & Alexa 2007);
/// Pi: per-vertex targets (projections onto the vertex's iso-value or onto a contact crease), ni
/// the unit search direction ∇f/|∇f| at the vertex when its target was found;
/// Wi = iso_weight · Ai / Ā and Ki = ki · anchor_weight · Ai / Ā (Ai: barycentric rest area of the
/// vertex, Ā: its mean over the vertices with area; a vertex without area counts as Ā), ki the
/// anchor stiffness, ai the call's anchors. Stiffness 1 pins a vertex at its anchor.
///
/// One `track()` call iterates, the field fixed (k = 1, 2, ...):
/// 1. **Local step** at xk: Ri by SVD of `Σj wij (pi − pj)(xi − xj)ᵀ` (reflections flipped); a
///    candidate target per vertex from a 1-D search along `∇f/|∇f|` at xi (Newton trial clamped to
///    `max_search` edges, then regula falsi inside a sign change or Newton again; the sample of
///    smallest |f − iso|). A gradient turning by more than `contact_angle_deg` along the search, or
///    the field's contact flag at xi, makes it a contact vertex: its candidate is the crease (3
///    bisections of the turn) set back by `contact_offset` on its own side, where ∇f points along
///    the vertex's inward normal (the field's flag alone: xi itself). A candidate replaces the
///    target only if it is not farther from xi (so E never rises), or if the old target misses its
///    iso-value by more than `iso_tolerance` and the candidate misses it by less (a reset). The
///    distance compared is the target term's, (xi − Pi)ᵀ Bi (xi − Pi) / Wi; with ε < 1 a plane
///    that no longer locates the iso-surface near xi (the candidate lies farther beyond it than
///    `iso_tolerance` / |∇f(xi)|) is also reset.
/// 2. **Global step**: Gk = argmin over x of E(x, R, P, n), the system `(2 L + B + K) x = Σj (wij
///    Ri + wji Rj)(pi − pj) + B P + K a` (`Lii = ½ Σj (wij + wji)`, `Lij = −½ (wij + wji)`),
///    pinned vertices eliminated, in double precision (CHOLMOD when available, else Eigen's
///    simplicial LLᵀ). With ε = 1 the matrix is the same for the 3 coordinates and factored once
///    per tracker and stiffness. With ε < 1 it couples them through the normals: conjugate
///    gradients from xk on the 3 × #unknowns system, preconditioned per coordinate by the factor of
///    `2 L + W + K` (the same for every normal: factored once per tracker and stiffness). Started from xk,
///    every conjugate-gradient iterate lowers E, so E never rises however many are taken.
/// 3. **Convergence** (EnergyTrackerOptions::energy_tolerance) of that plain step; if it holds, or
///    at `max_iterations`, the result is Gk. Otherwise x(k+1) is Gk accelerated by Anderson
///    (`anderson_window`); if its local step ends with a higher E than xk's, it is replaced by Gk.
/// All per-vertex loops are parallel over `grain`; results do not depend on it. TrackStats:
/// `backtracks` counts the rejected accelerated iterates; `vertex_updates` is #V × iterations;
/// residuals are over the unpinned vertices neither in contact nor lost, at the result.
///
/// \note Field convention (field.h): values in [0, 1], surface 0.5, inside > 0.5, gradients point
/// inward; triangles counter-clockwise seen from outside.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

#include "isokit/track/field.h"
#include "isokit/track/mesh.h"

namespace isokit::track {

namespace detail {
struct EnergyModel;
}

/// The energy solve's own options: its weights, target search, contact set-back, acceleration and
/// energy test (TrackerOptions::energy holds them for `Relaxation::kEnergy`). Lengths are in
/// "edges" (a vertex's mean rest edge length).
struct EnergySolveOptions {
  /// μ: weight of the target term, Wi = μ Ai / Ā (dimensionless, > 0; default 10; not in the
  /// papers: Projective Skinning's constraint weights are per-element areas likewise).
  float iso_weight{10};
  /// ε: the fraction of Wi that holds a vertex along its target's tangent plane (dimensionless, in
  /// (0, 1]; default 0.01, measured in docs/decisions/tracker-one-energy.md; 1: point targets). Below 1 a
  /// vertex slides along its iso-surface held only by the ARAP term, so tangential distortion relaxes in one
  /// global step instead of by W / (W + λ) per iteration; the global step then solves one 3 × #unknowns
  /// system by preconditioned conjugate gradients (see the file comment). Not in the papers: point-to-plane
  /// targets as in ICP (Chen & Medioni 1992); Projective Dynamics' constraints are point projections.
  float tangent_weight{0.01f};
  /// Weight of the anchor term at stiffness 1 (before pinning): Ki = ki · anchor_weight · Ai / Ā
  /// (dimensionless, ≥ 0; default 100, so k = 0.1 pulls as hard as the target term; not in the
  /// papers).
  float anchor_weight{100};
  /// Reach of the target search along ∇f from xi (edges, > 0; default 1.0; not in the papers).
  float max_search{1};
  /// Field evaluations along the search line per vertex and iteration, besides the one at xi and
  /// the 3 crease bisections of a contact (count, ≥ 1; default 4; not in the papers).
  int search_steps{4};
  /// How far a contact vertex's target is set back from the crease, on the vertex's own side
  /// (edges, ≥ 0; default 0.1; not in the papers): the target term is a penalty, so the ARAP term
  /// pushes a compressed contact vertex past its target; the set-back keeps it, and its triangles,
  /// on its own side. The crease itself is located to 1/8 of the search step that crossed it.
  float contact_offset{0.1f};
  /// Anderson acceleration over the last `anderson_window` iterates (count, 0 – 64; default 5; 0 =
  /// plain local–global iterations). Not in Projective Dynamics; Peng et al. 2018 ("Anderson
  /// Acceleration for Geometry Optimization and Physics Simulation"), E kept monotone by rejecting
  /// an accelerated iterate that raises it. The plain iterations relax tangential distortion at a
  /// rate that slows with the resolution: the target term holds a vertex where its last projection
  /// put it (tests/track/test_energy_tracker.cpp has the measurements).
  int anderson_window{5};
  /// Converged when (a) the plain global step lowers E by at most this fraction plus a floor,
  /// `E(xk) − E(Gk) ≤ energy_tolerance · E(xk) + Es`, `Es = (tolerance · diagonal)² · Σi (Wi + Ki +
  /// Σj wij)` (moves of `tolerance` everywhere: a call whose E falls to 0 converges), and (b) it
  /// moves no vertex by more than `tolerance` · diagonal. Every vertex has then either reached its
  /// iso-value within `iso_tolerance` or stopped moving: a vertex held off its iso-value by the
  /// ARAP term (the target term is a penalty), by the search's reach or by a contact counts as
  /// converged (TrackStats::max_residual reports it). Where the iterations contract slowly (soft
  /// sliding modes), converged positions can lie much farther than `tolerance` from the fixed
  /// point. (fraction, ≥ 0; default 1e-6; not in the papers).
  double energy_tolerance{1e-6};
};

/// Options of EnergyTracker (checked by its constructor): the solve's own and those it shares with
/// the 2014 tracker, with the meanings of TrackerOptions' fields of the same names (with
/// `Relaxation::kEnergy`, IsoSurfaceTracker passes its own). Lengths in edges or rest bounding-box
/// diagonals.
struct EnergyTrackerOptions : EnergySolveOptions {
  /// Per-corner clamp of the cotangent weights to [0, max_cotangent] (dimensionless, > 0; default
  /// 10 as TrackerOptions::max_cotangent; not in the papers).
  float max_cotangent{10};
  /// Gradient turn along the search that marks a contact (degrees in (0, 180]; default 55,
  /// Implicit Skinning 2013 §5).
  float contact_angle_deg{55};
  /// Detect contacts by the gradient turn (true, default; 2013 §5); false: only the field's flag.
  bool angle_contacts{true};
  /// Local–global iterations per call (count, ≥ 0; default 50).
  int max_iterations{50};
  /// Largest move of the plain global step that counts as stopped (rest bounding-box diagonals,
  /// ≥ 0; default 1e-5).
  float tolerance{1e-5f};
  /// |f − iso| under which a target counts as on its iso-value (field units, ≥ 0; default 1e-3;
  /// not in the papers). Also ends a vertex's search early at 1e-3 of it.
  float iso_tolerance{1e-3f};
  /// |∇f| at or below which a vertex is lost: its target is its position (no pull) and it is
  /// flagged (field units per length, ≥ 0; default 1e-6).
  float min_gradient{1e-6f};
  /// Vertices per parallel task (count; 0 = serial; default isokit::kDefaultGrain = 1024).
  std::size_t grain{1024};
};

/// Stateful tracker: precomputes weights, areas and the factor of the global step's matrix, then
/// tracks many times. Copyable (a copy refactors) and movable.
class EnergyTracker {
 public:
  /// \param rest `#V by 3` rest positions; \param triangles `#F by 3` (counter-clockwise seen from
  /// outside); \param iso `#V` target iso-values (e.g. `sample_iso_values` at rest).
  /// \throw InputError naming the item for mismatched sizes, non-finite values, bad indices or
  /// options outside their documented ranges.
  EnergyTracker(const Positions& rest, const Triangles& triangles, std::vector<float> iso,
                EnergyTrackerOptions options = {});
  EnergyTracker(const EnergyTracker& other);
  EnergyTracker(EnergyTracker&& other) noexcept;
  EnergyTracker& operator=(const EnergyTracker& other);
  EnergyTracker& operator=(EnergyTracker&& other) noexcept;
  ~EnergyTracker();

  /// Per-vertex anchor stiffness ki in [0, 1] (default all 0): 0 < k < 1 adds Ki ‖xi − ai‖²,
  /// k = 1 pins the vertex at its anchor (eliminated from the solve; its neighbours see it there).
  /// Refactors the matrix. \throw InputError for a wrong size or a value outside [0, 1] or NaN.
  void set_anchor_stiffness(std::vector<float> stiffness);

  /// Changes EnergyTrackerOptions::max_iterations for the next calls (count, ≥ 0), e.g. for a live
  /// preview that continues the solve by calling again at the same pose.
  /// \throw InputError for a negative count.
  void set_max_iterations(int iterations);

  /// A test run before each iteration of the next calls (empty, the default: none). kStop ends the
  /// iterations as the cap does (TrackStats::converged false, `interrupted` true; the positions are
  /// the last plain step Gk); kAbandon returns at once with those positions (`abandoned`; the flags
  /// stay the last finished call's).
  void set_interrupt(std::function<TrackInterrupt()> interrupt);

  /// Tracks `field` from `positions` (in: initial guess, out: result); the anchors are the initial
  /// positions. \throw InputError for an empty field, a wrong size or non-finite positions.
  TrackStats track(const FieldFunction& field, Positions& positions);
  /// As above with this call's anchors (`#V by 3`). \throw InputError also for wrong-sized or
  /// non-finite anchors.
  TrackStats track(const FieldFunction& field, Positions& positions, const Positions& anchors);

  /// Per vertex, from the last call: `contact` (its target is a contact crease or the field flagged
  /// it), `lost` (no usable gradient at the last local step); `beta` and `free` all 0.
  const VertexFlags& flags() const;
  /// The last call's energies: E(xk, Rk, Pk) after each local step, then E of the result. Never
  /// rises except after a local step with resets (`reset_log()`).
  const std::vector<double>& energy_log() const;
  /// Aligned with `energy_log()`: the targets the local step before each entry replaced by farther
  /// ones (resets: the old target off its iso-value by more than `iso_tolerance`, the new one less).
  const std::vector<int>& reset_log() const;
  const EnergyTrackerOptions& options() const;

 private:
  std::unique_ptr<detail::EnergyModel> model_;  // libtrack/src/energy_model.h
};

}  // namespace isokit::track
