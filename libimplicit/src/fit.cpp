// SPDX-License-Identifier: MIT
#include "isokit/implicit/fit.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "fit_caps.h"
#include "isokit/core/error.h"
#include "isokit/implicit/fit_quality.h"

namespace isokit::implicit {

namespace {

/// splitmix64: a tiny deterministic generator (the same stream on every platform).
struct SplitMix {
  std::uint64_t s;
  std::uint64_t next() {
    std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform() { return double(next() >> 11) * (1.0 / 9007199254740992.0); }
};

bool finite(const Vec3d& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

double segment_distance(const Vec3d& p, double len) {  // to the segment (0,0,0)-(0,0,len)
  const double z = std::clamp(p.z, 0.0, len);
  return norm(p - Vec3d{0, 0, z});
}

std::vector<std::size_t> dart_throw(const std::vector<HrbfSample>& c, double radius, std::size_t cap) {
  std::vector<std::size_t> kept;
  const double r2 = radius * radius;
  for (std::size_t i = 0; i < c.size() && kept.size() <= cap; ++i) {
    bool ok = true;
    for (std::size_t k : kept) {
      if (squared_norm(c[i].position - c[k].position) < r2) {
        ok = false;
        break;
      }
    }
    if (ok) kept.push_back(i);
  }
  return kept;
}

}  // namespace

FieldPtr FittedPart::field() const {
  if (grid) return grid;
  return local;
}

namespace {

/// The frame with origin `a`, z along `b − a` and x along `x` made orthogonal to z.
Rigid3d frame_from(const Vec3d& a, const Vec3d& ez, const Vec3d& x) {
  Vec3d ex = x - ez * dot(x, ez);
  ex = ex / norm(ex);
  const Vec3d ey = cross(ez, ex);
  Rigid3d xf;
  for (int r = 0; r < 3; ++r) {
    xf.R(r, 0) = ex[r];
    xf.R(r, 1) = ey[r];
    xf.R(r, 2) = ez[r];
  }
  xf.t = a;
  return xf;
}

}  // namespace

Rigid3d bone_frame(const Vec3d& a, const Vec3d& b) {
  const Vec3d ez = (b - a) / norm(b - a);
  // x: the world axis least aligned with the bone, made orthogonal.
  const Vec3d pick = std::abs(ez.x) <= std::abs(ez.y) && std::abs(ez.x) <= std::abs(ez.z)
                         ? Vec3d{1, 0, 0}
                         : (std::abs(ez.y) <= std::abs(ez.z) ? Vec3d{0, 1, 0} : Vec3d{0, 0, 1});
  return frame_from(a, ez, pick);
}

namespace {

/// A part's sub-mesh in its bone frame, with what the sampling needs.
struct LocalMesh {
  std::vector<Vec3d> v;     ///< vertices, bone frame
  std::vector<Vec3d> vn;    ///< area-weighted vertex normals (not normalised)
  std::vector<double> cum;  ///< cumulative triangle areas
  double area{0};
  double len{0};  ///< bone length
};

void validate_options(const PartFitOptions& o, const std::string& name) {
  require(o.target_samples >= 4 && o.target_samples <= 10000, name + ": target_samples",
          "must be in [4, 10000] (got " + std::to_string(o.target_samples) + ")", "use the default 50");
  require(o.candidates_per_sample >= 1, name + ": candidates_per_sample", "must be >= 1",
          "use the default 10");
  require(o.cull_h >= 0 && o.cull_h < 0.5, name + ": cull_h",
          "must be in [0, 0.5) (got " + format_number(o.cull_h) + ")", "use the default 0.05");
  require(o.opening_offset >= 0 && o.opening_offset <= 2, name + ": opening_offset",
          "must be in [0, 2] (got " + format_number(o.opening_offset) + ")", "use 0.1 (the default)");
  require(o.cap_height >= 0 && o.cap_height <= 2, name + ": cap_height",
          "must be in [0, 2] (got " + format_number(o.cap_height) + ")", "use 1 (the default)");
  require(o.support_margin > 0 && std::isfinite(o.support_margin), name + ": support_margin", "must be > 0",
          "use the default 1");
}

/// The sub-mesh in the bone frame `frame`, checked: finite, non-empty, a bone of non-zero
/// length, indices in range, non-zero area.
LocalMesh local_mesh(const MeshPart& part, const Rigid3d& frame, double len) {
  const std::string& name = part.name;
  LocalMesh m;
  m.len = len;
  m.v.resize(part.vertices.size());
  for (std::size_t i = 0; i < m.v.size(); ++i) m.v[i] = frame.apply_inverse(part.vertices[i]);
  const int nv = int(m.v.size());
  m.vn.resize(m.v.size());
  m.cum.resize(part.triangles.size());
  for (std::size_t t = 0; t < part.triangles.size(); ++t) {
    const auto& tri = part.triangles[t];
    for (int k = 0; k < 3; ++k)
      if (tri[k] < 0 || tri[k] >= nv)
        require(false, name + ": triangle " + std::to_string(t),
                "indexes vertex " + std::to_string(tri[k]) + " of " + std::to_string(nv), "fix the indices");
    const Vec3d n = cross(m.v[tri[1]] - m.v[tri[0]], m.v[tri[2]] - m.v[tri[0]]);
    for (int k = 0; k < 3; ++k) m.vn[tri[k]] += n;
    m.area += 0.5 * norm(n);
    m.cum[t] = m.area;
  }
  require(m.area > 0, name, "the sub-mesh has zero area", "give the part real triangles");
  return m;
}

/// The bone length, after checking the bone and the vertices (finite, a sub-mesh, a bone of
/// non-zero length).
double checked_bone_length(const MeshPart& part) {
  const std::string& name = part.name;
  require(finite(part.bone_start) && finite(part.bone_end), name + ": bone", "has non-finite end points",
          "fix the skeleton");
  const double len = norm(part.bone_end - part.bone_start);
  require(!part.vertices.empty() && !part.triangles.empty(), name, "the sub-mesh is empty",
          "assign triangles to this bone or leave it out of the rig");
  Box3d vbox;
  for (std::size_t i = 0; i < part.vertices.size(); ++i) {
    if (!finite(part.vertices[i]))
      require(false, name + ": vertex " + std::to_string(i), "is not finite", "remove NaN/inf vertices");
    vbox.extend(part.vertices[i]);
  }
  require(len > 1e-9 * std::max(1.0, norm(vbox.size())), name + ": bone",
          "has zero length (" + format_number(len) + ")", "give the bone distinct end points");
  return len;
}

/// Candidates: `ncand` area-weighted uniform points (seeded), culled by the planes of eq. 2, with
/// their interpolated normals.
std::vector<HrbfSample> candidates(const MeshPart& part, const LocalMesh& m, const PartFitOptions& o,
                                   std::size_t ncand) {
  SplitMix rng{o.seed};
  std::vector<HrbfSample> cand;
  cand.reserve(ncand);
  for (std::size_t c = 0; c < ncand; ++c) {
    const double pick = rng.uniform() * m.area;
    const std::size_t t = std::min(
        std::size_t(std::lower_bound(m.cum.begin(), m.cum.end(), pick) - m.cum.begin()), m.cum.size() - 1);
    const double su = std::sqrt(rng.uniform()), w = rng.uniform();
    const double b0 = 1 - su, b1 = su * (1 - w), b2 = su * w;
    const auto& tri = part.triangles[t];
    const Vec3d p = m.v[tri[0]] * b0 + m.v[tri[1]] * b1 + m.v[tri[2]] * b2;
    const double u = p.z / m.len;
    if (!(u > o.cull_h && u < 1 - o.cull_h)) continue;
    Vec3d n = m.vn[tri[0]] * b0 + m.vn[tri[1]] * b1 + m.vn[tri[2]] * b2;
    if (!(norm(n) > 0)) n = cross(m.v[tri[1]] - m.v[tri[0]], m.v[tri[2]] - m.v[tri[0]]);
    if (!(norm(n) > 0)) continue;
    cand.push_back({p, n / norm(n)});
  }
  return cand;
}

/// Poisson-disk selection: bisects the disk radius so that greedy dart throwing keeps about
/// `target` candidates (the smallest count >= target found, else the largest). `kept_area`: the
/// area the candidates cover.
std::vector<std::size_t> poisson_disk(const std::vector<HrbfSample>& cand, std::size_t target,
                                      double kept_area) {
  std::vector<std::size_t> best;
  if (cand.size() <= target) {
    for (std::size_t i = 0; i < cand.size(); ++i) best.push_back(i);
    return best;
  }
  const double guess = std::sqrt(2.0 * kept_area / (std::sqrt(3.0) * double(target)));
  double lo = 0.1 * guess, hi = 2.0 * guess;
  for (int it = 0; it < 16; ++it) {
    const double mid = 0.5 * (lo + hi);
    std::vector<std::size_t> kept = dart_throw(cand, mid, 2 * target);
    const bool enough = kept.size() >= target;
    if (enough && (best.size() < target || kept.size() < best.size())) best = kept;
    if (!enough && best.size() < target && kept.size() > best.size()) best = kept;
    if (kept.size() >= target && kept.size() <= target + 2) break;
    (enough ? lo : hi) = mid;
  }
  return best;
}

/// Orientation: outward normals point away from the bone on average. An inward-oriented mesh
/// would give an inverted field (inside < 0.5): refuse it rather than fit it.
void require_outward(const std::vector<HrbfSample>& samples, double len, const std::string& name) {
  double outward = 0;
  for (const HrbfSample& s : samples) {
    const Vec3d radial = s.position - Vec3d{0, 0, std::clamp(s.position.z, 0.0, len)};
    const double rl = norm(radial);
    if (rl > 0) outward += dot(s.normal, radial) / rl;
  }
  require(outward > 0, name, "the triangles are oriented inward (normals point towards the bone)",
          "flip the triangle winding of this part");
}

/// Closure points (2013 §4.1, Fig. 3), appended to `out.samples`: on the axis, `s` beyond each
/// closed bone end, and `opening_offset × s` beyond each opening; normals outward.
void add_closure_points(const MeshPart& part, const LocalMesh& m, const PartFitOptions& o, FittedPart& out) {
  const std::string& name = part.name;
  const double len = m.len;
  auto nearest = [&](const Vec3d& joint) {
    double s = std::numeric_limits<double>::infinity();
    for (const Vec3d& p : m.v) s = std::min(s, norm(p - joint));
    return s;
  };
  if (o.close_start) {
    const double s = nearest({0, 0, 0});
    require(s > 1e-6 * len, name + ": closure at bone_start", "a vertex lies on the joint",
            "move the joint inside the limb or disable PartFitOptions::close_start");
    out.samples.push_back({{0, 0, -s}, {0, 0, -1}});
    ++out.closure_points;
  }
  if (o.close_end) {
    const double s = nearest({0, 0, len});
    require(s > 1e-6 * len, name + ": closure at bone_end", "a vertex lies on the joint",
            "move the joint inside the limb or disable PartFitOptions::close_end");
    out.samples.push_back({{0, 0, len + s}, {0, 0, 1}});
    ++out.closure_points;
  }
  const Rigid3d& frame = out.local_to_world;
  for (std::size_t k = 0; k < part.openings.size(); ++k) {
    const Vec3d j = frame.apply_inverse(part.openings[k].joint);
    const Vec3d d = frame.rotate_inverse(part.openings[k].direction);
    const std::string item = name + ": opening " + std::to_string(k);
    require(finite(j) && finite(d) && norm(d) > 0.5 && norm(d) < 2, item,
            "needs a finite joint and a unit direction",
            "pass the child joint and the direction out of the part");
    const double s = nearest(j);
    require(s > 1e-6 * len, item, "a vertex lies on the joint", "move the joint inside the part");
    out.samples.push_back({j + d * (o.opening_offset * s / norm(d)), d / norm(d)});
    ++out.closure_points;
  }
}

/// Border caps (`PartFitOptions::Closure::border_caps`), appended to `out.samples`: a dome over
/// each open border loop of the part's triangles, its points about `spacing` apart.
void add_border_caps(const MeshPart& part, const LocalMesh& m, const PartFitOptions& o, double spacing,
                     FittedPart& out) {
  for (const std::vector<int>& loop : detail::boundary_loops(part.triangles, int(m.v.size()))) {
    const std::vector<HrbfSample> cap = detail::loop_cap(m.v, loop, o.cap_height, spacing, {0, 0, 1});
    out.samples.insert(out.samples.end(), cap.begin(), cap.end());
    out.closure_points += int(cap.size());
  }
}

/// The compact field `t_r(d)` of the fitted HRBF into `out.local`, `out.r` = the largest distance
/// from the bone segment to a sample. Support box: the samples' box grown by margin × r, grown
/// further (up to 8×) until d >= r on all its faces (d is not a true distance: |∇d| may fall
/// below 1 away from the samples).
void compact_field(const std::shared_ptr<const Hrbf>& hrbf, double len, const PartFitOptions& o,
                   const std::string& name, FittedPart& out) {
  Box3d sbox;
  for (const HrbfSample& s : hrbf->samples()) {
    sbox.extend(s.position);
    out.r = std::max(out.r, segment_distance(s.position, len));
  }
  std::string last_error;
  for (double grow : {1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0}) {
    const double g = o.support_margin * grow * out.r;
    const Box3f box{{float(sbox.lo.x - g), float(sbox.lo.y - g), float(sbox.lo.z - g)},
                    {float(sbox.hi.x + g), float(sbox.hi.y + g), float(sbox.hi.z + g)}};
    try {
      out.local = std::make_shared<const HrbfField>(hrbf, out.r, box);
      break;
    } catch (const InputError& e) {
      last_error = e.what();
    }
  }
  require(out.local != nullptr, name,
          "the HRBF field does not vanish on any support box tried (" + last_error + ")",
          "check the part's samples and normals");
}

/// One fit with one closure rule (`o.closure` is `joints` or `border_caps`).
FittedPart fit_part_closed(const MeshPart& part, const PartFitOptions& o) {
  const std::string& name = part.name;
  const double len = checked_bone_length(part);
  FittedPart out;
  out.local_to_world = bone_frame(part.bone_start, part.bone_end);
  const LocalMesh mesh = local_mesh(part, out.local_to_world, len);
  const std::size_t ncand = std::size_t(o.target_samples) * std::size_t(o.candidates_per_sample);
  const std::vector<HrbfSample> cand = candidates(part, mesh, o, ncand);
  require(cand.size() >= 4, name, "fewer than 4 surface samples survive the culling planes",
          "check that the sub-mesh surrounds its bone, or lower PartFitOptions::cull_h");
  const double kept_area = mesh.area * double(cand.size()) / double(ncand);
  for (std::size_t i : poisson_disk(cand, std::size_t(o.target_samples), kept_area))
    out.samples.push_back(cand[i]);
  require_outward(out.samples, len, name);
  if (o.closure == PartFitOptions::Closure::joints) {
    add_closure_points(part, mesh, o, out);
  } else {
    const double spacing = std::sqrt(kept_area / double(std::max<std::size_t>(out.samples.size(), 1)));
    add_border_caps(part, mesh, o, spacing, out);
  }
  compact_field(std::make_shared<const Hrbf>(out.samples, o.hrbf, name), len, o, name, out);
  if (o.sample_grid) {
    GridFieldOptions go;
    go.resolution = o.grid_resolution;
    go.storage = o.grid_storage;
    out.grid = std::make_shared<const GridField>(*out.local, out.local->support(), go);
  }
  return out;
}

/// The score `Closure::best` compares: vertex → surface plus surface → part p95, the part closed
/// by a flat fan over each border loop (world units).
double closed_fit_score(const FittedPart& fit, const MeshPart& part) {
  std::vector<Vec3d> v = part.vertices;
  std::vector<std::array<int, 3>> t = part.triangles;
  detail::close_with_fans(v, t);
  FitDistanceOptions fo;
  fo.resolution = 24;
  const FitDistances d = fit_distances(*fit.field(), fit.local_to_world, v, t, {}, fo);
  return d.to_surface_p95 + d.from_surface_p95;
}

}  // namespace

FittedPart fit_part(const MeshPart& part, const PartFitOptions& o) {
  validate_options(o, part.name);
  if (o.field == PartFitOptions::FieldKind::distance) return fit_part_distance(part, o);
  if (o.closure != PartFitOptions::Closure::best) {
    FittedPart out = fit_part_closed(part, o);
    out.error = closed_fit_score(out, part);
    return out;
  }
  PartFitOptions oj = o, oc = o;
  oj.closure = PartFitOptions::Closure::joints;
  oc.closure = PartFitOptions::Closure::border_caps;
  FittedPart joints, caps;
  std::string error;
  try {
    joints = fit_part_closed(part, oj);
  } catch (const InputError& e) {
    error = e.what();
  }
  try {
    caps = fit_part_closed(part, oc);
  } catch (const InputError&) {
    if (!joints.local) throw InputError(error);
    joints.error = closed_fit_score(joints, part);
    return joints;
  }
  caps.error = closed_fit_score(caps, part);
  if (!joints.local) return caps;
  joints.error = closed_fit_score(joints, part);
  return caps.error < joints.error ? caps : joints;
}

std::vector<FittedPart> fit_parts(const std::vector<MeshPart>& parts, const PartFitOptions& options,
                                  std::vector<std::string>* errors) {
  std::vector<FittedPart> out(parts.size());
  if (errors) errors->assign(parts.size(), std::string());
  for (std::size_t i = 0; i < parts.size(); ++i) {
    try {
      out[i] = fit_part(parts[i], options);
    } catch (const InputError& e) {
      if (!errors) throw;
      (*errors)[i] = e.what();
    }
  }
  return out;
}

}  // namespace isokit::implicit
