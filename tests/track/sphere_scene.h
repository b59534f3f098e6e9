// SPDX-License-Identifier: MIT
// A tracker test scene: a sphere mesh, its field moved by a shift, and an initial guess.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "test_util.h"
#include "track_fixtures.h"

namespace isokit::test {

/// A sphere mesh, its field moved by `shift`, and an initial guess: rest + shift + a random
/// perturbation of `noise` (a few percent of an edge) in every direction.
struct SphereScene {
  Mesh mesh = capsule_mesh(0.5f, 0.f, 20, 0, 10);
  std::shared_ptr<implicit::SphereField> rest_field =
      std::make_shared<implicit::SphereField>(Vec3f{0, 0, 0}, 0.5f);
  std::shared_ptr<implicit::SphereField> field;
  std::vector<float> iso = track::sample_iso_values(as_function(rest_field), mesh.V);
  track::Positions start;

  SphereScene(const Vec3f& shift, float noise, std::uint32_t seed) {
    field = std::make_shared<implicit::SphereField>(shift, 0.5f);
    Rng rng(seed);
    start = mesh.V;
    for (Eigen::Index i = 0; i < start.rows(); ++i) {
      const Vec3d n = rng.unit();
      start.row(i) += Eigen::RowVector3f(shift.x, shift.y, shift.z) +
                      noise * Eigen::RowVector3f(float(n.x), float(n.y), float(n.z));
    }
  }
};

}  // namespace isokit::test
