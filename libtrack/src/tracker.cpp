// SPDX-License-Identifier: MIT
#include "isokit/track/tracker.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <utility>

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
// Fold test: a triangle is tested at its centroid when its normal deviates from the outward
// direction at one of its vertices by more than this (an inverted one deviates by more than 90°).
constexpr float kFoldCandidateDeg = 45.f;

/// `out[k] = v[order[k]]`.
template <class T>
std::vector<T> permuted(const std::vector<T>& v, const std::vector<int>& order) {
  std::vector<T> out(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) out[k] = v[std::size_t(order[k])];
  return out;
}

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
          "use 0 (plain Jacobi) or e.g. 0.995");
  require(o.cg_max_iterations >= 1 && o.cg_rings >= 1, "TrackerOptions CG",
          "cg_max_iterations and cg_rings must be >= 1", "use e.g. 200 and 2");
  require(o.smoothing.beta_diffusion_steps >= 0 && o.smoothing.smoothing_steps >= 0, "SmoothingOptions",
          "step counts must be >= 0", "pass non-negative counts");
  require(std::isfinite(o.fold_repair.max_fraction) && o.fold_repair.max_fraction >= 0 &&
              o.fold_repair.max_fraction <= 1,
          "FoldRepairOptions::max_fraction",
          "must be in [0, 1] (got " + format_number(o.fold_repair.max_fraction) + ")", "use e.g. 0.1");
  require(o.fold_repair.rounds >= 0 && o.fold_repair.steps >= 0 && o.fold_repair.rings >= 0,
          "FoldRepairOptions", "rounds, steps and rings must be >= 0", "use e.g. 8, 5 and 2 (0 rounds: off)");
  const OrientationRepairOptions& r = o.orientation_repair;
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

IsoSurfaceTracker::IsoSurfaceTracker(const Positions& rest, const Triangles& triangles,
                                     std::vector<float> iso, TrackerOptions options)
    : triangles_(triangles), iso_(std::move(iso)), options_(options) {
  check_options(options_);
  detail::validate_mesh(rest, triangles_, iso_.size());
  rest_pts_ = detail::to_points(rest, "rest positions");
  for (std::size_t i = 0; i < iso_.size(); ++i)
    if (!std::isfinite(iso_[i]))
      require(false, "iso value " + std::to_string(i), "is not finite (" + format_number(iso_[i]) + ")",
              "sample iso-values from a finite field");
  if (options_.reorder_vertices) {
    order_ = detail::spatial_order(rest_pts_);
    rank_.resize(order_.size());
    for (std::size_t k = 0; k < order_.size(); ++k) rank_[std::size_t(order_[k])] = static_cast<int>(k);
    rest_pts_ = permuted(rest_pts_, order_);
    iso_ = permuted(iso_, order_);
    for (Eigen::Index f = 0; f < triangles_.rows(); ++f)
      for (int c = 0; c < 3; ++c) triangles_(f, c) = rank_[std::size_t(triangles_(f, c))];
  }
  const std::vector<Vec3f>& pts = rest_pts_;
  adj_ = vertex_adjacency(triangles_, static_cast<int>(pts.size()));
  detail::cotangent_weights(pts, triangles_, adj_, options_.max_cotangent, weights_, weight_sum_);
  max_step_ = detail::mean_edge_lengths(pts, adj_);
  diagonal_ = detail::bbox_diagonal(pts);
  // Lazy evaluation radius: a tangential move d from where the field was evaluated leaves the
  // vertex off its iso-surface by about κ |d|² / 2 (κ: the iso-surface's curvature) beyond what the
  // linearised field predicts; with κ at most 1 / ℓ (ℓ: the vertex's mean edge length: the mesh
  // resolves the surface) that stays below the tolerance for |d|² ≤ 2 · tolerance · ℓ.
  lazy_r2_.resize(max_step_.size());
  for (std::size_t i = 0; i < max_step_.size(); ++i)
    lazy_r2_[i] = 2.f * options_.tolerance * diagonal_ * max_step_[i];
  for (float& s : max_step_) s *= options_.max_step;
  mask_.assign(pts.size(), 1.f);
  vertex_faces_ = detail::vertex_faces(triangles_, pts.size());
}

