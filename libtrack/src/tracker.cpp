// SPDX-License-Identifier: MIT
#include "isokit/track/tracker.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "detail.h"
#include "isokit/core/parallel.h"

namespace isokit::track {

namespace {

// Relaxation iterations before the Chebyshev acceleration starts (Wang 2015 uses 10): the first
// iterations are dominated by the Newton projection of the initial guess, not by the linear part.
constexpr int kChebyshevDelay = 10;
// The Chebyshev extrapolation assumes a linear iteration: a vertex whose gradient turned by more
// than this between its last two evaluations (a crease, a contact valley) takes a plain Jacobi step.
constexpr float kChebyshevMaxTurnDeg = 10.f;

void check_options(const TrackerOptions& o) {
  require(std::isfinite(o.sigma) && o.sigma > 0.f && o.sigma <= 1.f, "TrackerOptions::sigma",
          "must be in (0, 1] (got " + format_number(o.sigma) + ")", "use 1 (Newton) or 0.35 (2013)");
  require(o.initial_newton_steps >= 0 && o.max_iterations >= 0, "TrackerOptions iterations", "must be >= 0",
          "pass non-negative iteration counts");
  require(std::isfinite(o.tolerance) && o.tolerance >= 0.f, "TrackerOptions::tolerance",
          "must be finite and >= 0", "use e.g. 1e-5");
  require(std::isfinite(o.max_step) && o.max_step > 0.f, "TrackerOptions::max_step", "must be > 0",
          "use e.g. 0.5");
  require(std::isfinite(o.max_cotangent) && o.max_cotangent > 0.f, "TrackerOptions::max_cotangent",
          "must be > 0", "use e.g. 10");
  require(std::isfinite(o.min_gradient) && o.min_gradient > 0.f, "TrackerOptions::min_gradient",
          "must be > 0", "use e.g. 1e-6");
  require(o.contact_angle_deg > 0.f && o.contact_angle_deg <= 180.f, "TrackerOptions::contact_angle_deg",
          "must be in (0, 180]", "use 55 (2013)");
  require(std::isfinite(o.min_contact_damping) && o.min_contact_damping > 0.f && o.min_contact_damping <= 1.f,
          "TrackerOptions::min_contact_damping",
          "must be in (0, 1] (got " + format_number(o.min_contact_damping) + ")", "use e.g. 0.25");
  require(std::isfinite(o.chebyshev_rho) && o.chebyshev_rho >= 0.f && o.chebyshev_rho < 1.f,
          "TrackerOptions::chebyshev_rho", "must be in [0, 1) (got " + format_number(o.chebyshev_rho) + ")",
          "use 0 (plain Jacobi) or e.g. 0.998");
  require(o.smoothing.beta_diffusion_steps >= 0 && o.smoothing.smoothing_steps >= 0, "SmoothingOptions",
          "step counts must be >= 0", "pass non-negative counts");
}

}  // namespace

IsoSurfaceTracker::IsoSurfaceTracker(const Positions& rest, const Triangles& triangles,
                                     std::vector<float> iso, TrackerOptions options)
    : rest_(rest), triangles_(triangles), iso_(std::move(iso)), options_(options) {
  check_options(options_);
  detail::validate_mesh(rest_, triangles_, iso_.size());
  rest_pts_ = detail::to_points(rest_, "rest positions");
  const std::vector<Vec3f>& pts = rest_pts_;
  for (std::size_t i = 0; i < iso_.size(); ++i)
    require(std::isfinite(iso_[i]), "iso value " + std::to_string(i),
            "is not finite (" + format_number(iso_[i]) + ")", "sample iso-values from a finite field");
  adj_ = vertex_adjacency(triangles_, static_cast<int>(pts.size()));
  detail::cotangent_weights(pts, triangles_, adj_, options_.max_cotangent, weights_, weight_sum_);
  max_step_ = detail::mean_edge_lengths(pts, adj_);
  for (float& s : max_step_) s *= options_.max_step;
  diagonal_ = detail::bbox_diagonal(pts);
  mask_.assign(pts.size(), 1.f);
}

void IsoSurfaceTracker::set_relaxation_mask(std::vector<float> mask) {
  require(mask.size() == mask_.size(), "relaxation mask",
          "size " + std::to_string(mask.size()) + " differs from the vertex count " +
              std::to_string(mask_.size()),
          "pass one value per vertex");
  for (std::size_t i = 0; i < mask.size(); ++i)
    require(mask[i] >= 0.f && mask[i] <= 1.f, "relaxation mask vertex " + std::to_string(i),
            "is outside [0, 1] (" + format_number(mask[i]) + ")", "use 0 (no tangential move) .. 1");
  mask_ = std::move(mask);
}

TrackStats IsoSurfaceTracker::track(const FieldFunction& field, const std::vector<Mat3f>& rotations,
                                    Positions& positions) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t n = iso_.size();
  detail::validate_call(positions, n, field);
  require(rotations.empty() || rotations.size() == n, "rotations",
          "size " + std::to_string(rotations.size()) + " differs from the vertex count " + std::to_string(n),
          "pass one rotation per vertex or none (identity)");
  for (std::size_t i = 0; i < rotations.size(); ++i)
    for (float v : rotations[i].m)
      require(std::isfinite(v), "rotation " + std::to_string(i), "is not finite", "pass finite rotations");
  std::vector<Vec3f> cur = detail::to_points(positions, "initial positions");
  // Three position buffers: x_{k-1} (`prev`, for the Chebyshev step), x_k (`cur`), x_{k+1}.
  std::vector<Vec3f> prev = cur, next(n), grads(n), normal(n, Vec3f{});
  std::vector<float> values(n), moves(n), damping(n, 1.f);  // moves: squared lengths
  std::vector<std::uint8_t> fc(n);
  flags_.contact.assign(n, 0);
  flags_.lost.assign(n, 0);
  const std::vector<Vec3f>& rest = rest_pts_;
  const bool has_rot = !rotations.empty();
  const float cos_contact = std::cos(options_.contact_angle_deg * 3.14159265358979f / 180.f);
  const float min_g2 = options_.min_gradient * options_.min_gradient;
  const float tol = options_.tolerance * diagonal_;
  const float rho2 = options_.chebyshev_rho * options_.chebyshev_rho;
  const float cos_linear = std::cos(kChebyshevMaxTurnDeg * 3.14159265358979f / 180.f);
  std::vector<std::uint8_t> linear(n, 0);  // gradient turned by < kChebyshevMaxTurnDeg last time
  float omega = 1.f;                       // Chebyshev weight of the current iteration (1: plain Jacobi)

