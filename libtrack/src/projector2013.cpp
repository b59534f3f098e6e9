// SPDX-License-Identifier: MIT
#include "isokit/track/projector2013.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <utility>

#include "contact_smoothing.h"
#include "field_eval.h"
#include "isokit/core/error.h"
#include "isokit/core/parallel.h"
#include "mesh_geometry.h"
#include "points.h"
#include "statistics.h"
#include "validation.h"

namespace isokit::track {

namespace {

// Mean value coordinates (Floater 2003; Hormann & Floater 2006) of the origin with respect to
// the polygon of the one-ring projected onto the plane ⊥ n, ordered by angle. Returns false
// (no relaxation for this vertex) when the origin is not strictly inside a valid star: a
// boundary vertex (an angular gap ≥ π), or a degenerate (zero-length / collinear) neighbour.
bool mean_value_coordinates(const std::vector<Vec3f>& d, const Vec3f& n, std::vector<float>& phi) {
  const std::size_t m = d.size();
  phi.assign(m, 0.f);
  if (m < 3) return false;
  Vec3f u = std::abs(n.x) < 0.9f ? cross(n, Vec3f{1, 0, 0}) : cross(n, Vec3f{0, 1, 0});
  u = u / norm(u);
  const Vec3f v = cross(n, u);
  std::vector<double> x(m), y(m), ang(m);
  std::vector<std::size_t> order(m);
  for (std::size_t k = 0; k < m; ++k) {
    x[k] = dot(d[k], u), y[k] = dot(d[k], v);
    if (!(x[k] * x[k] + y[k] * y[k] > 1e-20)) return false;
    ang[k] = std::atan2(y[k], x[k]);
  }
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return ang[a] < ang[b]; });
  std::vector<double> tan_half(m);
  for (std::size_t k = 0; k < m; ++k) {
    const std::size_t a = order[k], b = order[(k + 1) % m];
    const double c = x[a] * y[b] - y[a] * x[b];  // sin of the angle * ra * rb
    const double dd = x[a] * x[b] + y[a] * y[b];
    const double ra = std::hypot(x[a], y[a]), rb = std::hypot(x[b], y[b]);
    if (!(c > 1e-12 * ra * rb)) return false;  // gap ≥ π or collinear: not inside
    tan_half[k] = (ra * rb - dd) / c;          // tan(α/2) = (1 - cos α) / sin α
  }
  double total = 0;
  std::vector<double> w(m);
  for (std::size_t k = 0; k < m; ++k) {
    const std::size_t a = order[k];
    w[k] = (tan_half[(k + m - 1) % m] + tan_half[k]) / std::hypot(x[a], y[a]);
    total += w[k];
  }
  if (!(total > 0)) return false;
  for (std::size_t k = 0; k < m; ++k) phi[order[k]] = static_cast<float>(w[k] / total);
  return true;
}

// One MVC tangential relaxation of vertex i (2013 eq. 5): `v_i + μ Σ_j Φ_ij (q_ij - v_i)`, q_ij
// the neighbour j projected onto the plane through v_i orthogonal to the unit normal n.
Vec3f mvc_relaxed(const Adjacency& adj, const std::vector<float>& phi, const std::vector<Vec3f>& pts,
                  std::size_t i, const Vec3f& n, float mu) {
  Vec3f delta{};
  for (int k = adj.offsets[i]; k < adj.offsets[i + 1]; ++k) {
    const Vec3f e = pts[adj.neighbors[k]] - pts[i];
    delta += (e - n * dot(e, n)) * phi[k];  // qij - vi
  }
  return pts[i] + delta * mu;
}

}  // namespace

