// SPDX-License-Identifier: MIT
// The energy tracker's precomputation: input and option checks, cotangent weights, barycentric
// areas and the weights Wi, Ki of the energy (energy_tracker.h).
#include <algorithm>
#include <cmath>
#include <string>

#include "energy_model.h"
#include "isokit/core/error.h"
#include "mesh_geometry.h"
#include "points.h"
#include "validation.h"

namespace isokit::track::detail {

namespace {

bool in_range(float v, float lo, float hi) {
  return std::isfinite(v) && v >= lo && v <= hi;
}

/// Ai / Ā per vertex: a third of the rest area of each incident triangle over the mean of the
/// non-zero areas; a vertex without area gets 1.
std::vector<double> area_ratios(const std::vector<Vec3d>& rest, const Triangles& triangles) {
  std::vector<double> area(rest.size(), 0.0);
  for (Eigen::Index f = 0; f < triangles.rows(); ++f) {
    const int a = triangles(f, 0), b = triangles(f, 1), c = triangles(f, 2);
    const double third = norm(cross(rest[b] - rest[a], rest[c] - rest[a])) / 6.0;
    for (int v : {a, b, c}) area[std::size_t(v)] += third;
  }
  double sum = 0;
  long count = 0;
  for (double x : area)
    if (x > 0) sum += x, ++count;
  const double mean = count > 0 ? sum / double(count) : 1.0;
  for (double& x : area) x = x > 0 ? x / mean : 1.0;
  return area;
}

double bounding_diagonal(const std::vector<Vec3d>& pts) {
  Box3d box;
  for (const Vec3d& p : pts) box.extend(p);
  return norm(box.size());
}

}  // namespace

void validate_energy_options(const EnergyTrackerOptions& o) {
  const std::string fix = "use the default (energy_tracker.h)";
  require(std::isfinite(o.iso_weight) && o.iso_weight > 0, "EnergyTrackerOptions::iso_weight",
          "must be finite and > 0 (got " + format_number(o.iso_weight) + ")", fix + ": 10");
  require(std::isfinite(o.tangent_weight) && o.tangent_weight > 0 && o.tangent_weight <= 1,
          "EnergyTrackerOptions::tangent_weight",
          "must be in (0, 1] (got " + format_number(o.tangent_weight) + ")", fix + ": 0.01");
  require(in_range(o.anchor_weight, 0, 1e30f), "EnergyTrackerOptions::anchor_weight",
          "must be finite and >= 0 (got " + format_number(o.anchor_weight) + ")", fix + ": 100");
  require(std::isfinite(o.max_cotangent) && o.max_cotangent > 0, "EnergyTrackerOptions::max_cotangent",
          "must be finite and > 0 (got " + format_number(o.max_cotangent) + ")", fix + ": 10");
  require(std::isfinite(o.max_search) && o.max_search > 0, "EnergyTrackerOptions::max_search",
          "must be finite and > 0 (got " + format_number(o.max_search) + ")", fix + ": 1");
  require(o.search_steps >= 1, "EnergyTrackerOptions::search_steps",
          "must be >= 1 (got " + std::to_string(o.search_steps) + ")", fix + ": 4");
  require(std::isfinite(o.contact_angle_deg) && o.contact_angle_deg > 0 && o.contact_angle_deg <= 180,
          "EnergyTrackerOptions::contact_angle_deg",
          "must be in (0, 180] (got " + format_number(o.contact_angle_deg) + ")", fix + ": 55");
  require(in_range(o.contact_offset, 0, 1e30f), "EnergyTrackerOptions::contact_offset",
          "must be finite and >= 0 (got " + format_number(o.contact_offset) + ")", fix + ": 0.1");
  require(o.max_iterations >= 0, "EnergyTrackerOptions::max_iterations",
          "must be >= 0 (got " + std::to_string(o.max_iterations) + ")", fix + ": 50");
  require(o.anderson_window >= 0 && o.anderson_window <= 64, "EnergyTrackerOptions::anderson_window",
          "must be in [0, 64] (got " + std::to_string(o.anderson_window) + ")", fix + ": 5");
  require(in_range(o.tolerance, 0, 1e30f), "EnergyTrackerOptions::tolerance",
          "must be finite and >= 0 (got " + format_number(o.tolerance) + ")", fix + ": 1e-5");
  require(std::isfinite(o.energy_tolerance) && o.energy_tolerance >= 0,
          "EnergyTrackerOptions::energy_tolerance",
          "must be finite and >= 0 (got " + format_number(o.energy_tolerance) + ")", fix + ": 1e-6");
  require(in_range(o.iso_tolerance, 0, 1e30f), "EnergyTrackerOptions::iso_tolerance",
          "must be finite and >= 0 (got " + format_number(o.iso_tolerance) + ")", fix + ": 1e-3");
  require(in_range(o.min_gradient, 0, 1e30f), "EnergyTrackerOptions::min_gradient",
          "must be finite and >= 0 (got " + format_number(o.min_gradient) + ")", fix + ": 1e-6");
}

void build_model(EnergyModel& m, const Positions& rest, const Triangles& triangles, std::vector<float> iso,
                 const EnergyTrackerOptions& options) {
  validate_mesh(rest, triangles, iso.size());
  validate_iso_values(iso);
  validate_energy_options(options);
  const std::vector<Vec3f> pts = to_points(rest, "rest positions");
  m.options = options;
  m.n = pts.size();
  m.triangles = triangles;
  m.iso = std::move(iso);
  m.rest.resize(m.n);
  for (std::size_t i = 0; i < m.n; ++i) m.rest[i] = {pts[i].x, pts[i].y, pts[i].z};
  m.adj = vertex_adjacency(triangles, static_cast<int>(m.n));
  std::vector<float> wf, sums;
  cotangent_weights(pts, triangles, m.adj, options.max_cotangent, wf, sums);
  m.w.assign(wf.begin(), wf.end());
  m.w_rev.resize(wf.size());
  for (std::size_t i = 0; i < m.n; ++i)
    for (int k = m.adj.offsets[i]; k < m.adj.offsets[i + 1]; ++k)
      m.w_rev[std::size_t(k)] =
          wf[std::size_t(find_neighbor(m.adj, m.adj.neighbors[std::size_t(k)], int(i)))];
  m.edge = mean_edge_lengths(pts, m.adj);
  m.area = area_ratios(m.rest, triangles);
  m.iso_w.resize(m.n);
  for (std::size_t i = 0; i < m.n; ++i) m.iso_w[i] = double(options.iso_weight) * m.area[i];
  m.diagonal = bounding_diagonal(m.rest);
  m.stiffness.assign(m.n, 0.f);
  m.flags.contact.assign(m.n, 0);
  m.flags.lost.assign(m.n, 0);
  m.flags.beta.assign(m.n, 0.f);
  m.flags.free.assign(m.n, 0);
  m.refactor();
}

void EnergyModel::refactor() {
  unknown.assign(n, -1);
  anchor_w.assign(n, 0.0);
  moving.clear();
  unknowns = 0;
  energy_scale = 0;
  for (std::size_t i = 0; i < n; ++i) {
    double wsum = 0;
    for (int k = adj.offsets[i]; k < adj.offsets[i + 1]; ++k) wsum += w[std::size_t(k)];
    if (stiffness[i] < 1.f) {
      unknown[i] = unknowns++;
      moving.push_back(static_cast<int>(i));
      anchor_w[i] = double(stiffness[i]) * double(options.anchor_weight) * area[i];
    }
    energy_scale += iso_w[i] + anchor_w[i] + wsum;
  }
  rotating.clear();
  for (std::size_t i = 0; i < n; ++i) {
    bool moves = !pinned(i);
    for (int k = adj.offsets[i]; k < adj.offsets[i + 1] && !moves; ++k)
      moves = !pinned(std::size_t(adj.neighbors[std::size_t(k)]));
    if (moves) rotating.push_back(static_cast<int>(i));
  }
  pending_factorizations += system.factor(*this);
}

}  // namespace isokit::track::detail
