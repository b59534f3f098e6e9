// SPDX-License-Identifier: MIT
#include "isokit/track/projector2013.h"

#include <algorithm>
#include <chrono>
#include <cmath>
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

/// The working arrays of one project() call.
struct ProjectionBuffers {
  explicit ProjectionBuffers(std::vector<Vec3f> initial)
      : cur(std::move(initial)),
        next(cur.size()),
        grads(cur.size()),
        normal(cur.size(), Vec3f{}),
        batch(cur.size()),
        values(cur.size()),
        resid(cur.size(), 0.f),
        fc(cur.size()),
        done(cur.size(), 0),
        live(cur.size()) {
    for (std::size_t i = 0; i < live.size(); ++i) live[i] = static_cast<int>(i);
  }
  std::vector<Vec3f> cur, next, grads, normal, batch;
  std::vector<float> values, resid;
  std::vector<std::uint8_t> fc, done;
  /// The vertices still projected: a vertex stopped at a contact or lost keeps its position for
  /// the rest of the call, so its field is not evaluated again (the same result, fewer
  /// evaluations). `batch` holds their positions, gathered per iteration.
  std::vector<int> live;
};

/// One Newton step of every live vertex (2013 eq. 4, sign so that f moves toward iso with inward
/// gradients); a vertex whose gradient turned by more than the contact angle stops (contact), one
/// without a usable gradient is lost. The stopped vertices leave `live`.
void newton_step(const FieldFunction& field, const ProjectorOptions& o, const std::vector<float>& iso,
                 const std::vector<float>& max_step, VertexFlags& flags, ProjectionBuffers& s) {
  const float cos_contact = std::cos(o.contact_angle_deg * kPiF / 180.f);
  const float min_g2 = o.min_gradient * o.min_gradient;
  s.next = s.cur;
  parallel_for(s.live.size(), o.grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) s.batch[k] = s.cur[static_cast<std::size_t>(s.live[k])];
    detail::eval_field(field, s.batch.data() + b, e - b, s.values.data() + b, s.grads.data() + b,
                       s.fc.data() + b, 0);
    for (std::size_t k = b; k < e; ++k) {
      const auto i = static_cast<std::size_t>(s.live[k]);
      const Vec3f g = s.grads[k];
      const float value = s.values[k];
      const float g2 = squared_norm(g);
      if (!std::isfinite(value) || !detail::finite(g) || !(g2 > min_g2)) {
        flags.lost[i] = 1;
        continue;
      }
      const Vec3f nrm = g / std::sqrt(g2);
      if (s.normal[i] != Vec3f{} && dot(nrm, s.normal[i]) < cos_contact) {
        flags.contact[i] = 1;  // stopped at a gradient discontinuity
        continue;
      }
      s.normal[i] = nrm;
      s.resid[i] = std::abs(iso[i] - value);
      s.done[i] = s.resid[i] <= o.tolerance;
      Vec3f step = g * (o.sigma * (iso[i] - value) / g2);
      const float len = norm(step);
      if (len > max_step[i]) step = step * (max_step[i] / len);
      s.next[i] = s.cur[i] + step;
    }
  });
  s.cur.swap(s.next);
  const auto stopped = [&](int i) {
    return flags.contact[static_cast<std::size_t>(i)] || flags.lost[static_cast<std::size_t>(i)];
  };
  s.live.erase(std::remove_if(s.live.begin(), s.live.end(), stopped), s.live.end());
}

/// MVC tangential relaxation (2013 eq. 5, 6) of the vertices still projected, with the paper's
/// μ(|f - iso|) unless ProjectorOptions::mu is set.
void relaxation_step(const Adjacency& adj, const std::vector<float>& phi, const ProjectorOptions& o,
                     const VertexFlags& flags, ProjectionBuffers& s) {
  parallel_for(s.cur.size(), o.grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      s.next[i] = s.cur[i];
      if (flags.contact[i] || flags.lost[i] || s.normal[i] == Vec3f{}) continue;
      float mu = o.mu;
      if (mu < 0.f) {
        const float r = s.resid[i] - 1.f;
        mu = std::max(0.f, 1.f - r * r * r * r);
      }
      s.next[i] = mvc_relaxed(adj, phi, s.cur, i, s.normal[i], mu);
    }
  });
  s.cur.swap(s.next);
}

}  // namespace

TrackStats Projector2013::project(const FieldFunction& field, Positions& positions) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t n = iso_.size();
  detail::validate_call(positions, n, field);
  ProjectionBuffers s(detail::to_points(positions, "initial positions"));
  flags_.contact.assign(n, 0);
  flags_.lost.assign(n, 0);

  TrackStats stats;
  for (int it = 0; it < options_.max_iterations; ++it) {
    newton_step(field, options_, iso_, max_step_, flags_, s);
    stats.iterations = it + 1;
    bool all = true;
    for (std::size_t i = 0; i < n; ++i) all = all && (s.done[i] || flags_.contact[i] || flags_.lost[i]);
    if (all) {
      stats.converged = true;
      break;
    }
    // A relaxation after every pair of Newton steps (2013 §5).
    if (it % 2 == 1) relaxation_step(adj_, phi_, options_, flags_, s);
  }
  if (options_.max_iterations == 0) stats.converged = true;
  stats.smoothed_vertices =
      detail::contact_smoothing(adj_, flags_.contact, options_.smoothing, options_.grain, s.cur, flags_.beta);
  detail::final_stats(field, s.cur, triangles_, iso_, options_.grain, flags_, stats);
  detail::from_points(s.cur, positions);
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return stats;
}

}  // namespace isokit::track
