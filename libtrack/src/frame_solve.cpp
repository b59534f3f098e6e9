// SPDX-License-Identifier: MIT
// 2014 stages 2 and 3 as one convergent solve per call (TrackerOptions::relaxation = kGlobal;
// docs/tracking.md, "The global solve"): safeguarded Newton projections onto each vertex's
// iso-value alternated with the exact tangent-plane ARAP solve (global_solve.cpp).
#include <algorithm>
#include <cmath>
#include <limits>

#include "field_eval.h"
#include "global_solve.h"
#include "mesh_geometry.h"
#include "newton_step.h"
#include "points.h"

namespace isokit::track::detail {

namespace {

// A call stops as capped when its tangential residual has not fallen below kStagnationDecrease
// times its best value for kStagnationIterations iterations.
constexpr int kStagnationIterations = 8;
constexpr float kStagnationDecrease = 0.9f;
// Newton steps after each tangential solve (each one evaluation of the vertices still off).
constexpr int kNewtonStepsPerIteration = 4;
// A vertex takes Newton steps while its iso residual exceeds this fraction of the iso tolerance,
// or its distance to the iso-surface (|r| / |∇f|) this fraction of the tangential tolerance: an
// offset along the normal changes the ARAP residual, so the tangential test needs the projection
// to that precision.
constexpr float kNewtonTarget = 0.1f;
// Finite-difference step of the curvature estimate (mean rest edges).
constexpr float kCurvatureStep = 0.25f;
// Line search: step halvings per iteration, and the relative energy rise still accepted (round-off).
constexpr int kMaxBacktracks = 5;
constexpr double kEnergySlack = 1e-7;

// Per-call scratch of the solve.
struct FrameScratch {
  explicit FrameScratch(std::size_t n)
      : grad(n),
        stale(n, 0),
        held(n, 0),
        stopped(n, 0),
        curvature(n, Sym3{}),
        d(n),
        normals(n),
        a(n),
        b(n),
        ra(n),
        rb(n),
        bracketed(n, 0),
        side(n, 0) {}
  std::vector<Vec3f> grad;            // ∇f at the last evaluation
  std::vector<std::uint8_t> stale;    // moved since its last evaluation
  std::vector<std::uint8_t> held;     // no tangential move for the rest of the call
  std::vector<std::uint8_t> stopped;  // no move at all for the rest of the call (unsettled projection)
  std::vector<Sym3> curvature;        // μi ∇²f at each vertex (the Lagrangian's curvature term)
  std::vector<Vec3f> d, normals;      // the tangential solve's moves and plane normals
  std::vector<int> list;
  // Projection: the bracket [a, b] of a vertex whose residual changed sign (residuals ra, rb),
  // and which endpoint the last regula falsi step replaced (1: a, 2: b).
  std::vector<Vec3f> a, b;
  std::vector<float> ra, rb;
  std::vector<std::uint8_t> bracketed, side;
};

// Vertex i was evaluated at s.cur[i]: value f, gradient g, the field's contact flag fc. A vertex
// without a usable gradient is lost for the rest of the call; a gradient turned by more than the
// contact angle flags a contact (2013 §5).
void take_evaluation(TrackState& s, FrameScratch& f, std::size_t i, float val, const Vec3f& g,
                     std::uint8_t fc) {
  const TrackerOptions& o = s.m.options;
  s.values[i] = val;
  s.field_contact[i] = fc;
  f.stale[i] = 0;
  const float g2 = squared_norm(g);
  if (!std::isfinite(val) || !finite(g) || !(g2 > s.min_g2)) {
    s.flags.lost[i] = 1;
    s.normal[i] = Vec3f{};
    f.grad[i] = Vec3f{};
    return;
  }
  const Vec3f nrm = g / std::sqrt(g2);
  const bool seen = s.normal[i] != Vec3f{};
  // No step damping here (the Jacobi path's min_contact_damping): the projection brackets a
  // kink instead (newton_phase), and damped steps left vertices off their iso-value.
  if (seen && dot(nrm, s.normal[i]) < s.cos_contact && !s.flags.free[i] && o.angle_contacts)
    s.flags.contact[i] = 1;
  s.normal[i] = nrm;
  f.grad[i] = g;
}

// Evaluates the field at the listed vertices (one batched, parallel call).
void evaluate(TrackState& s, FrameScratch& f, const std::vector<int>& list) {
  const std::size_t m = list.size();
  for (std::size_t a = 0; a < m; ++a) s.batch_points[a] = s.cur[std::size_t(list[a])];
  eval_field(s.field, s.batch_points.data(), m, s.batch_values.data(), s.batch_gradients.data(),
             s.batch_contact.data(), s.m.options.grain);
  for (std::size_t a = 0; a < m; ++a)
    take_evaluation(s, f, std::size_t(list[a]), s.batch_values[a], s.batch_gradients[a], s.batch_contact[a]);
  s.evaluations += static_cast<long>(m);
}

bool held_to_iso(const TrackState& s, std::size_t i) {
  return !s.flags.lost[i] && !s.flags.free[i] && !s.pinned(i);
}

// A vertex that takes projection steps (not lost, not free, not stopped).
bool projected(const TrackState& s, const FrameScratch& f, std::size_t i) {
  return held_to_iso(s, i) && !f.stopped[i];
}

// Whether vertex i still needs projection steps: its residual above the iso target or its
// distance to the iso-surface above the distance target.
bool off_iso(const TrackState& s, const FrameScratch& f, std::size_t i) {
  const float r = std::abs(s.m.iso[i] - s.values[i]);
  return r > kNewtonTarget * s.m.options.iso_tolerance ||
         r * r > kNewtonTarget * kNewtonTarget * s.tol2 * squared_norm(f.grad[i]);
}

// Up to `steps` projection steps of the vertices off their iso-value, each followed by an
// evaluation of the vertices it moved. A step is the Newton step `p <- p + σ (iso - f) ∇f / |∇f|²`
// (at most max_step long; no contact damping) until the residual changes sign; from
// then on the root is bracketed on the segment between the last two points and the steps are
// regula falsi (Illinois variant) on it, which converges on a kink of the field where Newton
// steps would 2-cycle (docs/tracking.md, "Known limits").
void newton_phase(TrackState& s, FrameScratch& f, int steps, bool stop_unsettled) {
  for (int k = 0;; ++k) {
    f.list.clear();
    for (std::size_t i = 0; i < s.n; ++i)
      if (projected(s, f, i) && off_iso(s, f, i)) f.list.push_back(static_cast<int>(i));
    if (f.list.empty()) return;
    if (k == steps) {
      // A contact vertex still off after every step sits where the field's gradient does not
      // lead to its iso-value (the contact valley: the gradient runs along the contact surface);
      // it is stopped where it is for the rest of the call, as 2013 §5 stops a vertex at a
      // gradient discontinuity (the contact smoothing takes it). Other vertices go on in the
      // next iteration.
      if (stop_unsettled)
        for (int v : f.list)
          if (f.held[std::size_t(v)]) f.stopped[std::size_t(v)] = 1;
      return;
    }
    for (int v : f.list) {
      const std::size_t i = std::size_t(v);
      const float r = s.m.iso[i] - s.values[i];
      if (f.bracketed[i]) {
        const float t = f.ra[i] / (f.ra[i] - f.rb[i]);
        s.cur[i] = f.a[i] + (f.b[i] - f.a[i]) * std::clamp(t, 0.f, 1.f);
      } else {
        f.a[i] = s.cur[i], f.ra[i] = r;  // the point before the step
        s.cur[i] += newton_step(s, i, f.grad[i], squared_norm(f.grad[i]), r);
      }
    }
    evaluate(s, f, f.list);
    for (int v : f.list) {
      const std::size_t i = std::size_t(v);
      if (s.flags.lost[i]) continue;
      const float r = s.m.iso[i] - s.values[i];
      if (!f.bracketed[i]) {
        if (r * f.ra[i] < 0.f) f.bracketed[i] = 1, f.b[i] = s.cur[i], f.rb[i] = r, f.side[i] = 0;
        continue;
      }
      // Replace the endpoint of the new point's sign; Illinois: the same side twice halves the
      // other endpoint's residual, so that it moves too.
      const int side = r * f.ra[i] > 0.f ? 1 : 2;
      if (side == 1) {
        f.a[i] = s.cur[i], f.ra[i] = r;
        if (f.side[i] == 1) f.rb[i] *= 0.5f;
      } else {
        f.b[i] = s.cur[i], f.rb[i] = r;
        if (f.side[i] == 2) f.ra[i] *= 0.5f;
      }
      f.side[i] = std::uint8_t(side);
    }
  }
}

// The plane each vertex moves in: the tangent plane of the field's last gradient. A contact vertex
// (flagged by the field or by the angle rule), where the gradient is discontinuous and no tangent
// plane exists, is held for the rest of the call: only its Newton steps move it, onto the contact
// surface (2013 §5 stops it there); a lost vertex is held too. Being held is sticky within the
// call, so the problem changes only when the held set grows (the field's contact flag may come
// and go as a vertex moves along the contact surface).
void plane_normals(const TrackState& s, FrameScratch& f) {
  for (std::size_t i = 0; i < s.n; ++i) {
    if (s.flags.lost[i] || s.flags.contact[i] || s.field_contact[i]) f.held[i] = 1;
    f.normals[i] = f.held[i] ? Vec3f{} : s.normal[i];
  }
}

// The largest iso residual of the vertices held to their iso-value and not in contact (now or
// earlier in the call).
float iso_residual(const TrackState& s, const FrameScratch& f) {
  float mx = 0.f;
  for (std::size_t i = 0; i < s.n; ++i)
    if (held_to_iso(s, i) && !s.flags.contact[i] && !s.field_contact[i] && !f.held[i])
      mx = std::max(mx, std::abs(s.m.iso[i] - s.values[i]));
  return mx;
}

// Applies `step` times the tangential moves, each at most one mean rest edge long, and evaluates
// the vertices that moved. Returns the largest move before the clamp.
float apply_moves(TrackState& s, FrameScratch& f, float step) {
  float mx2 = 0.f;
  f.list.clear();
  for (std::size_t i = 0; i < s.n; ++i) {
    Vec3f d = f.d[i] * step;
    const float len2 = squared_norm(d);
    if (!(len2 > 0.f)) continue;
    mx2 = std::max(mx2, len2);
    const float edge = s.m.max_step[i] / s.m.options.max_step;
    if (len2 > edge * edge) d = d * (edge / std::sqrt(len2));
    s.cur[i] += d;
    f.stale[i] = 1;
    f.bracketed[i] = 0;  // a bracket holds on the segment it was found on
    f.list.push_back(static_cast<int>(i));
  }
  evaluate(s, f, f.list);
  return std::sqrt(mx2);
}

// The curvature term of the Lagrangian's Hessian, `μi ∇²f(pi)` with the multiplier μi = gi·∇f /
// |∇f|² (gi the ARAP residual, which the constraint balances at a solution): without it the
// tangential solve ignores that the iso-surface curves away under the ARAP pull and over- or
// undershoots by the ratio of the normal pull to the tangential stiffness (a contact fold: the
// oscillations of docs/tracking.md). ∇²f is the finite difference of the field's gradient over a
// quarter edge along two tangent directions (two evaluations per vertex), symmetrised.
void curvature_terms(TrackState& s, FrameScratch& f) {
  const std::size_t n = s.n;
  std::vector<int> list;
  std::vector<Vec3f> u(n), v(n);
  std::vector<float> h(n);
  for (std::size_t i = 0; i < n; ++i) {
    f.curvature[i] = Sym3{};
    if (f.held[i] || !held_to_iso(s, i) || s.normal[i] == Vec3f{} || s.m.adj.degree(int(i)) == 0) continue;
    const Vec3f nrm = s.normal[i];
    u[i] = perpendicular(nrm);
    v[i] = cross(nrm, u[i]);
    h[i] = kCurvatureStep * s.m.max_step[i] / s.m.options.max_step;
    list.push_back(static_cast<int>(i));
  }
  const std::size_t m = list.size();
  if (m == 0) return;
  std::vector<Vec3f> pts(2 * m), grads(2 * m);
  std::vector<float> vals(2 * m);
  std::vector<std::uint8_t> fc(2 * m);
  for (std::size_t a = 0; a < m; ++a) {
    const std::size_t i = std::size_t(list[a]);
    pts[2 * a] = s.cur[i] + u[i] * h[i];
    pts[2 * a + 1] = s.cur[i] + v[i] * h[i];
  }
  eval_field(s.field, pts.data(), 2 * m, vals.data(), grads.data(), fc.data(), s.m.options.grain);
  s.evaluations += static_cast<long>(2 * m);
  const Adjacency& adj = s.m.adj;
  for (std::size_t a = 0; a < m; ++a) {
    const std::size_t i = std::size_t(list[a]);
    const Vec3f g0 = f.grad[i];
    const Vec3f gu = grads[2 * a], gv = grads[2 * a + 1];
    if (!finite(gu) || !finite(gv) || fc[2 * a] || fc[2 * a + 1]) continue;
    Vec3f r{};
    for (int k = adj.offsets[i]; k < adj.offsets[i + 1]; ++k)
      r += ((s.cur[std::size_t(adj.neighbors[k])] - s.cur[i]) + s.targets[std::size_t(k)]) * s.m.weights[k];
    const float mu = dot(r, g0) / squared_norm(g0);
    // Tangential Hessian in the (u, v) basis, symmetrised, then as a 3 × 3 tensor U H Uᵀ.
    const float huu = dot(gu - g0, u[i]) / h[i], hvv = dot(gv - g0, v[i]) / h[i];
    const float huv = 0.5f * (dot(gu - g0, v[i]) + dot(gv - g0, u[i])) / h[i];
    const Vec3f a0 = u[i], b0 = v[i];
    auto entry = [&](float x0, float y0, float x1, float y1) {
      return mu * (huu * x0 * x1 + hvv * y0 * y1 + huv * (x0 * y1 + y0 * x1));
    };
    f.curvature[i] = {entry(a0.x, b0.x, a0.x, b0.x), entry(a0.y, b0.y, a0.y, b0.y),
                      entry(a0.z, b0.z, a0.z, b0.z), entry(a0.x, b0.x, a0.y, b0.y),
                      entry(a0.x, b0.x, a0.z, b0.z), entry(a0.y, b0.y, a0.z, b0.z)};
  }
}

// The ARAP energy of 2014 eq. 3, Σi Σj wij |(pj - pi) + tij|², at the current positions.
double arap_energy(const TrackState& s) {
  const Adjacency& adj = s.m.adj;
  double e = 0;
  for (std::size_t i = 0; i < s.n; ++i)
    for (int k = adj.offsets[i]; k < adj.offsets[i + 1]; ++k) {
      const Vec3f r = (s.cur[std::size_t(adj.neighbors[k])] - s.cur[i]) + s.targets[std::size_t(k)];
      e += double(s.m.weights[std::size_t(k)]) * double(squared_norm(r));
    }
  return e;
}

// What an evaluation changes, saved so that a rejected line-search step can be undone.
struct Snapshot {
  std::vector<Vec3f> cur, normal, grad, a, b;
  std::vector<float> values, ra, rb;
  std::vector<std::uint8_t> field_contact, stale, bracketed, side;
  void save(const TrackState& s, const FrameScratch& f) {
    cur = s.cur, normal = s.normal, grad = f.grad, values = s.values;
    field_contact = s.field_contact, stale = f.stale;
    a = f.a, b = f.b, ra = f.ra, rb = f.rb, bracketed = f.bracketed, side = f.side;
  }
  void restore(TrackState& s, FrameScratch& f) const {
    s.cur = cur, s.normal = normal, f.grad = grad, s.values = values;
    s.field_contact = field_contact, f.stale = stale;
    f.a = a, f.b = b, f.ra = ra, f.rb = rb, f.bracketed = bracketed, f.side = side;
  }
};

// One step along the tangential solve's moves, then the Newton projection; backtracking: while
// the ARAP energy of the projected positions rose, the step is undone and halved (at most
// kMaxBacktracks times; the last one is kept). The moves are a descent direction of the energy
// on the iso-surfaces (the system is positive definite), so a short enough step lowers it: the
// iterations cannot cycle.
void line_search(TrackState& s, FrameScratch& f, Snapshot& snap) {
  const double e0 = arap_energy(s);
  snap.save(s, f);
  float step = 1.f;
  for (int t = 0;; ++t) {
    apply_moves(s, f, step);
    if (t == 0) s.stats.vertex_updates += static_cast<long>(f.list.size());
    newton_phase(s, f, kNewtonStepsPerIteration, true);
    if (t == kMaxBacktracks || arap_energy(s) <= e0 * (1.0 + kEnergySlack)) return;
    snap.restore(s, f);
    step *= 0.5f;
    ++s.stats.backtracks;
  }
}

// The largest distance between corresponding points.
float largest_distance(const std::vector<Vec3f>& a, const std::vector<Vec3f>& b) {
  float mx2 = 0.f;
  for (std::size_t i = 0; i < a.size(); ++i) mx2 = std::max(mx2, squared_norm(b[i] - a[i]));
  return std::sqrt(mx2);
}

// Largest tangential move of the last solve.
float largest_move(const FrameScratch& f) {
  float mx2 = 0.f;
  for (const Vec3f& d : f.d) mx2 = std::max(mx2, squared_norm(d));
  return std::sqrt(mx2);
}

}  // namespace

void solve_frame(TrackState& s, TangentSolver& solver) {
  const TrackerOptions& o = s.m.options;
  FrameScratch f(s.n);
  std::vector<int> all(s.n);
  for (std::size_t i = 0; i < s.n; ++i) all[i] = static_cast<int>(i);
  evaluate(s, f, all);
  newton_phase(s, f, o.initial_newton_steps, false);
  float best = std::numeric_limits<float>::infinity();
  float net = std::numeric_limits<float>::infinity();  // the last iteration's largest move
  int since_best = 0;
  Snapshot snap;
  std::vector<Vec3f> before;
  for (int k = 0; k < o.max_iterations; ++k) {
    if (interrupted(s)) break;
    plane_normals(s, f);
    curvature_terms(s, f);
    solver.solve(s, f.normals, f.curvature, f.d);
    const float dmax = largest_move(f);
    const float rmax = iso_residual(s, f);
    s.stats.iterations = k + 1;
    s.stats.tangential_residual = std::min(dmax, net);
    if (s.stats.tangential_residual <= s.tol && rmax <= o.iso_tolerance) {
      s.stats.converged = true;
      break;
    }
    if (s.stats.tangential_residual < kStagnationDecrease * best) {
      best = s.stats.tangential_residual;
      since_best = 0;
    } else if (++since_best >= kStagnationIterations) {
      break;
    }
    before = s.cur;
    line_search(s, f, snap);
    net = largest_distance(before, s.cur);
    s.stats.max_move = net;
  }
  if (o.max_iterations == 0) s.stats.converged = iso_residual(s, f) <= o.iso_tolerance;
  for (std::size_t i = 0; i < s.n; ++i) s.touched[i] = f.stale[i];
  s.first = false;
  s.stats.field_evaluations = s.evaluations;
}

}  // namespace isokit::track::detail
