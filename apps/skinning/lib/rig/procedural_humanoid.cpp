// SPDX-License-Identifier: MIT
// The procedural humanoid: a T-pose skeleton (22 joints, 46 with fingers) and a smooth implicit
// body (tapered capsules along the bones, folded by a C1 polynomial smooth union with a blend
// radius per piece), meshed by CGAL Mesh_3 (polygonize_mesh3.cpp) at the facet size that a
// measured vertex-count table gives for the requested count.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "isokit/core/error.h"
#include "isokit/skinning/procedural.h"
#include "rig/polygonize.h"
#include "rig/procedural_detail.h"

namespace isokit::skinning {
namespace {

using detail::JointSpec;
using detail::TriangleMesh;
using V3 = Eigen::Vector3d;

/// Tapered capsule (round cone: convex hull of the spheres (a, ra) and (b, rb)) with its exact
/// signed distance; `k` is its smooth-union blend radius with everything added before it and
/// `detail` the fraction of its radius used as the local facet size (see `Body::local_size`).
struct Piece {
  V3 a, b;
  double ra, rb, k, detail;
  // Derived by `prepare`.
  V3 u{V3::UnitY()}, lo{V3::Zero()}, hi{V3::Zero()};
  double len{0}, s{0}, c{1};

  void prepare() {
    len = (b - a).norm();
    if (len > 1e-12) u = (b - a) / len;
    s = len > 1e-12 ? (ra - rb) / len : 0.0;
    c = std::sqrt(std::max(0.0, 1 - s * s));
    const double m = std::max(ra, rb) + k;
    lo = a.cwiseMin(b) - V3::Constant(m);
    hi = a.cwiseMax(b) + V3::Constant(m);
  }
  /// Signed distance; `t` gets the axial parameter in [0, 1] of the closest axis point.
  double distance(const V3& p, double& t) const {
    const V3 ap = p - a;
    if (len <= 1e-12) {
      t = 0;
      return ap.norm() - std::max(ra, rb);
    }
    const double x = ap.dot(u);
    const double y = std::sqrt(std::max(0.0, ap.squaredNorm() - x * x));
    const double along = x * c - y * s;
    t = std::clamp(x / len, 0.0, 1.0);
    if (along < 0) return ap.norm() - ra;
    if (along > len * c) return (p - b).norm() - rb;
    return x * s + y * c - ra;
  }
  double radius(double t) const { return ra + t * (rb - ra); }
  /// Distance from p to the axis box grown by (max radius + k); where positive, a lower bound of
  /// (distance − k).
  double box_distance(const V3& p) const { return (lo - p).cwiseMax(p - hi).cwiseMax(V3::Zero()).norm(); }
  double box_distance(const V3& blo, const V3& bhi) const {
    return (lo - bhi).cwiseMax(blo - hi).cwiseMax(V3::Zero()).norm();
  }
  /// Upper bound of the signed distance over a box (the axis distance is convex: max at a corner).
  double max_distance(const V3& blo, const V3& bhi) const {
    double m = 0;
    for (int corner = 0; corner < 8; ++corner) {
      const V3 q((corner & 1) ? bhi.x() : blo.x(), (corner & 2) ? bhi.y() : blo.y(),
                 (corner & 4) ? bhi.z() : blo.z());
      const double x = std::clamp((q - a).dot(u), 0.0, len);
      m = std::max(m, (q - a - x * u).norm());
    }
    return m - std::min(ra, rb);
  }
};

/// Quadratic polynomial smooth minimum (C1): equals min(a, b) when |a − b| ≥ k.
double smooth_min(double a, double b, double k) {
  if (k <= 0) return std::min(a, b);
  const double h = std::max(k - std::abs(a - b), 0.0) / k;
  return std::min(a, b) - 0.25 * h * h * k;
}

/// The body: pieces folded in order, `f = smin(...smin(smin(d0, d1, k1), d2, k2)..., dn, kn)`,
/// continuous and C1. A uniform grid lists per cell the pieces that can change the result there
/// (the others are skipped exactly, so the grid changes speed, not values).
struct Body {
  std::vector<Piece> pieces;
  V3 grid_lo, grid_hi;
  double cell{0.02};
  Eigen::Vector3i dims{0, 0, 0};
  std::vector<int> sdf_offsets, sdf_list, size_offsets, size_list;

