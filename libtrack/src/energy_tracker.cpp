// SPDX-License-Identifier: MIT
// EnergyTracker: the call as named stages — start (positions to double, pinned vertices to their
// anchors), local–global iterations with the energy log and the convergence test, finish
// (positions out, flags, statistics); energy_tracker.h.
#include "isokit/track/energy_tracker.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

#include "energy_model.h"
#include "field_eval.h"
#include "isokit/core/error.h"
#include "points.h"
#include "validation.h"

namespace isokit::track {

namespace detail {

namespace {

Vec3d to_double(const Vec3f& v) {
  return {v.x, v.y, v.z};
}

void start_call(EnergyCall& c, const Positions& positions, const Positions& anchors) {
  const EnergyData& m = c.m;
  const std::vector<Vec3f> x = to_points(positions, "initial positions");
  const std::vector<Vec3f> a = to_points(anchors, "anchors");
  c.x.resize(m.n);
  c.anchor.resize(m.n);
  for (std::size_t i = 0; i < m.n; ++i) {
    c.anchor[i] = to_double(a[i]);
    c.x[i] = m.pinned(i) ? c.anchor[i] : to_double(x[i]);
  }
  c.targets.point = c.x;
  c.targets.normal.assign(m.n, Vec3d{});
  c.targets.res.assign(m.n, std::numeric_limits<float>::infinity());
  c.targets.kind.assign(m.n, TargetKind::kNone);
  c.rot.assign(m.n, Mat3d{});
  c.value.assign(m.n, 0.f);
  c.grad.assign(m.n, Vec3f{});
  c.field_contact.assign(m.n, 0);
  c.lost.assign(m.n, 0);
  c.reset_count.assign(m.n, 0);
}

std::vector<double> pack(const EnergyData& m, const std::vector<Vec3d>& x) {
  std::vector<double> v(3 * m.moving.size());
  for (std::size_t a = 0; a < m.moving.size(); ++a) {
    const Vec3d& p = x[std::size_t(m.moving[a])];
    v[3 * a] = p.x, v[3 * a + 1] = p.y, v[3 * a + 2] = p.z;
  }
  return v;
}

void unpack(const EnergyData& m, const std::vector<double>& v, std::vector<Vec3d>& x) {
  for (std::size_t a = 0; a < m.moving.size(); ++a)
    x[std::size_t(m.moving[a])] = {v[3 * a], v[3 * a + 1], v[3 * a + 2]};
}

/// The iterate before its local step, and what to fall back to if its energy is higher than the
/// last accepted one's: the plain global step from that one and the targets it had.
struct Trial {
  bool accelerated{false};
  double energy{0};       // E at the last accepted iterate, after its local step
  double next_energy{0};  // E at the fallback (the same R and P)
  std::vector<Vec3d> fallback;
  TargetSet targets;
};

// The local step at the current iterate; an accelerated iterate that raised E is replaced by the
// plain step (Peng et al. 2018), so that the logged energies never rise except after a reset.
double accepted_local_step(EnergyCall& c, Trial& t, Anderson& aa) {
  local_step(c);
  double e = energy(c, c.x);
  if (t.accelerated && e > t.energy) {
    ++c.stats.backtracks;
    c.targets = t.targets;
    c.x = t.fallback;
    aa.reset();
    local_step(c);
    e = energy(c, c.x);
  }
  if (c.resets > 0) aa.reset();  // the targets moved: the secant history no longer applies
  return e;
}

// Local–global iterations until the test of EnergyTrackerOptions::energy_tolerance holds, the
// cap, or the caller's interrupt (before an iteration: the positions are then the last plain step).
TrackInterrupt iterate(EnergyCall& c, std::vector<double>& log, std::vector<int>& resets) {
  const EnergyData& m = c.m;
  const EnergyTrackerOptions& o = m.options;
  const double move_tol = double(o.tolerance) * m.diagonal;
  const double floor = move_tol * move_tol * m.energy_scale;
  log.clear();
  resets.clear();
  Anderson aa(o.anderson_window);
  Trial trial;
  std::vector<Vec3d> next;
  for (int k = 1; k <= o.max_iterations; ++k) {
    const TrackInterrupt ask = m.interrupt ? m.interrupt() : TrackInterrupt::kContinue;
    if (ask != TrackInterrupt::kContinue) {
      if (k > 1) c.x = trial.fallback, log.push_back(trial.next_energy), resets.push_back(0);
      c.stats.interrupted = true;
      return ask;
    }
    const double e = accepted_local_step(c, trial, aa);
    log.push_back(e);
    resets.push_back(c.resets);
    const double move = global_step(c, next);
    const double e_next = energy(c, next);
    c.stats.iterations = k;
    c.stats.max_move = float(move);
    const bool done = e - e_next <= o.energy_tolerance * e + floor && move <= move_tol;
    if (done || k == o.max_iterations) {
      c.x = next;
      log.push_back(e_next);
      resets.push_back(0);
      c.stats.converged = done;
      break;
    }
    trial.energy = e;
    trial.next_energy = e_next;
    trial.fallback = next;
    trial.targets = c.targets;
    std::vector<double> x = pack(m, c.x);
    trial.accelerated = aa.step(x, pack(m, next));
    unpack(m, x, c.x);
  }
  return TrackInterrupt::kContinue;
}

// Positions out, flags, and the statistics of the final positions (residuals over the unpinned
// vertices that are neither contact nor lost; their evaluations are not counted).
std::vector<Vec3f> write_positions(const EnergyCall& c, Positions& positions) {
  std::vector<Vec3f> pts(c.x.size());
  for (std::size_t i = 0; i < pts.size(); ++i) pts[i] = {float(c.x[i].x), float(c.x[i].y), float(c.x[i].z)};
  from_points(pts, positions);
  return pts;
}

void finish_call(EnergyCall& c, EnergyData& m, Positions& positions) {
  const std::vector<Vec3f> pts = write_positions(c, positions);
  std::vector<float> values(m.n);
  std::vector<Vec3f> grads(m.n);
  std::vector<std::uint8_t> contact(m.n);
  eval_field(c.field, pts.data(), m.n, values.data(), grads.data(), contact.data(), m.options.grain);
  double sum = 0;
  int count = 0;
  TrackStats& s = c.stats;
  for (std::size_t i = 0; i < m.n; ++i) {
    m.flags.contact[i] = c.targets.kind[i] == TargetKind::kContact;
    m.flags.lost[i] = c.lost[i];
    s.contact_vertices += m.flags.contact[i];
    s.lost_vertices += m.flags.lost[i];
    if (m.pinned(i) || m.flags.contact[i] || m.flags.lost[i]) continue;
    const float r = std::abs(values[i] - m.iso[i]);
    s.max_residual = std::max(s.max_residual, r);
    sum += r;
    ++count;
  }
  s.mean_residual = count > 0 ? float(sum / count) : 0.f;
  s.vertex_updates = long(m.n) * s.iterations;
  s.factorizations = m.pending_factorizations;
  m.pending_factorizations = 0;
}

}  // namespace

}  // namespace detail

EnergyTracker::EnergyTracker(const Positions& rest, const Triangles& triangles, std::vector<float> iso,
                             EnergyTrackerOptions options)
    : model_(std::make_unique<detail::EnergyModel>()) {
  detail::build_model(*model_, rest, triangles, std::move(iso), options);
}
EnergyTracker::EnergyTracker(const EnergyTracker& other)
    : model_(std::make_unique<detail::EnergyModel>(static_cast<const detail::EnergyData&>(*other.model_))) {}
EnergyTracker::EnergyTracker(EnergyTracker&& other) noexcept = default;
EnergyTracker& EnergyTracker::operator=(const EnergyTracker& other) {
  if (this != &other)
    model_ = std::make_unique<detail::EnergyModel>(static_cast<const detail::EnergyData&>(*other.model_));
  return *this;
}
EnergyTracker& EnergyTracker::operator=(EnergyTracker&& other) noexcept = default;
EnergyTracker::~EnergyTracker() = default;

void EnergyTracker::set_anchor_stiffness(std::vector<float> stiffness) {
  detail::EnergyModel& m = *model_;
  require(
      stiffness.size() == m.n, "anchor stiffness",
      "size " + std::to_string(stiffness.size()) + " differs from the vertex count " + std::to_string(m.n),
      "pass one stiffness per vertex");
  for (std::size_t i = 0; i < stiffness.size(); ++i)
    if (!(stiffness[i] >= 0.f && stiffness[i] <= 1.f))  // message built only on failure
      require(false, "anchor stiffness " + std::to_string(i),
              "must be in [0, 1] (got " + format_number(stiffness[i]) + ")",
              "clamp the painted values to [0, 1]");
  m.stiffness = std::move(stiffness);
  m.refactor();
}

void EnergyTracker::set_max_iterations(int iterations) {
  require(iterations >= 0, "energy tracker iterations",
          "must be >= 0 (got " + std::to_string(iterations) + ")", "use e.g. 50");
  model_->options.max_iterations = iterations;
}

void EnergyTracker::set_interrupt(std::function<TrackInterrupt()> interrupt) {
  model_->interrupt = std::move(interrupt);
}

TrackStats EnergyTracker::track(const FieldFunction& field, Positions& positions) {
  const Positions anchors = positions;
  return track(field, positions, anchors);
}

TrackStats EnergyTracker::track(const FieldFunction& field, Positions& positions, const Positions& anchors) {
  const auto t0 = std::chrono::steady_clock::now();
  detail::EnergyModel& m = *model_;
  detail::validate_call(positions, m.n, field);
  require(
      static_cast<std::size_t>(anchors.rows()) == m.n, "anchors",
      "have " + std::to_string(anchors.rows()) + " rows, the mesh has " + std::to_string(m.n) + " vertices",
      "pass one anchor per vertex");
  detail::EnergyCall c(m, field);
  detail::start_call(c, positions, anchors);
  if (detail::iterate(c, m.energy_log, m.reset_log) == TrackInterrupt::kAbandon) {
    detail::write_positions(c, positions);
    c.stats.abandoned = true;
  } else {
    detail::finish_call(c, m, positions);
  }
  c.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return c.stats;
}

const VertexFlags& EnergyTracker::flags() const {
  return model_->flags;
}
const std::vector<double>& EnergyTracker::energy_log() const {
  return model_->energy_log;
}
const std::vector<int>& EnergyTracker::reset_log() const {
  return model_->reset_log;
}
const EnergyTrackerOptions& EnergyTracker::options() const {
  return model_->options;
}

}  // namespace isokit::track
