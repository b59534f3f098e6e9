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
// Fold test: a triangle is tested at its centroid when its normal deviates from the outward
// direction at one of its vertices by more than this (an inverted one deviates by more than 90°).
constexpr float kFoldCandidateDeg = 45.f;

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
  mask_ = std::move(mask);
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
  void update(std::vector<int>& active, std::vector<std::uint8_t>& moved, std::size_t grain) {
    const std::size_t n = dense_.size();
    std::size_t count = 0;
    for (int i : active) count += moved[i];
    if (count == n) {  // everything still moves: keep every vertex
      std::fill(moved.begin(), moved.end(), std::uint8_t{0});
      return;
    }
    if (count * 4 > n) {
      // Dense pass (pull): a vertex is active if it or a neighbour moved; `moved` is 0 outside
      // the previous set.
      parallel_for(n, grain, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
          std::uint8_t m = moved[i];
          for (int k = adj_.offsets[i]; k < adj_.offsets[i + 1] && !m; ++k) m = moved[adj_.neighbors[k]];
          mark_[i] = m;
        }
      });
      active.clear();
      for (std::size_t i = 0; i < n; ++i)
        if (mark_[i]) active.push_back(static_cast<int>(i));
      std::fill(mark_.begin(), mark_.end(), std::uint8_t{0});
      std::fill(moved.begin(), moved.end(), std::uint8_t{0});
      return;
    }
    std::vector<int> seeds;
    seeds.reserve(count);
    for (int i : active)
      if (moved[i]) seeds.push_back(i), moved[i] = 0;
    dilate(seeds);
    active.swap(seeds);
  }

  /// Adds the one-ring neighbours of every vertex of `active` (sorted ascending on return).
  void dilate(std::vector<int>& active) {
    std::vector<int> next;
    next.reserve(active.size() * 8);
    auto add = [&](int v) {
      if (!mark_[v]) mark_[v] = 1, next.push_back(v);
    };
    for (int i : active) {
      add(i);
      for (int k = adj_.offsets[i]; k < adj_.offsets[i + 1]; ++k) add(adj_.neighbors[k]);
    }
    for (int v : next) mark_[v] = 0;
    std::sort(next.begin(), next.end());
    active.swap(next);
  }

 private:
  const Adjacency& adj_;
  std::vector<std::uint8_t> mark_;
  std::vector<int> dense_;
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
      require(std::isfinite(v), "rotation " + std::to_string(i), "is not finite", "pass finite rotations");
  std::vector<Vec3f> cur = detail::to_points(positions, "initial positions");
  // Three position buffers: x_{k-1} (`prev`, for the Chebyshev step), x_k (`cur`), x_{k+1}.
  // Only the active vertices are written; for the others next = cur = prev.
  std::vector<Vec3f> prev = cur, next = cur, grads(n), normal(n, Vec3f{});
  std::vector<float> values(n), moves(n, 0.f), damping(n, 1.f);  // moves: squared lengths
  const bool cg = options_.relaxation == Relaxation::kConjugateGradient;
  // CG relaxation: a vertex whose Newton steps overshoot (the residual changes sign without
  // halving: a 2-cycle across a kink of the field) has its Newton steps halved for the rest of the
  // call, down to 1/16; the Jacobi relaxation keeps the paper's plain Newton steps.
  std::vector<float> last_residual(n, 0.f), newton_scale(n, 1.f);
  std::vector<std::uint8_t> fc(n, 0), moved(n, 0), touched(n, 0);
  // Compact per-iteration buffers of the active vertices (field input and output).
  // Allocated at the first sparse iteration (a dense call never touches them).
  std::vector<Vec3f> apts, agrads;
  std::vector<float> avals;
  std::vector<std::uint8_t> afc;
  flags_.contact.assign(n, 0);
  flags_.lost.assign(n, 0);
  const std::vector<Vec3f>& rest = rest_pts_;
  const bool has_rot = !rotations.empty();
  const float cos_contact = std::cos(options_.contact_angle_deg * 3.14159265358979f / 180.f);
  const float min_g2 = options_.min_gradient * options_.min_gradient;
  const float tol = options_.tolerance * diagonal_;
  const float tol2 = tol * tol;
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
        targets[k] = has_rot ? (rotations[i] * e_ij + rotations[j] * e_ij) * 0.5f : e_ij;
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
  // in place on `next`.
  // With every vertex active (`dense`) the field reads and writes the per-vertex arrays directly;
  // otherwise the active vertices are gathered into the compact buffers.
  // `disp` (CG relaxation): per-vertex displacement applied instead of the Jacobi step.
  std::vector<Vec3f> disp;
  auto kernel = [&](bool jacobi, bool dense, std::size_t b, std::size_t e) {
    const Vec3f* cu = cur.data();
    const Vec3f* pv = prev.data();
    Vec3f* nx = next.data();
    const int* act = active.data();
    Vec3f* in = dense ? nx : apts.data();
    float* val = dense ? values.data() : avals.data();
    Vec3f* grd = dense ? grads.data() : agrads.data();
    std::uint8_t* fcv = dense ? fc.data() : afc.data();
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
      in[a] = q;
    }
    detail::eval_field(field, in + b, e - b, val + b, grd + b, fcv + b, 0);
    for (std::size_t a = b; a < e; ++a) {
      const std::size_t i = dense ? a : static_cast<std::size_t>(act[a]);
      const Vec3f g = grd[a];
      const float g2 = squared_norm(g), f = val[a];
      if (!dense) values[i] = f, fc[i] = fcv[a];
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
      {
        const float r = iso_[i] - f;
        if (cg && seen && r * last_residual[i] < 0.f && std::abs(r) > 0.5f * std::abs(last_residual[i]))
          newton_scale[i] = std::max(newton_scale[i] * 0.5f, 1.f / 16.f);
        last_residual[i] = r;
        Vec3f step = g * (options_.sigma * damping[i] * newton_scale[i] * r / g2);
        const float len2 = squared_norm(step);
        if (len2 > max_step_[i] * max_step_[i]) step = step * (max_step_[i] / std::sqrt(len2));
        nx[i] += step;
      }
      normal[i] = nrm;
      moves[i] = squared_norm(nx[i] - cu[i]);  // squared: one square root per iteration below
    }
  };

  TrackStats stats;
  bool first = true;  // the first evaluation covers every vertex and does not mark it touched
  auto run = [&](bool jacobi) {
    const bool dense = active.size() == n;
    if (!dense && apts.empty()) {
      apts.resize(n);
      agrads.resize(n);
      avals.resize(n);
      afc.resize(n);
    }
    // Active sets are often a few thousand vertices: smaller tasks keep both cores busy (the grain
    // changes no result).
    const std::size_t grain =
        options_.grain == 0 ? 0 : std::clamp<std::size_t>(active.size() / 16, 64, options_.grain);
    parallel_for(active.size(), grain, [&](std::size_t b, std::size_t e) { kernel(jacobi, dense, b, e); });
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
      parallel_for(active.size(), grain, [&](std::size_t b, std::size_t e) {
        for (std::size_t a = b; a < e; ++a) {
          const int i = active[a];
          prev[i] = cur[i];  // prev <- x_k
          cur[i] = next[i];  // cur <- x_{k+1}
        }
      });
      for (int i : active) {
        mx = std::max(mx, moves[i]);
        moved[i] = moves[i] > tol2 ? 1 : 0;
        if (!first) touched[i] = 1;
      }
    }
    first = false;
    set.update(active, moved, options_.grain);
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
      for (int r = 1; r < options_.cg_rings && !active.empty(); ++r) set.dilate(active);
      if (active.empty()) {
        stats.converged = true;
        break;
      }
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
      stats.max_move = run(true);
      for (int i : unknowns) disp[std::size_t(i)] = Vec3f{};
      stats.iterations = k + 1;
      if (stats.max_move <= tol) {
        stats.converged = true;
        break;
      }
    }
  }
  for (int k = 0; k < (cg ? 0 : options_.max_iterations); ++k) {
    if (active.empty()) {
      stats.converged = true;
      break;
    }
    // Chebyshev weights (Wang 2015, "A Chebyshev semi-iterative approach for accelerating
    // projective and position-based dynamics"): ω = 2 / (2 - ρ²) at the first accelerated
    // iteration, then ω ← 4 / (4 - ρ² ω); plain Jacobi (ω = 1) before, or when ρ = 0.
    if (rho2 > 0.f && k >= kChebyshevDelay)
      omega = k == kChebyshevDelay ? 2.f / (2.f - rho2) : 4.f / (4.f - rho2 * omega);
    stats.vertex_updates += static_cast<long>(active.size());
    stats.max_move = run(true);
    stats.iterations = k + 1;
    if (stats.max_move <= tol) {
      stats.converged = true;
      break;
    }
  }
  if (options_.max_iterations == 0) stats.converged = true;
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
  detail::final_stats_touched(field, cur, triangles_, vertex_faces_, iso_, values, touched, options_.grain,
                              flags_, stats, inverted);
  last_inverted_ = inverted;
  for (std::size_t i = 0; i < n; ++i)
    if (!detail::finite(cur[i])) cur[i] = detail::row(positions, static_cast<Eigen::Index>(i));
  detail::from_points(cur, positions);
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return stats;
}

}  // namespace isokit::track