Projector2013::Projector2013(const Positions& rest, const Triangles& triangles,
                             const FieldFunction& rest_field, ProjectorOptions options)
    : rest_(rest), triangles_(triangles), options_(options) {
  require(std::isfinite(options_.sigma) && options_.sigma > 0.f && options_.sigma <= 1.f,
          "ProjectorOptions::sigma", "must be in (0, 1]", "use 0.35 (2013)");
  require(options_.max_iterations >= 0, "ProjectorOptions::max_iterations", "must be >= 0", "use e.g. 50");
  require(options_.mu <= 1.f && std::isfinite(options_.mu), "ProjectorOptions::mu", "must be <= 1 and finite",
          "use a negative value for the paper's μ or a constant in [0, 1]");
  require(options_.contact_angle_deg > 0.f && options_.contact_angle_deg <= 180.f,
          "ProjectorOptions::contact_angle_deg", "must be in (0, 180]", "use 55 (2013)");
  require(options_.stall_steps >= 0 && options_.stall_steps <= 255, "ProjectorOptions::stall_steps",
          "must be in [0, 255]", "use 3, or 0 for none (2013)");
  require(options_.progress > 0.f && options_.progress <= 1.f, "ProjectorOptions::progress",
          "must be in (0, 1]", "use 0.9");
  require(options_.secant_max_factor > 0.f && options_.secant_max_factor <= 1.f,
          "ProjectorOptions::secant_max_factor", "must be in (0, 1]", "use 0.7");
  require(std::isfinite(options_.tolerance) && options_.tolerance >= 0.f, "ProjectorOptions::tolerance",
          "must be >= 0 (field units)", "use 1e-4");
  require(static_cast<bool>(rest_field), "rest field", "is empty", "pass a field function");
  require(rest_.rows() > 0, "rest positions", "are empty", "pass a mesh with vertices");
  const std::vector<Vec3f> pts = detail::to_points(rest_, "rest positions");
  const std::size_t n = pts.size();
  adj_ = vertex_adjacency(triangles_, static_cast<int>(n));
  iso_.resize(n);
  rest_normals_.resize(n);
  std::vector<std::uint8_t> fc(n);
  detail::eval_field(rest_field, pts.data(), n, iso_.data(), rest_normals_.data(), fc.data(), 0);
  for (std::size_t i = 0; i < n; ++i) {
    require(std::isfinite(iso_[i]) && detail::finite(rest_normals_[i]),
            "rest field at vertex " + std::to_string(i), "is not finite", "check the field");
    const float g = norm(rest_normals_[i]);
    rest_normals_[i] = g > options_.min_gradient ? rest_normals_[i] / g : Vec3f{};
  }
  phi_.assign(adj_.neighbors.size(), 0.f);
  std::vector<Vec3f> d;
  std::vector<float> phi;
  for (std::size_t i = 0; i < n; ++i) {
    if (rest_normals_[i] == Vec3f{}) continue;
    d.clear();
    for (int k = adj_.offsets[i]; k < adj_.offsets[i + 1]; ++k) d.push_back(pts[adj_.neighbors[k]] - pts[i]);
    if (mean_value_coordinates(d, rest_normals_[i], phi))
      std::copy(phi.begin(), phi.end(), phi_.begin() + adj_.offsets[i]);
  }
  max_step_ = detail::mean_edge_lengths(pts, adj_);
  for (float& s : max_step_) s *= options_.max_step;
}

void Projector2013::relax(const std::vector<Vec3f>& normals, float mu, Positions& positions) const {
  const std::vector<Vec3f> cur = detail::to_points(positions, "positions");
  require(cur.size() == iso_.size() && normals.size() == iso_.size(), "relax inputs",
          "sizes differ from the mesh", "pass one position and normal per vertex");
  std::vector<Vec3f> out(cur.size());
  for (std::size_t i = 0; i < cur.size(); ++i) out[i] = mvc_relaxed(adj_, phi_, cur, i, normals[i], mu);
  detail::from_points(out, positions);
}