void IsoSurfaceTracker::set_relaxation_mask(std::vector<float> mask) {
  require(mask.size() == mask_.size(), "relaxation mask",
          "size " + std::to_string(mask.size()) + " differs from the vertex count " +
              std::to_string(mask_.size()),
          "pass one value per vertex");
  for (std::size_t i = 0; i < mask.size(); ++i)
    require(mask[i] >= 0.f && mask[i] <= 1.f, "relaxation mask vertex " + std::to_string(i),
            "is outside [0, 1] (" + format_number(mask[i]) + ")", "use 0 (no tangential move) .. 1");
  mask_ = order_.empty() ? std::move(mask) : permuted(mask, order_);
}

void IsoSurfaceTracker::set_fold_repair_mask(std::vector<std::uint8_t> mask) {
  require(mask.empty() || mask.size() == mask_.size(), "fold repair mask",
          "size " + std::to_string(mask.size()) + " differs from the vertex count " +
              std::to_string(mask_.size()),
          "pass one flag per vertex, or none");
  repair_mask_ = order_.empty() || mask.empty() ? std::move(mask) : permuted(mask, order_);
}

Adjacency IsoSurfaceTracker::adjacency() const {
  if (order_.empty()) return adj_;
  Adjacency out;
  const std::size_t n = order_.size();
  out.offsets.assign(n + 1, 0);
  for (std::size_t u = 0; u < n; ++u) out.offsets[u + 1] = out.offsets[u] + adj_.degree(rank_[u]);
  out.neighbors.resize(adj_.neighbors.size());
  for (std::size_t u = 0; u < n; ++u) {
    const int k = rank_[u];
    int* row = out.neighbors.data() + out.offsets[u];
    for (int e = adj_.offsets[std::size_t(k)]; e < adj_.offsets[std::size_t(k) + 1]; ++e)
      *row++ = order_[std::size_t(adj_.neighbors[std::size_t(e)])];
    std::sort(out.neighbors.data() + out.offsets[u], row);
  }
  return out;
}

std::vector<float> IsoSurfaceTracker::weights() const {
  if (order_.empty()) return weights_;
  const Adjacency user = adjacency();
  std::vector<float> out(weights_.size());
  for (std::size_t u = 0; u < order_.size(); ++u)
    for (int e = user.offsets[u]; e < user.offsets[u + 1]; ++e) {
      const int k = rank_[u], j = rank_[std::size_t(user.neighbors[std::size_t(e)])];
      out[std::size_t(e)] = weights_[std::size_t(detail::find_neighbor(adj_, k, j))];
    }
  return out;
}

void IsoSurfaceTracker::mark_rest_inversions(const FieldFunction& rest_field) {
  require(static_cast<bool>(rest_field), "rest field", "is empty", "pass the field at the rest pose");
  rest_inverted_ = detail::inverted_triangles(rest_field, rest_pts_, triangles_, options_.grain);
}

namespace {

// The vertex set one iteration updates: the vertices that moved by more than the tolerance in the
// previous iteration and their one-ring neighbours (whose Jacobi targets changed). Sorted ascending,
// so the result does not depend on the order in which vertices were found.
class ActiveSet {
 public:
  ActiveSet(std::size_t n, const Adjacency& adj) : adj_(adj), mark_(n, 0), dense_(n) {
    for (std::size_t i = 0; i < n; ++i) dense_[i] = static_cast<int>(i);
  }
  const std::vector<int>& all() const { return dense_; }

  /// Rebuilds `active` from the per-vertex flags `moved` (set only inside `active`; all zero on
  /// return).
  void update(std::vector<int>& active, std::vector<std::uint8_t>& moved) {
    const std::size_t n = dense_.size();
    std::size_t count = 0;
    for (int i : active) count += moved[i];
    if (count == n) {  // everything still moves: keep every vertex
      std::fill(moved.begin(), moved.end(), std::uint8_t{0});
      return;
    }
    if (small(count)) {
      seeds_.clear();
      for (int i : active)
        if (moved[i]) seeds_.push_back(i), moved[i] = 0;
      dilate(seeds_);
      active.swap(seeds_);
      return;
    }
    for (int i : active)
      if (moved[i]) moved[i] = 0, mark_ring(i);
    collect(active);
  }

