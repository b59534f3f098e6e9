// SPDX-License-Identifier: MIT
// Procedural rigs: shared assembly (frames, bind, weights), the surfaces of revolution of the
// cylinder and the finger, and the spec parser (the surface report: surface_report.cpp).
#include "isokit/skinning/procedural.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <map>
#include <numeric>
#include <sstream>
#include <tuple>

#include "isokit/core/error.h"
#include "isokit/core/math.h"
#include "isokit/skinning/metrics.h"
#include "rig/polygonize.h"
#include "rig/procedural_detail.h"

namespace isokit::skinning {
namespace detail {

Eigen::Matrix3d joint_frame(const Eigen::Vector3d& y_dir, const Eigen::Vector3d& z_ref) {
  const Eigen::Vector3d y = y_dir.normalized();
  Eigen::Vector3d z = z_ref - z_ref.dot(y) * y;
  if (z.norm() < 1e-9) z = y.unitOrthogonal();
  z.normalize();
  Eigen::Matrix3d r;
  r.col(0) = y.cross(z);
  r.col(1) = y;
  r.col(2) = z;
  return r;
}

Rig assemble_rig(const std::string& name, TriangleMesh mesh, const std::vector<JointSpec>& joints) {
  Rig rig;
  rig.name = name;
  rig.rest = std::move(mesh.vertices);
  rig.triangles = std::move(mesh.triangles);
  std::vector<Affine> world(joints.size());
  std::vector<std::vector<Segment>> segments(joints.size());
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const JointSpec& s = joints[j];
    Affine w = Affine::Identity();
    w.linear() = joint_frame(s.y_dir, s.z_ref);
    w.translation() = s.position;
    world[j] = w;
    Joint jt;
    jt.name = s.name;
    jt.parent = s.parent;
    jt.rest_local =
        s.parent < 0 ? w : Affine(world[static_cast<std::size_t>(s.parent)].inverse(Eigen::Isometry) * w);
    jt.inverse_bind = w.inverse(Eigen::Isometry);
    rig.joints.push_back(jt);
    segments[j] = s.bones;
  }
  HeatWeightOptions wo;
  wo.name = name;
  rig.weights = heat_weights(rig.rest, rig.triangles, segments, wo);
  validate(rig);
  return rig;
}

}  // namespace detail

namespace {

using detail::JointSpec;
using detail::TriangleMesh;

/// Surface of revolution about +y of a round cone (convex hull of the spheres (y0, r0) and
/// (y1, r1)), poles on the axis, rings spaced ≈ h·√3/2 along the profile with ≈ 2πr/h vertices,
/// alternately rotated by half a step (near-equilateral triangles).
class RoundConeProfile {
 public:
  RoundConeProfile(double y0, double r0, double y1, double r1) : y0_(y0), r0_(r0), len_(y1 - y0), r1_(r1) {
    s_ = (r0 - r1) / len_;
    c_ = std::sqrt(1 - s_ * s_);
    phi_ = std::atan2(c_, s_);
    arc0_ = r0 * (kPi - phi_);
    line_ = len_ * c_;
    arc1_ = r1 * phi_;
  }
  double length() const { return arc0_ + line_ + arc1_; }
  /// (axial y, radius) at profile arc length u ∈ [0, length()].
  std::pair<double, double> at(double u) const {
    if (u <= arc0_) {
      const double a = kPi - u / r0_;
      return {y0_ + r0_ * std::cos(a), r0_ * std::sin(a)};
    }
    if (u <= arc0_ + line_) {
      const double t = (u - arc0_) / line_;
      const double ya = y0_ + r0_ * s_, ra = r0_ * c_;
      const double yb = y0_ + len_ + r1_ * s_, rb = r1_ * c_;
      return {ya + t * (yb - ya), ra + t * (rb - ra)};
    }
    const double a = phi_ * (1 - (u - arc0_ - line_) / arc1_);
    return {y0_ + len_ + r1_ * std::cos(a), r1_ * std::sin(a)};
  }