namespace {

/// Why a vertex stopped moving in the call (contact and lost are VertexFlags).
enum class Stop : std::uint8_t { kLive, kDone, kStalled, kContact, kLost };

/// The working arrays of one project() call.
struct ProjectionBuffers {
  explicit ProjectionBuffers(std::vector<Vec3f> initial)
      : cur(std::move(initial)),
        prev(cur.size()),
        normal(cur.size(), Vec3f{}),
        batch(cur.size()),
        grads(cur.size()),
        moved(cur.size()),
        slot_values(cur.size()),
        slot_contact(cur.size()),
        field_contact(cur.size(), 0),
        values(cur.size()),
        signed_resid(cur.size(), 0.f),
        best(cur.size(), std::numeric_limits<float>::infinity()),
        sigma(cur.size(), 0.f),
        stop(cur.size(), Stop::kLive),
        strikes(cur.size(), 0),
        stale(cur.size(), 1),
        live(cur.size()) {
    for (std::size_t i = 0; i < live.size(); ++i) live[i] = static_cast<int>(i);
  }
  std::vector<Vec3f> cur;
  std::vector<Vec3f> prev;                  ///< where each vertex was at its last evaluation
  std::vector<Vec3f> normal;                ///< unit gradient of the last evaluation (contact rule)
  std::vector<Vec3f> batch, grads, moved;   ///< per live slot
  std::vector<float> slot_values;           ///< per live slot
  std::vector<std::uint8_t> slot_contact;   ///< per live slot: the field's contact flag
  std::vector<std::uint8_t> field_contact;  ///< the field's contact flag at the last evaluation
  std::vector<float> values;                ///< f at the last evaluation
  std::vector<float> signed_resid;          ///< iso - f at the last evaluation
  std::vector<float> best;                  ///< smallest |iso - f| of the call (progress rule)
  std::vector<float> sigma;  ///< the factor of the last Newton step (0: none yet, or a secant step)
  std::vector<Stop> stop;
  std::vector<std::uint8_t> strikes;  ///< consecutive Newton steps without progress
  std::vector<std::uint8_t> stale;    ///< moved since its last evaluation
  /// The vertices still moving, in index order: the field is evaluated at these only (a stopped
  /// vertex keeps its position, so its value is known).
  std::vector<int> live;
  bool relaxed{false};  ///< a relaxation step ran since the last Newton step
};

/// The Newton step factor of a vertex (ProjectorOptions::secant): σ (2013 eq. 4) until two samples
/// along one step show how the field falls along it; then the factor that the secant of those
/// samples says reaches the iso-value, within [σ, secant_max_factor]: a step with factor σ_k that took the
/// residual from `last` to `d` (same sign) measured the slope as (1 - d / last) / σ_k of the
/// gradient's. Without two such samples (a relaxation between, or no progress) the last factor
/// is kept, or σ.
float step_factor(const ProjectorOptions& o, bool paired, float d, float last, float previous) {
  if (!o.secant) return o.sigma;
  if (!paired) return previous > 0.f ? previous : o.sigma;
  const float rho = d / last;
  if (!(rho > 0.f && rho < 1.f)) return o.sigma;
  return std::clamp(previous / (1.f - rho), o.sigma, std::max(o.sigma, o.secant_max_factor));
}

/// The move of a live vertex after its evaluation (f, g): none when a rule stops it (its reason
/// in `s.stop`), else the Newton step of eq. 4 — or the secant point when the residual changed
/// sign since the last step (ProjectorOptions::secant).
Vec3f newton_move(const ProjectorOptions& o, float iso, float max_step, std::size_t i, float value,
                  const Vec3f& g, ProjectionBuffers& s) {
  const float g2 = squared_norm(g);
  if (!std::isfinite(value) || !detail::finite(g) || !(g2 > o.min_gradient * o.min_gradient)) {
    s.stop[i] = Stop::kLost;
    return {};
  }
  const Vec3f nrm = g / std::sqrt(g2);
  if (s.normal[i] != Vec3f{} && dot(nrm, s.normal[i]) < std::cos(o.contact_angle_deg * kPiF / 180.f)) {
    s.stop[i] = Stop::kContact;  // stopped at a gradient discontinuity (2013 §5)
    return {};
  }
  s.normal[i] = nrm;
  const float d = iso - value, r = std::abs(d);
  const float last = s.signed_resid[i];
  const bool paired = o.secant && !s.relaxed && s.sigma[i] > 0.f;  // two samples along the last step
  s.signed_resid[i] = d;
  if (r <= o.tolerance) {
    s.stop[i] = Stop::kDone;
    return {};
  }
  if (r < o.progress * s.best[i]) {
    s.best[i] = r;
    s.strikes[i] = 0;
  } else if (o.stall_steps > 0 && ++s.strikes[i] >= o.stall_steps) {
    s.stop[i] = Stop::kStalled;
    return {};
  }
  s.best[i] = std::min(s.best[i], r);
  if (paired && d * last < 0.f) {  // bracketed: the secant's zero between the two samples
    s.sigma[i] = 0.f;
    return (s.prev[i] - s.cur[i]) * (d / (d - last));
  }
  s.sigma[i] = step_factor(o, paired, d, last, s.sigma[i]);
  Vec3f step = g * (s.sigma[i] * d / g2);
  const float len = norm(step);
  if (len > max_step) step = step * (max_step / len);
  return step;
}

/// One Newton step of every live vertex (2013 eq. 4): the field evaluated in batches of live
/// vertices, each vertex moved or stopped (newton_move); the stopped ones leave `live`.
/// Returns the field evaluations made.
long newton_step(const FieldFunction& field, const ProjectorOptions& o, const std::vector<float>& iso,
                 const std::vector<float>& max_step, ProjectionBuffers& s) {
  const std::size_t m = s.live.size();
  parallel_for(m, o.grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) s.batch[k] = s.cur[static_cast<std::size_t>(s.live[k])];
    detail::eval_field(field, s.batch.data() + b, e - b, s.slot_values.data() + b, s.grads.data() + b,
                       s.slot_contact.data() + b, 0);
    for (std::size_t k = b; k < e; ++k) {
      const auto i = static_cast<std::size_t>(s.live[k]);
      s.values[i] = s.slot_values[k];
      s.field_contact[i] = s.slot_contact[k];
      s.moved[k] = newton_move(o, iso[i], max_step[i], i, s.values[i], s.grads[k], s);
    }
  });
  for (std::size_t k = 0; k < m; ++k) {
    const auto i = static_cast<std::size_t>(s.live[k]);
    s.stale[i] = 0;
    s.prev[i] = s.cur[i];
    if (s.stop[i] == Stop::kLive) {
      s.cur[i] += s.moved[k];
      s.stale[i] = 1;
    }
  }
  s.live.erase(std::remove_if(s.live.begin(), s.live.end(),
                              [&](int i) { return s.stop[static_cast<std::size_t>(i)] != Stop::kLive; }),
               s.live.end());
  s.relaxed = false;
  return static_cast<long>(m);
}