  /// Adds the one-ring neighbours of every vertex of `active` (sorted ascending on return).
  void dilate(std::vector<int>& active) {
    if (!small(active.size())) {
      for (int i : active) mark_ring(i);
      collect(active);
      return;
    }
    next_.clear();
    auto add = [&](int v) {
      if (!mark_[v]) mark_[v] = 1, next_.push_back(v);
    };
    for (int i : active) {
      add(i);
      for (int k = adj_.offsets[i]; k < adj_.offsets[i + 1]; ++k) add(adj_.neighbors[k]);
    }
    for (int v : next_) mark_[v] = 0;
    std::sort(next_.begin(), next_.end());
    active.swap(next_);
  }

 private:
  // Few seeds: list their rings and sort; more: mark them (branch-free stores) and scan the marks
  // (the scan costs about as much as 1/32 of the vertices' rings).
  bool small(std::size_t seeds) const { return seeds * 32 < mark_.size(); }
  void mark_ring(int i) {
    mark_[i] = 1;
    for (int k = adj_.offsets[i]; k < adj_.offsets[i + 1]; ++k) mark_[adj_.neighbors[k]] = 1;
  }
  // `out` <- the marked vertices in ascending order; clears the marks.
  void collect(std::vector<int>& out) {
    const std::size_t n = mark_.size();
    out.resize(n);
    std::size_t c = 0;
    for (std::size_t v = 0; v < n; ++v) {
      out[c] = static_cast<int>(v);
      c += mark_[v];
      mark_[v] = 0;
    }
    out.resize(c);
  }

