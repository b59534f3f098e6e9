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
  float sigma{0.35f};              ///< 2013 §5
  float contact_angle_deg{55.0f};  ///< 2013 §5
  int max_iterations{50};          ///< Newton steps per call
  float tolerance{1e-4f};          ///< stop when every active |f - iso| is below this
  float max_step{0.5f};            ///< Newton step ≤ max_step * mean rest edge length
  float mu{-1.0f};                 ///< < 0: the paper's μ(|f - iso|); ≥ 0: this constant
  float min_gradient{1e-6f};
  SmoothingOptions smoothing{};
  std::size_t grain{1024};
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