  void finish() {
    for (Piece& p : pieces) p.prepare();
    grid_lo = pieces[0].lo;
    grid_hi = pieces[0].hi;
    for (const Piece& p : pieces) {
      grid_lo = grid_lo.cwiseMin(p.lo);
      grid_hi = grid_hi.cwiseMax(p.hi);
    }
    for (int d = 0; d < 3; ++d)
      dims[d] = std::max(1, static_cast<int>(std::ceil((grid_hi[d] - grid_lo[d]) / cell)));
    const int n = dims.prod();
    sdf_offsets.assign(1, 0);
    size_offsets.assign(1, 0);
    std::vector<double> dmax(pieces.size());
    for (int idx = 0; idx < n; ++idx) {
      const Eigen::Vector3i c(idx % dims.x(), (idx / dims.x()) % dims.y(), idx / (dims.x() * dims.y()));
      const V3 blo = grid_lo + cell * c.cast<double>(), bhi = blo + V3::Constant(cell);
      double prefix = 1e30, size_bound = 1e30;
      for (std::size_t i = 0; i < pieces.size(); ++i) {
        dmax[i] = pieces[i].max_distance(blo, bhi);
        size_bound = std::min(size_bound, pieces[i].detail * std::max(pieces[i].ra, pieces[i].rb) +
                                              0.5 * std::max(dmax[i], 0.0));
      }
      for (std::size_t j = 0; j < pieces.size(); ++j) {
        // Exact skip: the cell lies outside j's box and some earlier piece i has
        // d_i ≤ dmax_i ≤ box distance of j ≤ d_j − k_j everywhere in the cell, so acc ≤ d_j − k_j
        // when j is folded and smin leaves acc as is.
        const double bd = pieces[j].box_distance(blo, bhi);
        if (j == 0 || bd <= 0 || bd < prefix) sdf_list.push_back(static_cast<int>(j));
        prefix = std::min(prefix, dmax[j]);
        const double lower = pieces[j].detail * std::min(pieces[j].ra, pieces[j].rb) + 0.5 * bd;
        if (lower <= size_bound) size_list.push_back(static_cast<int>(j));
      }
      sdf_offsets.push_back(static_cast<int>(sdf_list.size()));
      size_offsets.push_back(static_cast<int>(size_list.size()));
    }
  }
  int cell_of(const V3& p) const {
    Eigen::Vector3i c;
    for (int d = 0; d < 3; ++d) {
      const double x = (p[d] - grid_lo[d]) / cell;
      if (!(x >= 0 && x < dims[d])) return -1;
      c[d] = std::min(static_cast<int>(x), dims[d] - 1);
    }
    return c.x() + dims.x() * (c.y() + dims.y() * c.z());
  }
  /// Runs `f(piece index)` over the pieces that matter at p (all of them outside the grid).
  template <class F>
  void for_candidates(const V3& p, const std::vector<int>& offsets, const std::vector<int>& list,
                      F&& f) const {
    const int c = cell_of(p);
    if (c < 0) {
      for (std::size_t i = 0; i < pieces.size(); ++i) f(i);
      return;
    }
    for (int k = offsets[static_cast<std::size_t>(c)]; k < offsets[static_cast<std::size_t>(c) + 1]; ++k)
      f(static_cast<std::size_t>(list[static_cast<std::size_t>(k)]));
  }
  double sdf(const V3& p) const {
    double acc = 1e30;
    double t = 0;
    // Outside its box, the box distance is a lower bound of d − k: a piece with a positive box
    // distance ≥ acc leaves acc as is.
    for_candidates(p, sdf_offsets, sdf_list, [&](std::size_t i) {
      const double bd = pieces[i].box_distance(p);
      if (bd > 0 && bd >= acc) return;
      const double d = pieces[i].distance(p, t);
      acc = i == 0 ? d : smooth_min(acc, d, pieces[i].k);
    });
    return acc;
  }
  /// Local facet size: `min_i (detail_i × r_i + d_i⁺ / 2)`, a fraction of the nearest pieces'
  /// radius growing with the distance from them (1/2-Lipschitz): thin parts stay resolved
  /// whatever the global size.
  double local_size(const V3& p) const {
    double s = 1e30;
    double t = 0;
    for_candidates(p, size_offsets, size_list, [&](std::size_t i) {
      if (0.5 * pieces[i].box_distance(p) >= s) return;
      const double d = pieces[i].distance(p, t);
      s = std::min(s, pieces[i].detail * pieces[i].radius(t) + 0.5 * std::max(d, 0.0));
    });
    return s;
  }
};

// Local facet size = detail × piece radius: fingers get ≈ 8 edges around, the other pieces only
// matter when the global size is coarse (small vertex counts).
constexpr double kFingerDetail = 0.45;
constexpr double kBodyDetail = 0.8;
constexpr double kDistanceRatio = 0.15;  // facet distance bound / facet size

struct Skeleton {
  std::vector<JointSpec> joints;
  Body body;

