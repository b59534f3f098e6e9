// SPDX-License-Identifier: MIT
#include "validation.h"

#include <cmath>
#include <string>

#include "isokit/core/error.h"

namespace isokit::track::detail {

void validate_triangles(const Triangles& triangles, int num_vertices) {
  require(num_vertices >= 0, "vertex_adjacency num_vertices",
          "is negative (" + std::to_string(num_vertices) + ")", "pass the vertex count");
  // Messages are built only on failure: this runs over every triangle of large meshes.
  for (Eigen::Index f = 0; f < triangles.rows(); ++f) {
    const int a = triangles(f, 0), b = triangles(f, 1), c = triangles(f, 2);
    for (int v : {a, b, c})
      if (v < 0 || v >= num_vertices)
        require(false, "triangle " + std::to_string(f),
                "vertex index " + std::to_string(v) + " is outside [0, " + std::to_string(num_vertices) + ")",
                "fix the face list or pass all vertices");
    if (a == b || b == c || a == c)
      require(false, "triangle " + std::to_string(f),
              "repeats a vertex (" + std::to_string(a) + ", " + std::to_string(b) + ", " + std::to_string(c) +
                  ")",
              "remove degenerate triangles before building the mesh");
  }
}

void validate_mesh(const Positions& rest, const Triangles& triangles, std::size_t iso_size) {
  require(rest.rows() > 0, "rest positions", "are empty", "pass a mesh with vertices");
  require(
      iso_size == static_cast<std::size_t>(rest.rows()), "iso values",
      "size " + std::to_string(iso_size) + " differs from the vertex count " + std::to_string(rest.rows()),
      "pass one iso-value per vertex");
  validate_triangles(triangles, static_cast<int>(rest.rows()));
}

void validate_call(const Positions& positions, std::size_t n, const FieldFunction& field) {
  require(
      static_cast<std::size_t>(positions.rows()) == n, "initial positions",
      "have " + std::to_string(positions.rows()) + " rows, the mesh has " + std::to_string(n) + " vertices",
      "pass one position per vertex");
  require(static_cast<bool>(field), "field", "is empty", "pass a field function");
}

void validate_rotations(const std::vector<Mat3f>& rotations, std::size_t n) {
  require(rotations.empty() || rotations.size() == n, "rotations",
          "size " + std::to_string(rotations.size()) + " differs from the vertex count " + std::to_string(n),
          "pass one rotation per vertex or none (identity)");
  for (std::size_t i = 0; i < rotations.size(); ++i)
    for (float v : rotations[i].m)
      if (!std::isfinite(v))  // message built only on failure (hot path)
        require(false, "rotation " + std::to_string(i), "is not finite", "pass finite rotations");
}

void validate_iso_values(const std::vector<float>& iso) {
  for (std::size_t i = 0; i < iso.size(); ++i)
    if (!std::isfinite(iso[i]))
      require(false, "iso value " + std::to_string(i), "is not finite (" + format_number(iso[i]) + ")",
              "sample iso-values from a finite field");
}

namespace {

void validate_repair_options(const FoldRepairOptions& f, const OrientationRepairOptions& r) {
  require(std::isfinite(f.max_fraction) && f.max_fraction >= 0 && f.max_fraction <= 1,
          "FoldRepairOptions::max_fraction", "must be in [0, 1] (got " + format_number(f.max_fraction) + ")",
          "use e.g. 0.1");
  require(f.rounds >= 0 && f.steps >= 0 && f.rings >= 0, "FoldRepairOptions",
          "rounds, steps and rings must be >= 0", "use e.g. 8, 5 and 2 (0 rounds: off)");
  require(r.rounds >= 0 && r.samples >= 1, "OrientationRepairOptions",
          "rounds must be >= 0 and samples >= 1 (got " + std::to_string(r.rounds) + ", " +
              std::to_string(r.samples) + ")",
          "use e.g. 8 and 8 (0 rounds: off)");
  require(std::isfinite(r.max_move) && r.max_move > 0.f && r.max_move <= 4.f &&
              std::isfinite(r.max_outward_move) && r.max_outward_move >= 0.f &&
              r.max_outward_move <= r.max_move,
          "OrientationRepairOptions::max_move / max_outward_move",
          "must satisfy 0 < max_move <= 4 and 0 <= max_outward_move <= max_move (got " +
              format_number(r.max_move) + ", " + format_number(r.max_outward_move) + ")",
          "use e.g. 0.5 and 0.125");
  require(std::isfinite(r.margin) && r.margin >= 0.f && r.margin <= 1.f, "OrientationRepairOptions::margin",
          "must be in [0, 1] (got " + format_number(r.margin) + ")", "use e.g. 0.05");
  require(std::isfinite(r.max_fraction) && r.max_fraction >= 0 && r.max_fraction <= 1,
          "OrientationRepairOptions::max_fraction",
          "must be in [0, 1] (got " + format_number(r.max_fraction) + ")", "use e.g. 0.1");
}

}  // namespace

void validate_options(const TrackerOptions& o) {
  require(std::isfinite(o.sigma) && o.sigma > 0.f && o.sigma <= 1.f, "TrackerOptions::sigma",
          "must be in (0, 1] (got " + format_number(o.sigma) + ")", "use 1 (Newton) or 0.35 (2013)");
  require(o.initial_newton_steps >= 0 && o.max_iterations >= 0, "TrackerOptions iterations", "must be >= 0",
          "pass non-negative iteration counts");
  require(std::isfinite(o.tolerance) && o.tolerance >= 0.f, "TrackerOptions::tolerance",
          "must be finite and >= 0", "use e.g. 1e-5");
  require(std::isfinite(o.iso_tolerance) && o.iso_tolerance > 0.f, "TrackerOptions::iso_tolerance",
          "must be finite and > 0 (got " + format_number(o.iso_tolerance) + ")", "use e.g. 1e-3");
  require(std::isfinite(o.global_regularization) && o.global_regularization > 0.f,
          "TrackerOptions::global_regularization",
          "must be finite and > 0 (got " + format_number(o.global_regularization) + ")", "use e.g. 1e-4");
  require(std::isfinite(o.max_step) && o.max_step > 0.f, "TrackerOptions::max_step", "must be > 0",
          "use e.g. 0.5");
  require(std::isfinite(o.max_cotangent) && o.max_cotangent > 0.f, "TrackerOptions::max_cotangent",
          "must be > 0", "use e.g. 10");
  require(std::isfinite(o.min_gradient) && o.min_gradient > 0.f, "TrackerOptions::min_gradient",
          "must be > 0", "use e.g. 1e-6");
  require(o.contact_angle_deg > 0.f && o.contact_angle_deg <= 180.f, "TrackerOptions::contact_angle_deg",
          "must be in (0, 180]", "use 55 (2013)");
  require(o.free_vertex_angle_deg > 0.f && o.free_vertex_angle_deg <= 180.f,
          "TrackerOptions::free_vertex_angle_deg",
          "must be in (0, 180] (got " + format_number(o.free_vertex_angle_deg) + ")",
          "use 60 (the default) or 180 (every vertex tracked, 2014)");
  require(std::isfinite(o.min_contact_damping) && o.min_contact_damping > 0.f && o.min_contact_damping <= 1.f,
          "TrackerOptions::min_contact_damping",
          "must be in (0, 1] (got " + format_number(o.min_contact_damping) + ")", "use e.g. 0.25");
  require(std::isfinite(o.chebyshev_rho) && o.chebyshev_rho >= 0.f && o.chebyshev_rho < 1.f,
          "TrackerOptions::chebyshev_rho", "must be in [0, 1) (got " + format_number(o.chebyshev_rho) + ")",
          "use 0 (plain Jacobi) or e.g. 0.995");
  require(o.cg_max_iterations >= 1 && o.cg_rings >= 1, "TrackerOptions CG",
          "cg_max_iterations and cg_rings must be >= 1", "use e.g. 200 and 2");
  require(o.smoothing.beta_diffusion_steps >= 0 && o.smoothing.smoothing_steps >= 0 &&
              o.smoothing.reproject_steps >= 0,
          "SmoothingOptions", "step counts must be >= 0", "pass non-negative counts");
  validate_repair_options(o.fold_repair, o.orientation_repair);
}

}  // namespace isokit::track::detail