/// MVC tangential relaxation (2013 eq. 5, 6) of the live vertices, with the paper's μ(|f - iso|)
/// unless ProjectorOptions::mu is set. Stopped vertices hold their place.
void relaxation_step(const Adjacency& adj, const std::vector<float>& phi, const ProjectorOptions& o,
                     ProjectionBuffers& s) {
  const std::size_t m = s.live.size();
  parallel_for(m, o.grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) {
      const auto i = static_cast<std::size_t>(s.live[k]);
      s.moved[k] = s.cur[i];
      float mu = o.mu;
      if (mu < 0.f) {
        const float r = std::abs(s.signed_resid[i]) - 1.f;
        mu = std::max(0.f, 1.f - r * r * r * r);
      }
      s.moved[k] = mvc_relaxed(adj, phi, s.cur, i, s.normal[i], mu);
    }
  });
  for (std::size_t k = 0; k < m; ++k) s.cur[static_cast<std::size_t>(s.live[k])] = s.moved[k];
  s.relaxed = m > 0;
}

}  // namespace
TrackStats Projector2013::project(const FieldFunction& field, Positions& positions) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t n = iso_.size();
  detail::validate_call(positions, n, field);
  ProjectionBuffers s(detail::to_points(positions, "initial positions"));

  TrackStats stats;
  for (int it = 0; it < options_.max_iterations && !s.live.empty(); ++it) {
    stats.vertex_updates += static_cast<long>(s.live.size());
    stats.field_evaluations += newton_step(field, options_, iso_, max_step_, s);
    stats.iterations = it + 1;
    // A relaxation after every pair of Newton steps (2013 §5).
    if (it % 2 == 1) relaxation_step(adj_, phi_, options_, s);
  }
  stats.converged = s.live.empty() || options_.max_iterations == 0;
  flags_.contact.assign(n, 0);
  flags_.lost.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    flags_.contact[i] = s.stop[i] == Stop::kContact;
    flags_.lost[i] = s.stop[i] == Stop::kLost;
    stats.stalled_vertices += s.stop[i] == Stop::kStalled;
  }
  stats.smoothed_vertices =
      detail::contact_smoothing(adj_, flags_.contact, options_.smoothing, options_.grain, s.cur, flags_.beta);
  finish_statistics(field, s.cur, s.stale, s.values, s.field_contact, stats);
  detail::from_points(s.cur, positions);
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return stats;
}

void Projector2013::finish_statistics(const FieldFunction& field, const std::vector<Vec3f>& pts,
                                      const std::vector<std::uint8_t>& stale, std::vector<float>& values,
                                      std::vector<std::uint8_t>& field_contact, TrackStats& stats) {
  std::vector<int> redo;  // moved since their last evaluation (or never evaluated): evaluated again
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (stale[i] || flags_.beta[i] > 0.f) redo.push_back(static_cast<int>(i));
  std::vector<Vec3f> p(redo.size()), g(redo.size());
  std::vector<float> v(redo.size());
  std::vector<std::uint8_t> c(redo.size());
  for (std::size_t a = 0; a < redo.size(); ++a) p[a] = pts[static_cast<std::size_t>(redo[a])];
  detail::eval_field(field, p.data(), p.size(), v.data(), g.data(), c.data(), options_.grain);
  for (std::size_t a = 0; a < redo.size(); ++a) {
    values[static_cast<std::size_t>(redo[a])] = v[a];
    field_contact[static_cast<std::size_t>(redo[a])] = c[a];
  }
  for (std::size_t i = 0; i < pts.size(); ++i)  // contacts the field reports at the final positions
    if (field_contact[i]) flags_.contact[i] = 1;
  detail::vertex_stats(values, iso_, flags_, stats);
  if (options_.count_inverted)
    stats.inverted_triangles =
        detail::count_flags(detail::inverted_triangles(field, pts, triangles_, options_.grain));
}

}  // namespace isokit::track