  int add(const std::string& name, const std::string& parent, const V3& pos, const V3& z_ref) {
    int p = -1;
    if (!parent.empty()) {
      for (std::size_t j = 0; j < joints.size(); ++j)
        if (joints[j].name == parent) p = static_cast<int>(j);
    }
    JointSpec s;
    s.name = name;
    s.parent = p;
    s.position = pos;
    s.z_ref = z_ref;
    joints.push_back(s);
    if (p >= 0)
      joints[static_cast<std::size_t>(p)].bones.push_back(
          {joints[static_cast<std::size_t>(p)].position, pos});
    return static_cast<int>(joints.size()) - 1;
  }
  JointSpec& at(const std::string& name) {
    for (JointSpec& j : joints)
      if (j.name == name) return j;
    throw std::logic_error("procedural humanoid: no joint " + name);
  }
  void piece(const V3& a, double ra, const V3& b, double rb, double k, double detail = kBodyDetail) {
    Piece p;
    p.a = a;
    p.b = b;
    p.ra = ra;
    p.rb = rb;
    p.k = k;
    p.detail = detail;
    body.pieces.push_back(p);
  }
};

const V3 kUp = V3::UnitY(), kForward = V3::UnitZ(), kDown = -V3::UnitY(), kBack = -V3::UnitZ();

/// One side (sign +1: left at +x, −1: right) of the arms, hands and fingers.
void add_arm(Skeleton& s, double sign, bool fingers) {
  const std::string side = sign > 0 ? "Left" : "Right";
  auto m = [sign](double x, double y, double z) { return V3(sign * x, y, z); };
  s.add(side + "Shoulder", "Spine2", m(0.05, 1.43, 0), kForward);
  s.add(side + "Arm", side + "Shoulder", m(0.17, 1.43, 0), kForward);
  s.add(side + "ForeArm", side + "Arm", m(0.45, 1.43, 0), kForward);
  s.add(side + "Hand", side + "ForeArm", m(0.71, 1.43, 0), kDown);
  s.piece(m(0.04, 1.40, 0), 0.06, m(0.17, 1.43, 0), 0.055, 0.04);
  s.piece(m(0.17, 1.43, 0), 0.052, m(0.45, 1.43, 0), 0.040, 0.03);
  s.piece(m(0.45, 1.43, 0), 0.040, m(0.71, 1.43, 0), 0.028, 0.02);
  const V3 wrist = m(0.71, 1.43, 0);
  if (!fingers) {
    // Mitten: the palm pieces run on to the finger tips.
    s.piece(wrist, 0.02, m(0.87, 1.43, 0.018), 0.012, 0.012);
    s.piece(wrist, 0.02, m(0.885, 1.43, 0.0), 0.012, 0.012);
    s.piece(wrist, 0.02, m(0.86, 1.43, -0.018), 0.011, 0.012);
    JointSpec& hand = s.at(side + "Hand");
    hand.y_dir = m(1, 0, 0);
    hand.bones.push_back({wrist, m(0.86, 1.43, 0)});
    return;
  }
  struct Finger {
    const char* name;
    V3 base, dir;
    double len[3], r0, r1;
  };
  const Finger list[4] = {
      {"Thumb",
       m(0.725, 1.425, 0.028),
       m(0.55, -0.2, 0.81).normalized(),
       {0.035, 0.030, 0.025},
       0.0105,
       0.0085},
      {"Index", m(0.795, 1.43, 0.026), m(1, 0, 0), {0.040, 0.025, 0.020}, 0.0085, 0.0072},
      {"Middle", m(0.80, 1.43, 0.0), m(1, 0, 0), {0.045, 0.028, 0.022}, 0.0090, 0.0075},
      {"Pinky", m(0.785, 1.43, -0.026), m(1, 0, 0), {0.032, 0.020, 0.016}, 0.0075, 0.0062},
  };
  // Palm: three flat-lying pieces from the wrist to the finger bases.
  s.piece(wrist, 0.02, m(0.795, 1.43, 0.02), 0.016, 0.012);
  s.piece(wrist, 0.02, m(0.80, 1.43, 0.0), 0.017, 0.012);
  s.piece(wrist, 0.02, m(0.785, 1.43, -0.02), 0.015, 0.012);
  for (const Finger& f : list) {
    V3 p = f.base;
    std::string parent = side + "Hand";
    const double total = f.len[0] + f.len[1] + f.len[2];
    double done = 0;
    for (int k = 0; k < 3; ++k) {
      const std::string name = side + "Hand" + f.name + std::to_string(k + 1);
      s.add(name, parent, p, kDown);
      const V3 q = p + f.len[k] * f.dir;
      const double ra = f.r0 + (f.r1 - f.r0) * done / total;
      done += f.len[k];
      const double rb = f.r0 + (f.r1 - f.r0) * done / total;
      // The distal piece ends one tip radius short of the tip, whose sphere rounds it.
      const V3 end = k == 2 ? V3(q - rb * f.dir) : q;
      s.piece(p, ra, end, rb, 0.004, kFingerDetail);
      if (k == 2) {
        JointSpec& j = s.at(name);
        j.y_dir = f.dir;
        j.bones.push_back({p, end});
      }
      parent = name;
      p = q;
    }
  }
  s.at(side + "Hand").y_dir = (list[2].base - wrist).normalized();
}

void add_leg(Skeleton& s, double sign) {
  const std::string side = sign > 0 ? "Left" : "Right";
  auto m = [sign](double x, double y, double z) { return V3(sign * x, y, z); };
  s.add(side + "UpLeg", "Hips", m(0.095, 0.92, 0), kForward);
  s.add(side + "Leg", side + "UpLeg", m(0.105, 0.50, 0.005), kBack);
  s.add(side + "Foot", side + "Leg", m(0.11, 0.085, -0.01), kDown);
  s.add(side + "ToeBase", side + "Foot", m(0.11, 0.035, 0.12), kDown);
  JointSpec& toe = s.at(side + "ToeBase");
  toe.y_dir = V3(0, -0.005, 0.065).normalized();
  toe.bones.push_back({m(0.11, 0.035, 0.12), m(0.11, 0.03, 0.185)});
  s.piece(m(0.095, 0.92, 0), 0.085, m(0.105, 0.50, 0.005), 0.055, 0.03);
  s.piece(m(0.105, 0.50, 0.005), 0.055, m(0.11, 0.085, -0.01), 0.038, 0.02);
  s.piece(m(0.11, 0.055, -0.035), 0.05, m(0.11, 0.035, 0.12), 0.035, 0.02);
  s.piece(m(0.11, 0.035, 0.12), 0.035, m(0.11, 0.03, 0.185), 0.028, 0.01);
}

Skeleton humanoid_skeleton(bool fingers) {
  Skeleton s;
  s.add("Hips", "", V3(0, 0.97, 0), kForward);
  s.add("Spine", "Hips", V3(0, 1.07, 0), kForward);
  s.add("Spine1", "Spine", V3(0, 1.19, 0), kForward);
  s.add("Spine2", "Spine1", V3(0, 1.31, 0), kForward);
  s.add("Neck", "Spine2", V3(0, 1.47, 0), kForward);
  s.add("Head", "Neck", V3(0, 1.58, 0), kForward);
  s.at("Head").bones.push_back({V3(0, 1.58, 0), V3(0, 1.72, 0)});
  // Torso: left/right pairs of vertical pieces (an oval cross-section), then neck and head.
  for (double x : {0.07, -0.07}) {
    const double sx = x > 0 ? 1 : -1;
    s.piece(V3(x, 0.90, 0), 0.12, V3(sx * 0.06, 1.04, 0), 0.11, 0.05);
    s.piece(V3(sx * 0.06, 1.04, 0), 0.11, V3(x, 1.22, 0), 0.115, 0.05);
    s.piece(V3(x, 1.22, 0), 0.12, V3(sx * 0.06, 1.38, 0), 0.105, 0.05);
  }
  s.piece(V3(0, 1.40, 0), 0.05, V3(0, 1.56, 0), 0.045, 0.03);
  s.piece(V3(0, 1.61, 0.015), 0.085, V3(0, 1.70, 0.0), 0.10, 0.03);
  add_arm(s, 1, fingers);
  add_arm(s, -1, fingers);
  add_leg(s, 1);
  add_leg(s, -1);
  // Main-child bone directions (local +y): the first child, except where set above.
  for (JointSpec& j : s.joints)
    if (j.y_dir == V3::UnitY() && !j.bones.empty())
      j.y_dir = (j.bones.front().b - j.bones.front().a).normalized();
  s.at("Head").y_dir = kUp;
  s.body.finish();
  return s;
}

/// Measured vertex counts of the humanoid against the global facet size h (decreasing h); the
/// count at other sizes is interpolated (extrapolated beyond the ends) linearly in log-log.
/// Large h is limited by the local sizes (the floor). Regenerate if the body or the mesher
/// criteria change (the resulting counts are checked by the tests).
struct CountPoint {
  double h, n;
};
const std::vector<CountPoint> kCountsFingers = {
    {0.06, 3251},         {0.03, 3953},         {0.02, 5456},        {0.0152211, 7422},   {0.0104781, 13077},
    {0.00946, 15527},     {0.007975, 20799},    {0.00660873, 29513}, {0.00549663, 41839}, {0.00409103, 73882},
    {0.00351068, 100035}, {0.00268761, 169204}, {0.00249589, 197060}};
const std::vector<CountPoint> kCountsNoFingers = {{0.06, 1273},  {0.03, 1982},   {0.02, 3495},  {0.014, 6451},
                                                  {0.01, 12366}, {0.007, 24946}, {0.005, 48646}};

/// log n as a function of log h, and its slope, from a table.
std::pair<double, double> log_count(const std::vector<CountPoint>& t, double h) {
  std::size_t k = 0;
  while (k + 2 < t.size() && h < t[k + 1].h) ++k;
  const double x0 = std::log(t[k].h), x1 = std::log(t[k + 1].h);
  const double y0 = std::log(t[k].n), y1 = std::log(t[k + 1].n);
  const double slope = (y1 - y0) / (x1 - x0);
  return {y0 + slope * (std::log(h) - x0), slope};
}

/// The size for `target` vertices (the table's largest h when the target is below its floor).
double size_for(const std::vector<CountPoint>& t, double target) {
  if (target <= t.front().n) return t.front().h;
  double lo = std::log(t.back().h) - 3, hi = std::log(t.front().h);
  for (int it = 0; it < 100; ++it) {
    const double mid = 0.5 * (lo + hi);
    (log_count(t, std::exp(mid)).first > std::log(target) ? lo : hi) = mid;
  }
  return std::exp(0.5 * (lo + hi));
}

}  // namespace

Rig make_humanoid(const HumanoidOptions& o) {
  const int min_vertices = o.fingers ? 3000 : 2000;
  require(o.vertices >= min_vertices && o.vertices <= 400000, "procedural humanoid: vertices",
          "out of range (got " + std::to_string(o.vertices) + ")",
          "request between " + std::to_string(min_vertices) + " and 400000 vertices" +
              (o.fingers ? " (fingers need at least 3000; fingers=0 allows 2000)" : ""));
  const Skeleton s = humanoid_skeleton(o.fingers);
  const Body& body = s.body;
  detail::ImplicitShape shape;
  shape.sdf = [&body](const V3& p) { return body.sdf(p); };
  shape.local_size = [&body](const V3& p) { return body.local_size(p); };
  shape.center = V3(0, 0.9, 0);
  shape.radius = 1.45;
  for (const Piece& p : body.pieces) {
    const V3 mid = 0.5 * (p.a + p.b);
    const V3 axis = (p.b - p.a).norm() > 1e-12 ? V3((p.b - p.a).normalized()) : V3::UnitY();
    const V3 e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
    const double r = p.radius(0.5);
    for (const V3& d : {e1, V3(-e1), e2, V3(-e2)}) {
      const V3 out = mid + 1.6 * r * d;
      if (body.sdf(mid) < 0 && body.sdf(out) > 0) shape.seeds.emplace_back(mid, out);
    }
  }
  // Facet size from the measured count table, corrected (at most twice, with the table's local
  // log-log slope) when the mesh misses the target by more than 10 %.
  const std::vector<CountPoint>& table = o.fingers ? kCountsFingers : kCountsNoFingers;
  double h = size_for(table, o.vertices);
  TriangleMesh mesh = detail::mesh_implicit_surface(shape, h, kDistanceRatio);
  for (int round = 0; round < 2; ++round) {
    const double n = static_cast<double>(mesh.vertices.rows());
    if (std::abs(n - o.vertices) <= 0.10 * o.vertices || h >= table.front().h) break;
    const double slope = log_count(table, h).second;
    h = std::min(table.front().h, h * std::pow(n / o.vertices, -1.0 / slope));
    mesh = detail::mesh_implicit_surface(shape, h, kDistanceRatio);
  }
  const std::string name =
      "procedural:humanoid?vertices=" + std::to_string(o.vertices) + "&fingers=" + (o.fingers ? "1" : "0");
  return detail::assemble_rig(name, std::move(mesh), s.joints);
}

}  // namespace isokit::skinning