  // Per directed edge (i, j), constant during the call: ½ (Ri + Rj)(pi - pj) (= pi - pj exactly
  // for identity rotations, so the rest pose gives δ = 0 bit for bit).
  std::vector<Vec3f> targets(adj_.neighbors.size());
  parallel_for(n, options_.grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i)
      for (int k = adj_.offsets[i]; k < adj_.offsets[i + 1]; ++k) {
        const int j = adj_.neighbors[k];
        const Vec3f e_ij = rest[i] - rest[j];
        targets[k] = has_rot ? (rotations[i] * e_ij + rotations[j] * e_ij) * 0.5f : e_ij;
      }
  });

  // One iteration over the chunk [b, e): optional Jacobi tangential ARAP step (reads `cur` and
  // `prev`, writes `next`), one field evaluation at `next`, one Newton step in place on `next`.
  auto kernel = [&](bool jacobi, std::size_t b, std::size_t e) {
    // Raw pointers: lets the compiler keep them in registers across the stores to `nx`.
    const int* off = adj_.offsets.data();
    const int* nb = adj_.neighbors.data();
    const float* w = weights_.data();
    const Vec3f* tg = targets.data();
    const Vec3f* cu = cur.data();
    const Vec3f* pv = prev.data();
    Vec3f* nx = next.data();
    for (std::size_t i = b; i < e; ++i) {
      const Vec3f p = cu[i];
      Vec3f q = p;
      const int s = off[i], t = off[i + 1];
      if (jacobi && mask_[i] > 0.f && !flags_.lost[i] && s < t) {
        // Unconstrained minimiser of E in p̂i with the neighbours fixed, as a displacement:
        // δ = Σ wij ((p̂j - p̂i) + ½ (Ri + Rj)(pi - pj)) / Σ wij.
        // Summed per edge, so that p̂ = p with Ri = I gives exactly δ = 0 (no drift at rest).
        Vec3f acc{};
        for (int k = s; k < t; ++k) acc += ((cu[nb[k]] - p) + tg[k]) * w[k];
        Vec3f d = acc / weight_sum_[i];
        const Vec3f nrm = normal[i];
        // Restrict to the current tangent plane; not at contact vertices, whose gradient direction
        // is meaningless on the contact valley (full 3D step, damped below).
        if (!flags_.contact[i]) d = d - nrm * dot(d, nrm);
        const float scale = mask_[i] * damping[i];
        q = p + d * scale;
        if (omega != 1.f && linear[i]) {
          // Chebyshev semi-iteration: x_{k+1} = x_{k-1} + ω (x̂_{k+1} - x_{k-1}), i.e. the Jacobi
          // target plus (ω - 1) times its distance to x_{k-1}; that momentum is kept in the tangent
          // plane (the Newton step below handles the normal direction) and scaled like the step.
          const Vec3f mom = q - pv[i];
          q += (mom - nrm * dot(mom, nrm)) * ((omega - 1.f) * scale);
        }
      }
      nx[i] = q;
    }
    detail::eval_field(field, next.data() + b, e - b, values.data() + b, grads.data() + b, fc.data() + b, 0);
    for (std::size_t i = b; i < e; ++i) {
      const Vec3f g = grads[i];
      const float g2 = squared_norm(g);
      if (flags_.lost[i] || !std::isfinite(values[i]) || !detail::finite(g) || !(g2 > min_g2)) {
        flags_.lost[i] = 1;
        next[i] = cur[i];  // left in place
        moves[i] = 0.f;
        continue;
      }
      const Vec3f nrm = g / std::sqrt(g2);
      const bool seen = normal[i] != Vec3f{};
      const float turn = dot(nrm, normal[i]);  // cosine of the turn since the last evaluation
      linear[i] = seen && turn >= cos_linear ? 1 : 0;
      if (seen && turn < cos_contact) {
        // The gradient turned by more than the contact angle: the vertex crossed a gradient
        // discontinuity (a contact valley). Flag it and halve its Newton and tangential steps
        // from now on, so that it settles on the contact surface instead of oscillating across.
        if (options_.angle_contacts) flags_.contact[i] = 1;
        damping[i] = std::max(damping[i] * 0.5f, options_.min_contact_damping);
      }
      {
        Vec3f step = g * (options_.sigma * damping[i] * (iso_[i] - values[i]) / g2);
        const float len2 = squared_norm(step);
        if (len2 > max_step_[i] * max_step_[i]) step = step * (max_step_[i] / std::sqrt(len2));
        next[i] += step;
      }
      normal[i] = nrm;
      moves[i] = squared_norm(next[i] - cur[i]);  // squared: one square root per iteration below
    }
  };

  TrackStats stats;
  auto run = [&](bool jacobi) {
    parallel_for(n, options_.grain, [&](std::size_t b, std::size_t e) { kernel(jacobi, b, e); });
    prev.swap(cur);  // prev <- x_k
    cur.swap(next);  // cur <- x_{k+1}; `next` is scratch
    float mx = 0.f;
    for (std::size_t i = 0; i < n; ++i) mx = std::max(mx, moves[i]);
    mx = std::sqrt(mx);
    return mx;
  };
  for (int k = 0; k < options_.initial_newton_steps; ++k) {
    const float mx = run(false);
    if (mx <= tol) break;
  }
  for (int k = 0; k < options_.max_iterations; ++k) {
    // Chebyshev weights (Wang 2015, "A Chebyshev semi-iterative approach for accelerating
    // projective and position-based dynamics"): ω = 2 / (2 - ρ²) at the first accelerated
    // iteration, then ω ← 4 / (4 - ρ² ω); plain Jacobi (ω = 1) before, or when ρ = 0.
    if (rho2 > 0.f && k >= kChebyshevDelay)
      omega = k == kChebyshevDelay ? 2.f / (2.f - rho2) : 4.f / (4.f - rho2 * omega);
    stats.max_move = run(true);
    stats.iterations = k + 1;
    if (stats.max_move <= tol) {
      stats.converged = true;
      break;
    }
  }
  if (options_.max_iterations == 0) stats.converged = true;
  // Contacts reported by the field at the last evaluation also get smoothed.
  for (std::size_t i = 0; i < n; ++i)
    if (fc[i] && !flags_.lost[i]) flags_.contact[i] = 1;
  // Folds: the vertices of a triangle that the relaxation left inverted (typically at a crease
  // where no consecutive gradients differed by the contact angle) are smoothed like contacts.
  std::vector<std::uint8_t> inverted;
  if (options_.fold_contacts) {
    inverted = detail::inverted_triangles(field, cur, triangles_, options_.grain);
    for (Eigen::Index f = 0; f < triangles_.rows(); ++f)
      if (inverted[static_cast<std::size_t>(f)])
        for (int k = 0; k < 3; ++k)
          if (!flags_.lost[triangles_(f, k)]) flags_.contact[triangles_(f, k)] = 1;
  }
  stats.smoothed_vertices =
      detail::contact_smoothing(adj_, flags_.contact, options_.smoothing, options_.grain, cur, flags_.beta);
  // Unsmoothed positions: the fold test above already counted the inverted triangles.
  const bool unchanged = stats.smoothed_vertices == 0 || options_.smoothing.smoothing_steps == 0;
  detail::final_stats(field, cur, triangles_, iso_, options_.grain, flags_, stats,
                      options_.fold_contacts && unchanged ? &inverted : nullptr);
  for (std::size_t i = 0; i < n; ++i)
    if (!detail::finite(cur[i])) cur[i] = detail::row(positions, static_cast<Eigen::Index>(i));
  detail::from_points(cur, positions);
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return stats;
}

}  // namespace isokit::track
