// SPDX-License-Identifier: MIT
// The energy tracker's target search (energy_tracker.h, local step): per vertex a 1-D search for
// f = iso along the inward direction d = ∇f/|∇f| at xi — a clamped Newton trial, then regula falsi
// (Illinois) inside a sign-change bracket or Newton again outside one — and the contact test (the
// gradient turning by more than contact_angle_deg from ∇f(xi)), whose crease is bisected. Every
// sub-step evaluates the field once over all vertices still searching (eval_field: parallel
// chunks), so the result does not depend on the grain.
#include <algorithm>
#include <cmath>
#include <limits>

#include "energy_model.h"
#include "field_eval.h"
#include "isokit/core/parallel.h"
#include "mesh_geometry.h"
#include "points.h"

namespace isokit::track::detail {

namespace {

enum class Phase : std::uint8_t { kDone, kNewton, kBracket, kCrease };

// Crease bisections of a contact (EnergyTrackerOptions::search_steps does not count them).
constexpr int kCreaseBisections = 3;

/// One vertex's search: samples at xi + t d, t in [−reach, reach].
struct LineSearch {
  Vec3f origin, dir;
  float reach{0};
  float t_prev{0}, r_prev{0};                // last sample before any turn: t, f − iso
  float t_lo{0}, r_lo{0}, t_hi{0}, r_hi{0};  // sign-change bracket (ends unordered)
  int kept{0};                               // Illinois: end replaced last (−1 lo, +1 hi)
  float best_t{0}, best_r{0};                // sample of smallest |f − iso|
  float turn_lo{0}, turn_hi{0};              // crease bracket: before / after the gradient turn
  Vec3f g_prev, g_lo, g_hi;                  // unit gradients at the last sample and the bracket's ends
  float t_next{0};
  Phase phase{Phase::kDone};
};

struct SearchContext {
  const EnergyCall& c;
  float cos_turn, stop_res, min_gradient;
  bool angles;
};

bool finite3(const Vec3f& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Starts vertex i's search from the field at xi; returns false when the vertex needs none.
bool start_search(const SearchContext& s, std::size_t i, LineSearch& ls, TargetSet& out, std::uint8_t& lost) {
  const EnergyCall& c = s.c;
  const Vec3f g = c.grad[i];
  const float f = c.value[i], gn = norm(g);
  const Vec3d& x = c.x[i];
  out.point[i] = x;
  out.normal[i] = {};
  lost = !(std::isfinite(f) && finite3(g) && std::isfinite(gn) && gn > s.min_gradient);
  if (lost) {
    out.res[i] = std::numeric_limits<float>::infinity();
    out.kind[i] = TargetKind::kLost;
    return false;
  }
  out.normal[i] = {g.x / gn, g.y / gn, g.z / gn};
  if (c.field_contact[i]) {  // the field marks a contact: the vertex stops where it is
    out.res[i] = 0.f;
    out.kind[i] = TargetKind::kContact;
    return false;
  }
  const float r = f - c.m.iso[i];
  out.res[i] = std::abs(r);
  out.kind[i] = TargetKind::kIso;
  if (std::abs(r) <= s.stop_res) return false;
  ls.origin = {float(x.x), float(x.y), float(x.z)};
  ls.dir = g / gn;
  ls.g_prev = ls.dir;
  ls.reach = c.m.options.max_search * c.m.edge[i];
  ls.r_prev = ls.best_r = r;
  ls.t_next = std::clamp(-r / gn, -ls.reach, ls.reach);
  ls.phase = ls.t_next != 0.f ? Phase::kNewton : Phase::kDone;
  return ls.phase != Phase::kDone;
}

// The next sample inside the bracket (Illinois regula falsi; bisection if it falls outside).
void next_in_bracket(LineSearch& ls) {
  const float lo = std::min(ls.t_lo, ls.t_hi), hi = std::max(ls.t_lo, ls.t_hi);
  if (!(hi - lo > 1e-7f * ls.reach)) {
    ls.phase = Phase::kDone;
    return;
  }
  float t = (ls.t_lo * ls.r_hi - ls.t_hi * ls.r_lo) / (ls.r_hi - ls.r_lo);
  if (!(t > lo && t < hi)) t = 0.5f * (lo + hi);
  ls.t_next = t;
}

// Takes the sample (t, f, g) of a vertex in phase kNewton or kBracket.
void take_sample(const SearchContext& s, float iso, LineSearch& ls, float f, const Vec3f& g) {
  const float t = ls.t_next;
  if (!std::isfinite(f) || !finite3(g)) {
    ls.phase = Phase::kDone;
    return;
  }
  const float gn = norm(g);
  if (s.angles && gn > s.min_gradient && dot(g, ls.dir) < s.cos_turn * gn) {
    ls.turn_lo = ls.t_prev, ls.turn_hi = t;
    ls.g_lo = ls.g_prev, ls.g_hi = g / gn;
    ls.phase = Phase::kCrease;
    return;
  }
  if (gn > s.min_gradient) ls.g_prev = g / gn;
  const float r = f - iso;
  if (std::abs(r) < std::abs(ls.best_r)) ls.best_t = t, ls.best_r = r;
  if (std::abs(r) <= s.stop_res) {
    ls.phase = Phase::kDone;
    return;
  }
  const bool side = r > 0;
  if (ls.phase == Phase::kBracket) {
    if (side == (ls.r_lo > 0)) {
      ls.t_lo = t, ls.r_lo = r;
      if (ls.kept == -1) ls.r_hi *= 0.5f;
      ls.kept = -1;
    } else {
      ls.t_hi = t, ls.r_hi = r;
      if (ls.kept == 1) ls.r_lo *= 0.5f;
      ls.kept = 1;
    }
  } else if (side != (ls.r_prev > 0)) {
    ls.t_lo = ls.t_prev, ls.r_lo = ls.r_prev, ls.t_hi = t, ls.r_hi = r;
    ls.phase = Phase::kBracket;
  }
  ls.t_prev = t, ls.r_prev = r;
  if (ls.phase == Phase::kBracket) return next_in_bracket(ls);
  const float slope = dot(g, ls.dir);  // Newton along d from the trial, clamped to the reach
  const float tn = slope > s.min_gradient ? std::clamp(t - r / slope, -ls.reach, ls.reach) : t;
  if (tn == t || !std::isfinite(tn)) ls.phase = Phase::kDone;
  ls.t_next = tn;
}

// One batched sub-step: every vertex in `phase` (kCrease: at its crease bracket's midpoint)
// takes one sample; returns the number of samples.
long sub_step(const SearchContext& s, std::vector<LineSearch>& ls, bool crease) {
  std::vector<std::size_t> list;
  for (std::size_t i = 0; i < ls.size(); ++i)
    if (crease ? ls[i].phase == Phase::kCrease
               : (ls[i].phase == Phase::kNewton || ls[i].phase == Phase::kBracket))
      list.push_back(i);
  const std::size_t n = list.size();
  std::vector<Vec3f> pts(n), grads(n);
  std::vector<float> values(n);
  std::vector<std::uint8_t> contact(n);
  for (std::size_t a = 0; a < n; ++a) {
    LineSearch& l = ls[list[a]];
    if (crease) l.t_next = 0.5f * (l.turn_lo + l.turn_hi);
    pts[a] = l.origin + l.dir * l.t_next;
  }
  const std::size_t grain = s.c.m.options.grain;
  eval_field(s.c.field, pts.data(), n, values.data(), grads.data(), contact.data(), grain);
  parallel_for(n, grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      LineSearch& l = ls[list[a]];
      if (!crease) {
        take_sample(s, s.c.m.iso[list[a]], l, values[a], grads[a]);
        continue;
      }
      const Vec3f g = grads[a];
      const float gn = norm(g);
      const bool turned = finite3(g) && gn > s.min_gradient && dot(g, l.dir) < s.cos_turn * gn;
      (turned ? l.turn_hi : l.turn_lo) = l.t_next;
      if (gn > s.min_gradient && finite3(g)) (turned ? l.g_hi : l.g_lo) = g / gn;
    }
  });
  return long(n);
}

// The normal of the contact surface at a crease: where f = max(f1, f2) turns from ∇f1 to ∇f2 the
// surface f1 = f2 has the normal ∇f1 − ∇f2, taken here from the unit gradients at the ends of the
// crease bracket (the search direction when they coincide).
Vec3d crease_normal(const LineSearch& l, const Vec3d& d) {
  const Vec3f n = l.g_lo - l.g_hi;
  const float len = norm(n);
  if (!(len > 1e-3f)) return d;
  return {n.x / len, n.y / len, n.z / len};
}

// The candidates from the finished searches: a contact's crease on the vertex's own side (where
// ∇f points along its inward normal), otherwise the sample of smallest |f − iso|.
void finish(const EnergyCall& c, const std::vector<LineSearch>& ls, TargetSet& out) {
  bool any_crease = false;
  for (const LineSearch& l : ls) any_crease = any_crease || l.phase == Phase::kCrease;
  std::vector<Vec3f> normals;
  if (any_crease) {
    std::vector<Vec3f> pts(c.x.size());
    for (std::size_t i = 0; i < pts.size(); ++i) pts[i] = {float(c.x[i].x), float(c.x[i].y), float(c.x[i].z)};
    normals = area_weighted_normals(pts, c.m.triangles);
  }
  parallel_for(ls.size(), c.m.options.grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const LineSearch& l = ls[i];
      if (l.reach == 0.f) continue;  // no search: start_search set the candidate
      const Vec3d d{l.dir.x, l.dir.y, l.dir.z};
      if (l.phase == Phase::kCrease) {
        const bool before = dot(c.grad[i], normals[i]) <= 0.f;
        const float t = before ? l.turn_lo : l.turn_hi,
                    away = before ? l.turn_lo - l.turn_hi : l.turn_hi - l.turn_lo;
        const float back = c.m.options.contact_offset * c.m.edge[i] * (away < 0.f ? -1.f : 1.f);
        out.point[i] = c.x[i] + d * double(t + back);
        out.normal[i] = crease_normal(l, d);
        out.res[i] = 0.f;
        out.kind[i] = TargetKind::kContact;
      } else {
        out.point[i] = c.x[i] + d * double(l.best_t);
        out.res[i] = std::abs(l.best_r);
      }
    }
  });
}

}  // namespace

void search_targets(EnergyCall& c, TargetSet& out) {
  const EnergyData& m = c.m;
  const EnergyTrackerOptions& o = m.options;
  const SearchContext s{c, std::cos(o.contact_angle_deg * kPiF / 180.f), 1e-3f * o.iso_tolerance,
                        o.min_gradient, o.angle_contacts};
  out.point = c.x;
  out.normal.assign(m.n, Vec3d{});
  out.res.assign(m.n, 0.f);
  out.kind.assign(m.n, TargetKind::kNone);
  std::vector<LineSearch> ls(m.n);
  parallel_for(m.moving.size(), o.grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      const std::size_t i = std::size_t(m.moving[a]);
      if (!start_search(s, i, ls[i], out, c.lost[i])) ls[i] = LineSearch{};
    }
  });
  for (int step = 0; step < o.search_steps; ++step) c.stats.field_evaluations += sub_step(s, ls, false);
  for (int k = 0; k < kCreaseBisections; ++k) c.stats.field_evaluations += sub_step(s, ls, true);
  finish(c, ls, out);
}

}  // namespace isokit::track::detail