 private:
  double y0_, r0_, len_, r1_, s_{0}, c_{1}, phi_{0}, arc0_{0}, line_{0}, arc1_{0};
};

struct RingLayout {
  std::vector<double> y, r;
  std::vector<int> count;
  int vertices() const { return 2 + std::accumulate(count.begin(), count.end(), 0); }
};

RingLayout ring_layout(const RoundConeProfile& prof, double h) {
  RingLayout l;
  const int m = std::max(2, static_cast<int>(std::lround(prof.length() / (h * std::sqrt(3.0) / 2))));
  for (int k = 1; k < m; ++k) {
    const auto [y, r] = prof.at(prof.length() * k / m);
    l.y.push_back(y);
    l.r.push_back(r);
    l.count.push_back(std::max(3, static_cast<int>(std::lround(2 * kPi * r / h))));
  }
  return l;
}

TriangleMesh revolve(const RoundConeProfile& prof, int target_vertices) {
  // Bisection on log h for the vertex count closest to the target.
  double lo = std::log(prof.length() * 1e-4), hi = std::log(prof.length());
  for (int it = 0; it < 100; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (ring_layout(prof, std::exp(mid)).vertices() > target_vertices)
      lo = mid;
    else
      hi = mid;
  }
  const RingLayout fine = ring_layout(prof, std::exp(lo)), coarse = ring_layout(prof, std::exp(hi));
  const RingLayout& l =
      std::abs(fine.vertices() - target_vertices) <= std::abs(coarse.vertices() - target_vertices) ? fine
                                                                                                   : coarse;

  TriangleMesh mesh;
  const int nrings = static_cast<int>(l.count.size());
  mesh.vertices.resize(l.vertices(), 3);
  std::vector<int> first(static_cast<std::size_t>(nrings));
  std::vector<double> phase(static_cast<std::size_t>(nrings));
  const auto [ybot, rbot] = prof.at(0);
  const auto [ytop, rtop] = prof.at(prof.length());
  (void)rbot;
  (void)rtop;
  int v = 0;
  mesh.vertices.row(v++) << 0.f, static_cast<float>(ybot), 0.f;
  for (int k = 0; k < nrings; ++k) {
    const int n = l.count[static_cast<std::size_t>(k)];
    first[static_cast<std::size_t>(k)] = v;
    phase[static_cast<std::size_t>(k)] = (k % 2) ? kPi / n : 0.0;
    for (int i = 0; i < n; ++i) {
      const double t = phase[static_cast<std::size_t>(k)] + 2 * kPi * i / n;
      const double r = l.r[static_cast<std::size_t>(k)];
      mesh.vertices.row(v++) << static_cast<float>(r * std::cos(t)),
          static_cast<float>(l.y[static_cast<std::size_t>(k)]), static_cast<float>(-r * std::sin(t));
    }
  }
  const int top = v;
  mesh.vertices.row(v++) << 0.f, static_cast<float>(ytop), 0.f;

  std::vector<std::array<int, 3>> tris;
  auto ring_vertex = [&](int k, int i) {
    const int n = l.count[static_cast<std::size_t>(k)];
    return first[static_cast<std::size_t>(k)] + ((i % n) + n) % n;
  };
  for (int i = 0; i < l.count.front(); ++i) tris.push_back({0, ring_vertex(0, i + 1), ring_vertex(0, i)});
  for (int k = 0; k + 1 < nrings; ++k) {
    // Merge the lower ring A = k and the upper ring B = k + 1 by angle.
    const int na = l.count[static_cast<std::size_t>(k)], nb = l.count[static_cast<std::size_t>(k) + 1];
    const double pa = phase[static_cast<std::size_t>(k)], pb = phase[static_cast<std::size_t>(k) + 1];
    int j0 = static_cast<int>(std::lround((pa - pb) * nb / (2 * kPi)));
    const double b0 = pb + 2 * kPi * j0 / nb;
    auto ang_a = [&](int a) { return pa + 2 * kPi * a / na; };
    auto ang_b = [&](int b) { return b0 + 2 * kPi * b / nb; };
    int a = 0, b = 0;
    while (a < na || b < nb) {
      if (b == nb || (a < na && ang_a(a + 1) <= ang_b(b + 1))) {
        tris.push_back({ring_vertex(k, a), ring_vertex(k, a + 1), ring_vertex(k + 1, j0 + b)});
        ++a;
      } else {
        tris.push_back({ring_vertex(k, a), ring_vertex(k + 1, j0 + b + 1), ring_vertex(k + 1, j0 + b)});
        ++b;
      }
    }
  }
  for (int i = 0; i < l.count.back(); ++i)
    tris.push_back({ring_vertex(nrings - 1, i), ring_vertex(nrings - 1, i + 1), top});
  mesh.triangles.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (std::size_t f = 0; f < tris.size(); ++f)
    mesh.triangles.row(static_cast<Eigen::Index>(f)) << tris[f][0], tris[f][1], tris[f][2];
  return mesh;
}

/// Shortest decimal (up to 17 digits) that reads back as `x`.
std::string fmt(double x) {
  for (int digits = 6;; ++digits) {
    std::ostringstream s;
    s.precision(digits);
    s << x;
    if (digits >= 17 || std::strtod(s.str().c_str(), nullptr) == x) return s.str();
  }
}

void check_vertices(int v, int lo, int hi, const std::string& what) {
  require(v >= lo && v <= hi, what + ": vertices", "out of range (got " + std::to_string(v) + ")",
          "request between " + std::to_string(lo) + " and " + std::to_string(hi) + " vertices");
}

}  // namespace