  const Adjacency& adj_;
  std::vector<std::uint8_t> mark_;
  std::vector<int> dense_;
  std::vector<int> seeds_, next_;  // scratch, kept between iterations
};

}  // namespace

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
      if (!std::isfinite(v))  // message built only on failure (hot path)
        require(false, "rotation " + std::to_string(i), "is not finite", "pass finite rotations");
  std::vector<Vec3f> cur = detail::to_points(positions, "initial positions");
  if (!order_.empty()) cur = permuted(cur, order_);
  // The caller's index of internal vertex i.
  auto user = [&](std::size_t i) { return order_.empty() ? i : std::size_t(order_[i]); };
  // Three position buffers: x_{k-1} (`prev`, for the Chebyshev step), x_k (`cur`), x_{k+1}.
  // Only the active vertices are written; for the others next = cur = prev.
  std::vector<Vec3f> prev = cur, next = cur, normal(n, Vec3f{});
  std::vector<float> values(n), moves(n, 0.f), damping(n, 1.f);  // moves: squared lengths
  const bool cg = options_.relaxation == Relaxation::kConjugateGradient;
  // CG relaxation: a vertex whose Newton steps overshoot (the residual changes sign without
  // halving: a 2-cycle across a kink of the field) has its Newton steps halved for the rest of the
  // call, down to 1/16; the Jacobi relaxation keeps the paper's plain Newton steps.
  std::vector<float> last_residual(n, 0.f), newton_scale(n, 1.f);
  std::vector<std::uint8_t> fc(n, 0), moved(n, 0), touched(n, 0);
  // Compact per-iteration buffers of the evaluated vertices (field input and output, vertex).
  std::vector<Vec3f> apts(n), agrads(n);
  std::vector<float> avals(n);
  std::vector<std::uint8_t> afc(n);
  std::vector<int> aidx(n);
  // Lazy evaluation: where the field was last evaluated and its gradient there, whether the vertex
  // may take linearised Newton steps (`lazy`), and whether it moved since its last evaluation.
  const bool lazy_on = options_.lazy_evaluation;
  std::vector<Vec3f> eval_pts(lazy_on ? n : 0), eval_grads(lazy_on ? n : 0);
  std::vector<std::uint8_t> lazy(n, 0), pending(n, 0);
  std::atomic<long> evaluations{0};
  flags_.contact.assign(n, 0);
  flags_.lost.assign(n, 0);
  const std::vector<Vec3f>& rest = rest_pts_;
  const bool has_rot = !rotations.empty();
  const float cos_contact = std::cos(options_.contact_angle_deg * 3.14159265358979f / 180.f);
  const float min_g2 = options_.min_gradient * options_.min_gradient;
  const float tol = options_.tolerance * diagonal_;
  const float tol2 = tol * tol;
  // Squared trust radius of the linearisation per vertex: starts at twice the tolerance, then
  // follows the error measured at each evaluation after lazy steps; at most lazy_r2_.
  std::vector<float> radius2(lazy_on ? n : 0);
  for (std::size_t i = 0; i < radius2.size(); ++i) radius2[i] = std::min(4.f * tol2, lazy_r2_[i]);
  const float rho2 = options_.chebyshev_rho * options_.chebyshev_rho;
  const float cos_linear = std::cos(kChebyshevMaxTurnDeg * 3.14159265358979f / 180.f);
  std::vector<std::uint8_t> linear(n, 0);  // gradient turned by < kChebyshevMaxTurnDeg last time
  float omega = 1.f;                       // Chebyshev weight of the current iteration (1: plain Jacobi)
  ActiveSet set(n, adj_);
  std::vector<int> active = set.all();

  // Per directed edge (i, j), constant during the call: ½ (Ri + Rj)(pi - pj) (= pi - pj exactly
  // for identity rotations, so the rest pose gives δ = 0 bit for bit).
  std::vector<Vec3f> targets(adj_.neighbors.size());
  parallel_for(n, options_.grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i)
      for (int k = adj_.offsets[i]; k < adj_.offsets[i + 1]; ++k) {
        const int j = adj_.neighbors[k];
        const Vec3f e_ij = rest[i] - rest[j];
        targets[k] =
            has_rot ? (rotations[user(i)] * e_ij + rotations[user(std::size_t(j))] * e_ij) * 0.5f : e_ij;
      }
  });

  // Tangential ARAP displacement of vertex i (Jacobi, neighbours fixed), before the mask:
  // δ = Σ wij ((p̂j - p̂i) + ½ (Ri + Rj)(pi - pj)) / Σ wij, restricted to the current tangent plane
  // except at contact vertices, whose gradient direction is meaningless on the contact valley
  // (full 3D step, damped). Summed per edge, so that p̂ = p with Ri = I gives exactly δ = 0.
  const int* off = adj_.offsets.data();
  const int* nb = adj_.neighbors.data();
  const float* w = weights_.data();
  const Vec3f* tg = targets.data();
  // Raw pointers throughout the hot loops: lets the compiler keep them in registers across the
  // stores to the position buffers.
  const float* wsum = weight_sum_.data();
  const Vec3f* nrms = normal.data();
  const std::uint8_t* contact = flags_.contact.data();
  auto jacobi_delta = [=](const Vec3f* cu, std::size_t i, const Vec3f& p) {
    Vec3f acc{};
    for (int k = off[i]; k < off[i + 1]; ++k) acc += ((cu[nb[k]] - p) + tg[k]) * w[k];
    Vec3f d = acc / wsum[i];
    const Vec3f nrm = nrms[i];
    if (!contact[i]) d = d - nrm * dot(d, nrm);
    return d;
  };
  auto relaxes = [&](std::size_t i) { return mask_[i] > 0.f && !flags_.lost[i] && off[i] < off[i + 1]; };

  // One iteration over the active vertices [b, e) of `active`: optional Jacobi tangential ARAP
  // step (reads `cur` and `prev`, writes `next`), one field evaluation at `next`, one Newton step
  // in place on `next`. The points to evaluate are gathered into the compact buffers (positions
  // [b, b + count) of the task's range).
  // Lazy evaluation (options_.lazy_evaluation): a vertex that sat on its iso-surface at its last
  // evaluation, on a smooth part of the field, and is still within `lazy_r2` of where that
  // evaluation took place, takes its Newton step on the field linearised there instead
  // (`force`: evaluate every active vertex).
  // `disp` (CG relaxation): per-vertex displacement applied instead of the Jacobi step.
  std::vector<Vec3f> disp;
  auto kernel = [&](bool jacobi, bool dense, bool force, std::size_t b, std::size_t e) {
    const Vec3f* cu = cur.data();
    const Vec3f* pv = prev.data();
    Vec3f* nx = next.data();
    const int* act = active.data();
    Vec3f* in = apts.data();
    float* val = avals.data();
    Vec3f* grd = agrads.data();
    std::uint8_t* fcv = afc.data();
    int* idx = aidx.data();
    std::size_t count = b;
    auto newton_step = [&](std::size_t i, const Vec3f& g, float g2, float r) {
      Vec3f step = g * (options_.sigma * damping[i] * newton_scale[i] * r / g2);
      const float len2 = squared_norm(step);
      if (len2 > max_step_[i] * max_step_[i]) step = step * (max_step_[i] / std::sqrt(len2));
      return step;
    };
    for (std::size_t a = b; a < e; ++a) {
      const std::size_t i = dense ? a : static_cast<std::size_t>(act[a]);
      const Vec3f p = cu[i];
      Vec3f q = p;
      if (jacobi && !disp.empty()) {
        q = p + disp[i];
      } else if (jacobi && relaxes(i)) {
        const Vec3f nrm = nrms[i];
        const float scale = mask_[i] * damping[i];
        q = p + jacobi_delta(cu, i, p) * scale;
        if (omega != 1.f && linear[i]) {
          // Chebyshev semi-iteration: x_{k+1} = x_{k-1} + ω (x̂_{k+1} - x_{k-1}), i.e. the Jacobi
          // target plus (ω - 1) times its distance to x_{k-1}; that momentum is kept in the tangent
          // plane (the Newton step below handles the normal direction) and scaled like the step.
          const Vec3f mom = q - pv[i];
          q += (mom - nrm * dot(mom, nrm)) * ((omega - 1.f) * scale);
        }
      }
      nx[i] = q;
      if (!force && lazy[i]) {
        const Vec3f d = q - eval_pts[i];
        if (squared_norm(d) <= radius2[i]) {
          const Vec3f g = eval_grads[i];
          nx[i] += newton_step(i, g, squared_norm(g), iso_[i] - (values[i] + dot(g, d)));
          moves[i] = squared_norm(nx[i] - p);
          pending[i] = 1;
          continue;
        }
      }
      in[count] = q;
      idx[count++] = static_cast<int>(i);
    }
    detail::eval_field(field, in + b, count - b, val + b, grd + b, fcv + b, 0);
    for (std::size_t a = b; a < count; ++a) {
      const std::size_t i = static_cast<std::size_t>(idx[a]);
      const Vec3f g = grd[a];
      const float g2 = squared_norm(g), f = val[a];
      if (pending[i] && detail::finite(g) && std::isfinite(f)) {
        // Trust region of the linearisation: the error it made here, per unit of displacement,
        // sets how far the vertex may move on the next one (the composed gradient is not the exact
        // gradient of the composed value: see docs/tracking.md).
        const Vec3f d = nx[i] - eval_pts[i];
        const Vec3f ge = eval_grads[i];
        const float err = std::abs(f - values[i] - dot(ge, d)) / std::sqrt(squared_norm(ge));
        const float dl = std::sqrt(squared_norm(d));
        const float r = 0.5f * tol * dl;
        radius2[i] = err * err * lazy_r2_[i] > r * r ? r * r / (err * err) : lazy_r2_[i];
      }
      values[i] = f, fc[i] = fcv[a];
      pending[i] = 0;
      lazy[i] = 0;
      if (flags_.lost[i] || !std::isfinite(f) || !detail::finite(g) || !(g2 > min_g2)) {
        flags_.lost[i] = 1;
        nx[i] = cu[i];  // left in place
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
      const float r = iso_[i] - f;
      if (cg && seen && r * last_residual[i] < 0.f && std::abs(r) > 0.5f * std::abs(last_residual[i]))
        newton_scale[i] = std::max(newton_scale[i] * 0.5f, 1.f / 16.f);
      last_residual[i] = r;
      const Vec3f step = newton_step(i, g, g2, r);
      if (lazy_on && linear[i] && !contact[i] && !fc[i] && squared_norm(step) <= radius2[i]) {
        lazy[i] = 1;
        eval_pts[i] = nx[i];
        eval_grads[i] = g;
      }
      nx[i] += step;
      normal[i] = nrm;
      moves[i] = squared_norm(nx[i] - cu[i]);  // squared: one square root per iteration below
    }
    evaluations += static_cast<long>(count - b);
  };

  TrackStats stats;
  bool first = true;  // the first evaluation covers every vertex and does not mark it touched
  // Called when no vertex moved by more than the tolerance: true if the call has converged. With
  // lazy evaluation, the vertices moved on a linearised field since their last evaluation are
  // evaluated once more first (they become the active set of a `force`d iteration), unless the
  // last iteration was that one.
  auto settle = [&](bool verified) {
    if (verified || !lazy_on) return true;
    active.clear();
    for (std::size_t i = 0; i < n; ++i)
      if (pending[i]) active.push_back(static_cast<int>(i));
    return active.empty();
  };
  bool force = false;
  auto run = [&](bool jacobi, bool evaluate_all = false) {
    const bool dense = active.size() == n;
    // Active sets are often a few thousand vertices: smaller tasks keep both cores busy (the grain
    // changes no result).
    const std::size_t grain =
        options_.grain == 0 ? 0 : std::clamp<std::size_t>(active.size() / 16, 64, options_.grain);
    parallel_for(active.size(), grain,
                 [&](std::size_t b, std::size_t e) { kernel(jacobi, dense, evaluate_all, b, e); });
    float mx = 0.f;
    if (dense) {
      // Every vertex was written: rotate the buffers (Jacobi: x_{k+1} from x_k only).
      prev.swap(cur);  // prev <- x_k
      cur.swap(next);  // cur <- x_{k+1}; `next` is scratch
      for (std::size_t i = 0; i < n; ++i) {
        mx = std::max(mx, moves[i]);
        moved[i] = moves[i] > tol2 ? 1 : 0;
      }
      if (!first) std::fill(touched.begin(), touched.end(), std::uint8_t{1});
    } else {
      // Commit after every vertex has read its neighbours. For the inactive vertices prev = cur
      // already (up to their last move, below the tolerance).
      // (Serial: a copy per vertex costs less than waking the other threads.)
      for (int i : active) {
        prev[i] = cur[i];  // prev <- x_k
        cur[i] = next[i];  // cur <- x_{k+1}
        mx = std::max(mx, moves[i]);
        moved[i] = moves[i] > tol2 ? 1 : 0;
        if (!first) touched[i] = 1;
      }
    }
    first = false;
    set.update(active, moved);
    return std::sqrt(mx);
  };
  for (int k = 0; k < options_.initial_newton_steps && !active.empty(); ++k) {
    const float mx = run(false);
    if (mx <= tol) break;
  }
  if (options_.max_iterations > 0 && options_.initial_newton_steps == 0) {
    active = set.all();  // nothing evaluated yet: every vertex starts
  } else if (options_.max_iterations > 0) {
    // The relaxation starts on the vertices whose first tangential step is longer than the
    // tolerance, or that are still settling after the Newton steps: a vertex with a shorter step
    // would move by less than the tolerance and is left until a neighbour moves (no field
    // evaluation needed to find them).
    std::vector<std::uint8_t> start(n, 0);
    for (int i : active) start[i] = 1;
    parallel_for(n, options_.grain, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        if (start[i] || !relaxes(i) || normal[i] == Vec3f{}) continue;
        const float s = mask_[i] * damping[i];
        if (squared_norm(jacobi_delta(cur.data(), i, cur[i])) * s * s > tol2) start[i] = 1;
      }
    });
    active.clear();
    for (std::size_t i = 0; i < n; ++i)
      if (start[i]) active.push_back(static_cast<int>(i));
  }
  if (cg) {
    // Conjugate-gradient relaxation: per iteration, the tangential ARAP system of the active
    // vertices grown by cg_rings - 1 rings (their neighbours outside held in place) is solved by
    // CG, then every active vertex takes one Newton step (one field evaluation per vertex and
    // iteration). Iterations stop when no vertex moves by more than the tolerance.
    disp.assign(n, Vec3f{});
    std::vector<int> local(n, -1), unknowns;
    std::vector<float> scale(n, 1.f);
    std::vector<Vec3f> d;
    detail::TangentProblem tp;
    tp.adj = &adj_;
    tp.weights = w;
    tp.weight_sums = wsum;
    tp.targets = tg;
    tp.normals = nrms;
    tp.free3d = contact;
    tp.scale = scale.data();
    tp.tolerance = tol;
    tp.max_iterations = options_.cg_max_iterations;
    for (int k = 0; k < options_.max_iterations; ++k) {
      if (active.empty()) {
        if (settle(force)) {
          stats.converged = true;
          break;
        }
        force = true;
      }
      for (int r = 1; r < options_.cg_rings; ++r) set.dilate(active);
      unknowns.clear();
      for (int i : active)
        if (relaxes(i) && normal[i] != Vec3f{}) {
          unknowns.push_back(i);
          scale[i] = mask_[i] * damping[i];
        }
      tp.positions = cur.data();
      stats.solver_iterations += detail::solve_tangential_cg(tp, unknowns, local, d);
      for (std::size_t a = 0; a < unknowns.size(); ++a) disp[std::size_t(unknowns[a])] = d[a];
      stats.vertex_updates += static_cast<long>(active.size());
      stats.max_move = run(true, force);
      for (int i : unknowns) disp[std::size_t(i)] = Vec3f{};
      stats.iterations = k + 1;
      const bool verified = std::exchange(force, false);
      if (stats.max_move <= tol) {
        if (settle(verified)) {
          stats.converged = true;
          break;
        }
        force = true;
      }
    }
  }
  for (int k = 0; k < (cg ? 0 : options_.max_iterations); ++k) {
    if (active.empty()) {
      if (settle(force)) {
        stats.converged = true;
        break;
      }
      force = true;
    }
    // Chebyshev weights (Wang 2015, "A Chebyshev semi-iterative approach for accelerating
    // projective and position-based dynamics"): ω = 2 / (2 - ρ²) at the first accelerated
    // iteration, then ω ← 4 / (4 - ρ² ω); plain Jacobi (ω = 1) before, or when ρ = 0.
    if (rho2 > 0.f && k >= kChebyshevDelay)
      omega = k == kChebyshevDelay ? 2.f / (2.f - rho2) : 4.f / (4.f - rho2 * omega);
    stats.vertex_updates += static_cast<long>(active.size());
    stats.max_move = run(true, force);
    stats.iterations = k + 1;
    const bool verified = std::exchange(force, false);
    if (stats.max_move <= tol) {
      if (settle(verified)) {
        stats.converged = true;
        break;
      }
      force = true;
    }
  }
  if (options_.max_iterations == 0) stats.converged = true;
  if (!stats.converged && lazy_on && !settle(false)) {
    // Stopped by the iteration cap: the vertices last moved on a linearised field take one
    // evaluated Newton step (no tangential step), so that none ends on a linearisation.
    run(false, true);
  }
  stats.field_evaluations = evaluations;
  if (first) std::fill(touched.begin(), touched.end(), std::uint8_t{1});  // nothing evaluated yet
  // Contacts reported by the field at the last evaluation also get smoothed.
  for (std::size_t i = 0; i < n; ++i)
    if (fc[i] && !flags_.lost[i]) flags_.contact[i] = 1;
  // Folds: the vertices of a triangle that the relaxation left inverted (typically at a crease
  // where no consecutive gradients differed by the contact angle) are smoothed like contacts;
  // triangles already inverted at rest (mark_rest_inversions) are not folds.
  // Unless test_all_triangles, only the triangles that may be inverted are tested at their
  // centroid: those whose normal deviates by more than kFoldCandidateDeg from the outward
  // direction -∇f/|∇f| last evaluated at one of their vertices, with a contact or lost vertex, or
  // inverted at rest or at the end of the last call. Elsewhere the field would have to turn by
  // more than that angle inside the triangle, which it does only across contact creases.
  std::vector<int> candidates;
  if (!options_.test_all_triangles) {
    const float cos_candidate = std::cos(kFoldCandidateDeg * 3.14159265358979f / 180.f);
    for (Eigen::Index f = 0; f < triangles_.rows(); ++f) {
      const int v0 = triangles_(f, 0), v1 = triangles_(f, 1), v2 = triangles_(f, 2);
      const Vec3f c = cross(cur[v1] - cur[v0], cur[v2] - cur[v0]);
      const float len = std::sqrt(squared_norm(c));
      const std::size_t t = static_cast<std::size_t>(f);
      bool candidate = !(len > 0.f) || (!last_inverted_.empty() && last_inverted_[t]) ||
                       (!rest_inverted_.empty() && rest_inverted_[t]);
      for (int v : {v0, v1, v2}) {
        if (candidate) break;
        const Vec3f nv = normal[v];
        candidate =
            contact[v] || fc[v] || flags_.lost[v] || nv == Vec3f{} || -dot(c, nv) < cos_candidate * len;
      }
      if (candidate) candidates.push_back(static_cast<int>(f));
    }
  }
  std::vector<std::uint8_t> inverted = detail::inverted_triangles(
      field, cur, triangles_, options_.grain, options_.test_all_triangles ? nullptr : &candidates);
  if (options_.fold_contacts) {
    for (Eigen::Index f = 0; f < triangles_.rows(); ++f) {
      const std::size_t t = static_cast<std::size_t>(f);
      if (inverted[t] && (rest_inverted_.empty() || !rest_inverted_[t]))
        for (int k = 0; k < 3; ++k)
          if (!flags_.lost[triangles_(f, k)]) flags_.contact[triangles_(f, k)] = 1;
    }
  }
  stats.smoothed_vertices =
      detail::contact_smoothing(adj_, flags_.contact, options_.smoothing, options_.grain, cur, flags_.beta);
  if (options_.smoothing.smoothing_steps > 0)
    for (std::size_t i = 0; i < n; ++i)
      if (flags_.beta[i] > 0.f) touched[i] = 1;
  std::vector<std::uint8_t> fresh;  // triangles the fold repair tested at the final positions
  if (options_.fold_repair.rounds > 0 && options_.fold_repair.steps > 0) {
    detail::fold_repair(field, triangles_, adj_, vertex_faces_, rest_inverted_, flags_.lost, repair_mask_,
                        options_.fold_repair, options_.grain, cur, flags_.beta, touched, inverted, fresh);
    stats.smoothed_vertices = 0;
    for (std::size_t i = 0; i < n; ++i) stats.smoothed_vertices += flags_.beta[i] > 0.f ? 1 : 0;
  }
  detail::final_stats_touched(field, cur, triangles_, vertex_faces_, iso_, values, touched, options_.grain,
                              flags_, stats, inverted, &fresh);
  if (options_.orientation_repair.rounds > 0 && stats.inverted_triangles > 0) {
    const std::vector<int> oriented =
        detail::orientation_repair(field, triangles_, vertex_faces_, rest_inverted_, flags_.lost,
                                   repair_mask_, options_.orientation_repair, cur, inverted);
    stats.oriented_vertices = static_cast<int>(oriented.size());
    if (!oriented.empty()) {
      // Moved off their iso-values on purpose, like smoothed vertices: β = 1, out of the residual.
      for (int i : oriented) flags_.beta[static_cast<std::size_t>(i)] = 1.f;
      detail::refresh_values(field, cur, oriented, options_.grain, values, flags_);
      stats.smoothed_vertices = 0;
      for (std::size_t i = 0; i < n; ++i) stats.smoothed_vertices += flags_.beta[i] > 0.f ? 1 : 0;
      detail::vertex_stats(values, iso_, flags_, stats);
      stats.inverted_triangles = 0;
      for (std::uint8_t f : inverted) stats.inverted_triangles += f;
    }
  }
  last_inverted_ = inverted;
  for (std::size_t i = 0; i < n; ++i)
    if (!detail::finite(cur[i])) cur[i] = detail::row(positions, static_cast<Eigen::Index>(user(i)));
  if (!order_.empty()) {
    // Back to the caller's order: positions and flags.
    cur = permuted(cur, rank_);
    flags_.contact = permuted(flags_.contact, rank_);
    flags_.lost = permuted(flags_.lost, rank_);
    flags_.beta = permuted(flags_.beta, rank_);
  }
  detail::from_points(cur, positions);
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return stats;
}

}  // namespace isokit::track
