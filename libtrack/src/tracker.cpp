// SPDX-License-Identifier: MIT
// IsoSurfaceTracker: the precomputation, and `track()` as the sequence of its stages (stages.h).
#include "isokit/track/tracker.h"

#include <algorithm>
#include <chrono>
#include <string>
#include <utility>

#include "field_eval.h"
#include "global_solve.h"
#include "isokit/core/error.h"
#include "isokit/core/mesh_quality.h"
#include "mesh_geometry.h"
#include "points.h"
#include "spatial_order.h"
#include "stages.h"
#include "validation.h"

namespace isokit::track {

namespace {

// Moves the model into its internal vertex order (options.reorder_vertices).
void reorder(detail::TrackerModel& m) {
  m.order = detail::spatial_order(m.rest);
  m.rank.resize(m.order.size());
  for (std::size_t k = 0; k < m.order.size(); ++k) m.rank[std::size_t(m.order[k])] = static_cast<int>(k);
  m.rest = detail::permuted(m.rest, m.order);
  m.iso = detail::permuted(m.iso, m.order);
  for (Eigen::Index f = 0; f < m.triangles.rows(); ++f)
    for (int c = 0; c < 3; ++c) m.triangles(f, c) = m.rank[std::size_t(m.triangles(f, c))];
}

/// Relaxation::kEnergy: the local–global solve's options, with the fields TrackerOptions shares.
EnergyTrackerOptions energy_options(const TrackerOptions& o) {
  EnergyTrackerOptions e;
  static_cast<EnergySolveOptions&>(e) = o.energy;
  e.max_iterations = o.max_iterations;
  e.tolerance = o.tolerance;
  e.iso_tolerance = o.iso_tolerance;
  e.angle_contacts = o.angle_contacts;
  e.contact_angle_deg = o.contact_angle_deg;
  e.max_cotangent = o.max_cotangent;
  e.min_gradient = o.min_gradient;
  e.grain = o.grain;
  return e;
}

}  // namespace

IsoSurfaceTracker::IsoSurfaceTracker(const Positions& rest, const Triangles& triangles,
                                     std::vector<float> iso, TrackerOptions options)
    : model_(std::make_unique<detail::TrackerModel>()) {
  detail::TrackerModel& m = *model_;
  m.triangles = triangles;
  m.iso = std::move(iso);
  m.options = options;
  detail::validate_options(m.options);
  detail::validate_mesh(rest, m.triangles, m.iso.size());
  m.rest = detail::to_points(rest, "rest positions");
  detail::validate_iso_values(m.iso);
  if (m.options.relaxation == Relaxation::kEnergy)
    m.energy.emplace(rest, triangles, m.iso, energy_options(m.options));
  if (m.options.reorder_vertices) reorder(m);
  const std::vector<Vec3f>& pts = m.rest;
  m.adj = vertex_adjacency(m.triangles, static_cast<int>(pts.size()));
  detail::cotangent_weights(pts, m.triangles, m.adj, m.options.max_cotangent, m.weights, m.weight_sum);
  m.max_step = detail::mean_edge_lengths(pts, m.adj);
  m.diagonal = bbox_diagonal(pts.data(), pts.size());
  // Lazy evaluation radius: a tangential move d from where the field was evaluated leaves the
  // vertex off its iso-surface by about κ |d|² / 2 (κ: the iso-surface's curvature) beyond what the
  // linearised field predicts; with κ at most 1 / ℓ (ℓ: the vertex's mean edge length: the mesh
  // resolves the surface) that stays below the tolerance for |d|² ≤ 2 · tolerance · ℓ.
  m.lazy_r2.resize(m.max_step.size());
  for (std::size_t i = 0; i < m.max_step.size(); ++i)
    m.lazy_r2[i] = 2.f * m.options.tolerance * m.diagonal * m.max_step[i];
  for (float& s : m.max_step) s *= m.options.max_step;
  m.mask.assign(pts.size(), 1.f);
  m.free.assign(pts.size(), 0);
  m.vertex_faces = detail::vertex_faces(m.triangles, pts.size());
}

IsoSurfaceTracker::IsoSurfaceTracker(const IsoSurfaceTracker& other)
    : model_(std::make_unique<detail::TrackerModel>(*other.model_)) {}
IsoSurfaceTracker::IsoSurfaceTracker(IsoSurfaceTracker&& other) noexcept = default;
IsoSurfaceTracker& IsoSurfaceTracker::operator=(const IsoSurfaceTracker& other) {
  if (this != &other) model_ = std::make_unique<detail::TrackerModel>(*other.model_);
  return *this;
}
IsoSurfaceTracker& IsoSurfaceTracker::operator=(IsoSurfaceTracker&& other) noexcept = default;
IsoSurfaceTracker::~IsoSurfaceTracker() = default;

void IsoSurfaceTracker::set_relaxation_mask(std::vector<float> mask) {
  detail::TrackerModel& m = *model_;
  require(mask.size() == m.mask.size(), "relaxation mask",
          "size " + std::to_string(mask.size()) + " differs from the vertex count " +
              std::to_string(m.mask.size()),
          "pass one value per vertex");
  for (std::size_t i = 0; i < mask.size(); ++i)
    require(mask[i] >= 0.f && mask[i] <= 1.f, "relaxation mask vertex " + std::to_string(i),
            "is outside [0, 1] (" + format_number(mask[i]) + ")", "use 0 (no tangential move) .. 1");
  // The energy solve has no tangential step to scale: its mask is the anchor stiffness.
  require(!m.energy || std::all_of(mask.begin(), mask.end(), [](float v) { return v >= 1.f; }),
          "relaxation mask", "has no effect with the energy solve (Relaxation::kEnergy)",
          "pass 1 - mask to set_anchor_stiffness instead");
  m.mask = m.order.empty() ? std::move(mask) : detail::permuted(mask, m.order);
  m.global.reset();  // the unknowns follow the mask
}

void IsoSurfaceTracker::set_anchor_stiffness(std::vector<float> stiffness) {
  detail::TrackerModel& m = *model_;
  require(stiffness.size() == m.mask.size(), "anchor stiffness",
          "size " + std::to_string(stiffness.size()) + " differs from the vertex count " +
              std::to_string(m.mask.size()),
          "pass one value per vertex");
  bool any = false;
  for (std::size_t i = 0; i < stiffness.size(); ++i) {
    require(stiffness[i] >= 0.f && stiffness[i] <= 1.f, "anchor stiffness vertex " + std::to_string(i),
            "is outside [0, 1] (" + format_number(stiffness[i]) + ")", "use 0 (free) .. 1 (pinned)");
    any = any || stiffness[i] > 0.f;
  }
  if (m.energy) m.energy->set_anchor_stiffness(stiffness);
  if (!any) stiffness.clear();
  if (!m.order.empty() && !stiffness.empty()) stiffness = detail::permuted(stiffness, m.order);
  // Pinned vertices have no unknowns in the global solve: its factor follows the pinned set.
  auto pinned = [](const std::vector<float>& k, std::size_t i) { return !k.empty() && k[i] >= 1.f; };
  bool same = true;
  for (std::size_t i = 0; i < m.mask.size() && same; ++i)
    same = pinned(stiffness, i) == pinned(m.anchor_k, i);
  m.anchor_k = std::move(stiffness);
  if (!same) m.global.reset();
}

void IsoSurfaceTracker::set_max_iterations(int iterations) {
  require(iterations >= 0, "tracker iterations", "must be >= 0 (got " + std::to_string(iterations) + ")",
          "use e.g. 100");
  model_->options.max_iterations = iterations;
  if (model_->energy) model_->energy->set_max_iterations(iterations);
}

void IsoSurfaceTracker::set_interrupt(std::function<TrackInterrupt()> interrupt) {
  if (model_->energy) model_->energy->set_interrupt(interrupt);
  model_->interrupt = std::move(interrupt);
}

void IsoSurfaceTracker::set_fold_repair_mask(std::vector<std::uint8_t> mask) {
  detail::TrackerModel& m = *model_;
  require(mask.empty() || mask.size() == m.mask.size(), "fold repair mask",
          "size " + std::to_string(mask.size()) + " differs from the vertex count " +
              std::to_string(m.mask.size()),
          "pass one flag per vertex, or none");
  m.repair_mask = m.order.empty() || mask.empty() ? std::move(mask) : detail::permuted(mask, m.order);
}

const VertexFlags& IsoSurfaceTracker::flags() const {
  return model_->flags;
}

const TrackerOptions& IsoSurfaceTracker::options() const {
  return model_->options;
}

Adjacency IsoSurfaceTracker::adjacency() const {
  const detail::TrackerModel& m = *model_;
  if (m.order.empty()) return m.adj;
  Adjacency out;
  const std::size_t n = m.order.size();
  out.offsets.assign(n + 1, 0);
  for (std::size_t u = 0; u < n; ++u) out.offsets[u + 1] = out.offsets[u] + m.adj.degree(m.rank[u]);
  out.neighbors.resize(m.adj.neighbors.size());
  for (std::size_t u = 0; u < n; ++u) {
    const int k = m.rank[u];
    int* row = out.neighbors.data() + out.offsets[u];
    for (int e = m.adj.offsets[std::size_t(k)]; e < m.adj.offsets[std::size_t(k) + 1]; ++e)
      *row++ = m.order[std::size_t(m.adj.neighbors[std::size_t(e)])];
    std::sort(out.neighbors.data() + out.offsets[u], row);
  }
  return out;
}

std::vector<float> IsoSurfaceTracker::weights() const {
  const detail::TrackerModel& m = *model_;
  if (m.order.empty()) return m.weights;
  const Adjacency user = adjacency();
  std::vector<float> out(m.weights.size());
  for (std::size_t u = 0; u < m.order.size(); ++u)
    for (int e = user.offsets[u]; e < user.offsets[u + 1]; ++e) {
      const int k = m.rank[u], j = m.rank[std::size_t(user.neighbors[std::size_t(e)])];
      out[std::size_t(e)] = m.weights[std::size_t(detail::find_neighbor(m.adj, k, j))];
    }
  return out;
}

void IsoSurfaceTracker::mark_rest_inversions(const FieldFunction& rest_field) {
  require(static_cast<bool>(rest_field), "rest field", "is empty", "pass the field at the rest pose");
  detail::TrackerModel& m = *model_;
  m.rest_inverted = detail::inverted_triangles(rest_field, m.rest, m.triangles, m.options.grain);
}

void IsoSurfaceTracker::set_rest_field(const FieldFunction& rest_field) {
  if (model_->energy) {  // no free vertices and no fold test: one energy holds every vertex
    require(static_cast<bool>(rest_field), "rest field", "is empty", "pass the field at the rest pose");
    return;
  }
  mark_rest_inversions(rest_field);
  detail::TrackerModel& m = *model_;
  m.free = detail::free_vertices(rest_field, m.rest, m.triangles, m.options);
  m.global.reset();  // free vertices have three unknowns
}

namespace {

// The call's positions back to the caller: a non-finite one replaced by the caller's input, in
// the caller's order.
void write_positions(detail::TrackState& s, const detail::TrackerModel& m, Positions& positions) {
  std::vector<Vec3f>& cur = s.cur;
  for (std::size_t i = 0; i < s.n; ++i)
    if (!detail::finite(cur[i])) cur[i] = detail::row(positions, static_cast<Eigen::Index>(m.caller(i)));
  if (!m.order.empty()) cur = detail::permuted(cur, m.rank);
  detail::from_points(cur, positions);
}

// A finished call's results back to the model and the caller: the inverted flags for the next
// call's fold test, the positions and the flags in the caller's order. (An abandoned call,
// TrackInterrupt::kAbandon, writes its positions only: the flags stay the last finished call's.)
void finish(detail::TrackState& s, detail::TrackerModel& m, Positions& positions) {
  m.last_inverted = std::move(s.inverted);
  m.flags = std::move(s.flags);
  if (!m.order.empty()) {
    m.flags.contact = detail::permuted(m.flags.contact, m.rank);
    m.flags.lost = detail::permuted(m.flags.lost, m.rank);
    m.flags.beta = detail::permuted(m.flags.beta, m.rank);
    m.flags.free = detail::permuted(m.flags.free, m.rank);
  }
  write_positions(s, m, positions);
}

/// Relaxation::kEnergy: the whole call is the local–global solve (EnergyTracker); its flags become
/// the tracker's (no β, no free vertex).
TrackStats track_energy(detail::TrackerModel& m, const FieldFunction& field, Positions& positions,
                        const Positions& anchors) {
  const TrackStats st =
      &anchors == &positions ? m.energy->track(field, positions) : m.energy->track(field, positions, anchors);
  if (st.abandoned) return st;
  m.flags = m.energy->flags();
  m.flags.beta.assign(m.flags.contact.size(), 0.f);
  m.flags.free.assign(m.flags.contact.size(), 0);
  return st;
}

}  // namespace

TrackStats IsoSurfaceTracker::track(const FieldFunction& field, const std::vector<Mat3f>& rotations,
                                    Positions& positions) {
  return track(field, rotations, positions, positions);
}

TrackStats IsoSurfaceTracker::track(const FieldFunction& field, const std::vector<Mat3f>& rotations,
                                    Positions& positions, const Positions& anchors) {
  const auto t0 = std::chrono::steady_clock::now();
  detail::TrackerModel& m = *model_;
  detail::validate_call(positions, m.iso.size(), field);
  detail::validate_rotations(rotations, m.iso.size());
  if (m.energy) return track_energy(m, field, positions, anchors);
  std::vector<Vec3f> initial = detail::to_points(positions, "initial positions");
  if (!m.order.empty()) initial = detail::permuted(initial, m.order);
  std::vector<Vec3f> anchor;
  if (!m.anchor_k.empty()) {
    require(static_cast<std::size_t>(anchors.rows()) == m.iso.size(), "anchors",
            "have " + std::to_string(anchors.rows()) + " rows, the mesh has " + std::to_string(m.iso.size()) +
                " vertices",
            "pass one anchor per vertex");
    anchor = &anchors == &positions ? initial : detail::to_points(anchors, "anchors");
    if (&anchors != &positions && !m.order.empty()) anchor = detail::permuted(anchor, m.order);
    for (std::size_t i = 0; i < anchor.size(); ++i)
      if (m.anchor_k[i] >= 1.f) initial[i] = anchor[i];  // pinned: placed at the anchor
  }
  detail::TrackState s(m, field, rotations, std::move(initial));
  s.anchors = std::move(anchor);

  if (m.options.relaxation == Relaxation::kGlobal) {
    detail::solve_frame(s, m.global.get());  // 1 + 2. one convergent solve (not in the papers)
  } else {
    detail::project(s);  // 1. Newton projection (2014 §5 stage 2)
    const std::unique_ptr<detail::RelaxationStrategy> strategy =
        s.cg ? detail::cg_relaxation(s) : detail::jacobi_relaxation();
    detail::relax(s, *strategy);  // 2. tangential ARAP relaxation + Newton (2014 §5 stage 3, §5.2)
  }
  if (s.stats.abandoned) {  // the caller tracks these positions to a newer pose next
    write_positions(s, m, positions);
  } else {
    detail::mark_contacts(s);    // 3. contacts: field flags, angle rule (2013 §5), folds
    detail::smooth_contacts(s);  // 4. β-diffused Laplacian smoothing (2013 §5 eq. 7)
    detail::repair_folds(s);     // 5. fold repair (not in the papers)
    detail::collect_statistics(s);
    detail::repair_orientation(s);  // 6. orientation repair (not in the papers)
    finish(s, m, positions);
  }
  s.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return s.stats;
}

}  // namespace isokit::track