Rig make_cylinder(const CylinderOptions& o) {
  const std::string what = "procedural cylinder";
  check_vertices(o.vertices, 50, 2000000, what);
  require(o.length > 0 && std::isfinite(o.length), what + ": length", "must be > 0",
          "pass a positive length");
  require(o.radius > 0 && std::isfinite(o.radius), what + ": radius", "must be > 0",
          "pass a positive radius");
  TriangleMesh mesh = revolve(RoundConeProfile(0.0, o.radius, o.length, o.radius), o.vertices);
  const Eigen::Vector3d y = Eigen::Vector3d::UnitY(), z = Eigen::Vector3d::UnitZ();
  std::vector<JointSpec> j(2);
  j[0] = {"Bone0", -1, Eigen::Vector3d::Zero(), y, z, {{Eigen::Vector3d::Zero(), 0.5 * o.length * y}}};
  j[1] = {"Bone1", 0, 0.5 * o.length * y, y, z, {{0.5 * o.length * y, o.length * y}}};
  const std::string name = "procedural:cylinder?vertices=" + std::to_string(o.vertices) +
                           "&length=" + fmt(o.length) + "&radius=" + fmt(o.radius);
  return detail::assemble_rig(name, std::move(mesh), j);
}

Rig make_finger(const FingerOptions& o) {
  check_vertices(o.vertices, 50, 2000000, "procedural finger");
  const double r0 = 0.09, r1 = 0.072, tip = 1.0 - r1;
  TriangleMesh mesh = revolve(RoundConeProfile(0.0, r0, tip, r1), o.vertices);
  const Eigen::Vector3d y = Eigen::Vector3d::UnitY(), z = Eigen::Vector3d::UnitZ();
  const double at[5] = {0.0, 0.15, 0.55, 0.80, tip};
  std::vector<JointSpec> j;
  for (int k = 0; k < 4; ++k)
    j.push_back({"Finger" + std::to_string(k), k - 1, at[k] * y, y, z, {{at[k] * y, at[k + 1] * y}}});
  return detail::assemble_rig("procedural:finger?vertices=" + std::to_string(o.vertices), std::move(mesh), j);
}

Rig make_procedural(const std::string& spec) {
  const std::string valid_names = "cylinder, finger, humanoid";
  const auto q = spec.find('?');
  const std::string kind = spec.substr(0, q);
  std::map<std::string, std::string> kv;
  if (q != std::string::npos) {
    std::stringstream ss(spec.substr(q + 1));
    std::string item;
    while (std::getline(ss, item, '&')) {
      const auto eq = item.find('=');
      require(eq != std::string::npos && eq > 0, "procedural rig '" + spec + "'",
              "option '" + item + "' is not KEY=VALUE", "write e.g. humanoid?vertices=13000&fingers=0");
      kv[item.substr(0, eq)] = item.substr(eq + 1);
    }
  }
  auto valid_keys = [&](const std::string& keys) {
    for (const auto& [k, v] : kv)
      require(("," + keys + ",").find("," + k + ",") != std::string::npos, "procedural rig '" + spec + "'",
              "unknown option '" + k + "'", kind + " takes: " + keys);
  };
  auto as_int = [&](const std::string& key, int def) {
    const auto it = kv.find(key);
    if (it == kv.end()) return def;
    char* end = nullptr;
    const long x = std::strtol(it->second.c_str(), &end, 10);
    require(!it->second.empty() && *end == 0 && x >= 0 && x <= 100000000,
            "procedural rig '" + spec + "': " + key, "'" + it->second + "' is not a non-negative integer",
            "write e.g. " + key + "=" + std::to_string(def));
    return static_cast<int>(x);
  };
  auto as_double = [&](const std::string& key, double def) {
    const auto it = kv.find(key);
    if (it == kv.end()) return def;
    char* end = nullptr;
    const double x = std::strtod(it->second.c_str(), &end);
    require(!it->second.empty() && *end == 0 && std::isfinite(x), "procedural rig '" + spec + "': " + key,
            "'" + it->second + "' is not a number", "write e.g. " + key + "=" + fmt(def));
    return x;
  };
  if (kind == "cylinder") {
    valid_keys("vertices,length,radius");
    CylinderOptions o;
    o.vertices = as_int("vertices", o.vertices);
    o.length = as_double("length", o.length);
    o.radius = as_double("radius", o.radius);
    return make_cylinder(o);
  }
  if (kind == "finger") {
    valid_keys("vertices");
    FingerOptions o;
    o.vertices = as_int("vertices", o.vertices);
    return make_finger(o);
  }
  if (kind == "humanoid") {
    valid_keys("vertices,fingers");
    HumanoidOptions o;
    o.vertices = as_int("vertices", o.vertices);
    const int f = as_int("fingers", 1);
    require(f == 0 || f == 1, "procedural rig '" + spec + "': fingers", "must be 0 or 1",
            "write fingers=0 or fingers=1");
    o.fingers = f == 1;
    return make_humanoid(o);
  }
  require(false, "procedural rig '" + spec + "'", "unknown name '" + kind + "'",
          "use one of: " + valid_names);
  return {};
}

}  // namespace isokit::skinning
