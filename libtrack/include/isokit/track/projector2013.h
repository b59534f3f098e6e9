// SPDX-License-Identifier: MIT
/// \file
/// The 2013 projector (Implicit Skinning §5), the baseline: from an initial skinning pose,
/// Newton steps with σ = 0.35, a vertex stops when its gradient turns by more than 55° between
/// two consecutive steps (contact); after every pair of Newton steps one mean-value-coordinate
/// tangential relaxation `v <- (1 - μ) v + μ Σ Φij qij` with the paper's
/// `μ = max(0, 1 - (|f(v) - iso| - 1)^4)`; then β-diffused Laplacian smoothing.
/// Φ are mean value coordinates of the one-ring projected onto the rest tangent plane
/// (normal = rest field gradient), so relaxation leaves the rest pose unchanged.
#pragma once

#include <vector>

#include "isokit/track/field.h"
#include "isokit/track/mesh.h"
#include "isokit/track/tracker_options.h"

namespace isokit::track {

struct ProjectorOptions {
  float sigma{0.35f};              ///< Newton step factor σ of eq. 4 (2013 §5: 0.35)
  float contact_angle_deg{55.0f};  ///< gradient turn between two steps that stops a vertex (2013 §5: 55°)
  /// Newton steps per call, the cap (2013 §5 gives none; isokit: 50). A call ends before it when
  /// every vertex has stopped by one of the rules below.
  int max_iterations{50};
  /// A vertex is at its iso-value when |f - iso| ≤ tolerance (field units); it then stops: it is
  /// neither evaluated nor relaxed again in the call (2013 §5 projects each vertex onto its
  /// iso-value; the relaxation's μ of eq. 6 is ≈ 4 |f - iso|, i.e. ≈ 0, there). Default 1e-3,
  /// the 2014 tracker's TrackerOptions::iso_tolerance (the `paper` preset: 1e-4; the paper gives
  /// none; docs/decisions/projector-stopping-rules.md).
  float tolerance{1e-3f};
  float max_step{0.5f};  ///< a Newton step is at most max_step × the vertex's mean rest edge length
  /// < 0: the paper's μ(|f - iso|) of eq. 6; ≥ 0: this constant (a stopped vertex is not relaxed).
  float mu{-1.0f};
  float min_gradient{1e-6f};  ///< |∇f| at or below this: no usable gradient, the vertex is lost
  /// No progress: a vertex whose residual |f - iso| has not fallen below `progress` × its smallest
  /// residual of the call for `stall_steps` consecutive Newton steps stops where it is
  /// (TrackStats::stalled_vertices): it oscillates across a seam of the composed field or is held
  /// by the relaxation. 0 = never (the `paper` preset: only the cap stops it). Default 3 steps,
  /// progress 0.9: an undisturbed σ = 0.35 Newton step divides the residual by ≈ 1.5.
  int stall_steps{3};
  float progress{0.9f};  ///< see stall_steps; in (0, 1]
  /// Secant-corrected steps (isokit; off in the `paper` preset: every step uses σ). Two
  /// consecutive samples of a vertex with no relaxation between them show how the field falls
  /// along the step: when the residual kept its sign, the next steps use the factor that reaches
  /// the iso-value on that secant, within [σ, secant_max_factor]; when it changed sign, the
  /// iso-value is bracketed and the vertex moves to the secant's zero between the two samples.
  bool secant{true};
  /// Largest Newton step factor of a secant-corrected step, in (0, 1] (below σ: σ). Default 0.7: measured
  /// on the real rigs against 0.5 and 1 (docs/decisions/projector-stopping-rules.md).
  float secant_max_factor{0.7f};
  /// TrackStats::inverted_triangles counted (one field evaluation per triangle at the end of the
  /// call). Off: it stays 0 (the skinning pipeline measures inverted triangles in its metrics).
  bool count_inverted{true};
  SmoothingOptions smoothing{};  ///< β-diffused Laplacian smoothing after the projection (2013 eq. 7)
  std::size_t grain{1024};       ///< vertices per parallel task (0: serial)
};

class Projector2013 {
 public:
  /// Samples iso-values and rest normals from `rest_field` at `rest`, computes the MVC.
  /// \throw InputError naming the item for bad sizes, indices, non-finite data.
  Projector2013(const Positions& rest, const Triangles& triangles, const FieldFunction& rest_field,
                ProjectorOptions options = {});

  /// Projects `positions` (in: skinning pose, out: result).
  TrackStats project(const FieldFunction& field, Positions& positions);

  /// One MVC relaxation step with the given μ and unit normals (`#V`), for tests and tools.
  void relax(const std::vector<Vec3f>& normals, float mu, Positions& positions) const;

  const std::vector<float>& iso_values() const { return iso_; }
  const VertexFlags& flags() const { return flags_; }
  const Adjacency& adjacency() const { return adj_; }

 private:
  /// The call's residual statistics from each vertex's last value and field contact flag; the
  /// vertices moved since (`stale`, or smoothed) are evaluated again. Contacts the field reports
  /// at the final positions join flags().contact. Inverted triangles: ProjectorOptions::count_inverted.
  void finish_statistics(const FieldFunction& field, const std::vector<Vec3f>& pts,
                         const std::vector<std::uint8_t>& stale, std::vector<float>& values,
                         std::vector<std::uint8_t>& field_contact, TrackStats& stats);

  Positions rest_;
  Triangles triangles_;
  std::vector<float> iso_;
  std::vector<Vec3f> rest_normals_;
  ProjectorOptions options_;
  Adjacency adj_;
  std::vector<float> phi_, max_step_;
  VertexFlags flags_;
};

}  // namespace isokit::track
