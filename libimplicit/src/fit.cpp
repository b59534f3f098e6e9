// SPDX-License-Identifier: MIT
#include "isokit/implicit/fit.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "isokit/core/error.h"

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

Rigid3d bone_frame(const Vec3d& a, const Vec3d& b) {
  const Vec3d ez = (b - a) / norm(b - a);
  // x: the world axis least aligned with the bone, made orthogonal.
  const Vec3d pick = std::abs(ez.x) <= std::abs(ez.y) && std::abs(ez.x) <= std::abs(ez.z)
                         ? Vec3d{1, 0, 0}
                         : (std::abs(ez.y) <= std::abs(ez.z) ? Vec3d{0, 1, 0} : Vec3d{0, 0, 1});
  Vec3d ex = pick - ez * dot(pick, ez);
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

FittedPart fit_part(const MeshPart& part, const PartFitOptions& o) {
  const std::string& name = part.name;
  require(o.target_samples >= 4 && o.target_samples <= 10000, name + ": target_samples",
          "must be in [4, 10000] (got " + std::to_string(o.target_samples) + ")", "use the default 50");
  require(o.candidates_per_sample >= 1, name + ": candidates_per_sample", "must be >= 1",
          "use the default 30");
  require(o.cull_h >= 0 && o.cull_h < 0.5, name + ": cull_h",
          "must be in [0, 0.5) (got " + format_number(o.cull_h) + ")", "use the default 0.05");
  require(o.opening_offset >= 0 && o.opening_offset <= 2, name + ": opening_offset",
          "must be in [0, 2] (got " + format_number(o.opening_offset) + ")", "use 0.1 (the default)");
  require(o.support_margin > 0 && std::isfinite(o.support_margin), name + ": support_margin", "must be > 0",
          "use the default 1");
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

  const Rigid3d frame = bone_frame(part.bone_start, part.bone_end);
  std::vector<Vec3d> v(part.vertices.size());
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = frame.apply_inverse(part.vertices[i]);
  const int nv = int(v.size());

  std::vector<Vec3d> vn(v.size());
  std::vector<double> cum(part.triangles.size());
  double area = 0;
  for (std::size_t t = 0; t < part.triangles.size(); ++t) {
    const auto& tri = part.triangles[t];
    for (int k = 0; k < 3; ++k)
      if (tri[k] < 0 || tri[k] >= nv)
        require(false, name + ": triangle " + std::to_string(t),
                "indexes vertex " + std::to_string(tri[k]) + " of " + std::to_string(nv), "fix the indices");
    const Vec3d n = cross(v[tri[1]] - v[tri[0]], v[tri[2]] - v[tri[0]]);
    for (int k = 0; k < 3; ++k) vn[tri[k]] += n;
    area += 0.5 * norm(n);
    cum[t] = area;
  }
  require(area > 0, name, "the sub-mesh has zero area", "give the part real triangles");

  // Candidates: area-weighted uniform points, culled by the planes of eq. 2.
  SplitMix rng{o.seed};
  const std::size_t ncand = std::size_t(o.target_samples) * std::size_t(o.candidates_per_sample);
  std::vector<HrbfSample> cand;
  cand.reserve(ncand);
  for (std::size_t c = 0; c < ncand; ++c) {
    const double pick = rng.uniform() * area;
    const std::size_t t =
        std::min(std::size_t(std::lower_bound(cum.begin(), cum.end(), pick) - cum.begin()), cum.size() - 1);
    const double su = std::sqrt(rng.uniform()), w = rng.uniform();
    const double b0 = 1 - su, b1 = su * (1 - w), b2 = su * w;
    const auto& tri = part.triangles[t];
    const Vec3d p = v[tri[0]] * b0 + v[tri[1]] * b1 + v[tri[2]] * b2;
    const double u = p.z / len;
    if (!(u > o.cull_h && u < 1 - o.cull_h)) continue;
    Vec3d n = vn[tri[0]] * b0 + vn[tri[1]] * b1 + vn[tri[2]] * b2;
    if (!(norm(n) > 0)) n = cross(v[tri[1]] - v[tri[0]], v[tri[2]] - v[tri[0]]);
    if (!(norm(n) > 0)) continue;
    cand.push_back({p, n / norm(n)});
  }
  require(cand.size() >= 4, name, "fewer than 4 surface samples survive the culling planes",
          "check that the sub-mesh surrounds its bone, or lower PartFitOptions::cull_h");

  // Poisson-disk selection: bisect the disk radius so that greedy dart throwing keeps about
  // target_samples candidates (the smallest count >= target found, else the largest).
  const std::size_t target = std::size_t(o.target_samples);
  std::vector<std::size_t> best;
  if (cand.size() <= target) {
    for (std::size_t i = 0; i < cand.size(); ++i) best.push_back(i);
  } else {
    const double kept_area = area * double(cand.size()) / double(ncand);
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
  }

  FittedPart out;
  out.local_to_world = frame;
  for (std::size_t i : best) out.samples.push_back(cand[i]);
  // Orientation: outward normals point away from the bone on average. An inward-oriented mesh
  // would give an inverted field (inside < 0.5): refuse it rather than fit it.
  double outward = 0;
  for (const HrbfSample& s : out.samples) {
    const Vec3d radial = s.position - Vec3d{0, 0, std::clamp(s.position.z, 0.0, len)};
    const double rl = norm(radial);
    if (rl > 0) outward += dot(s.normal, radial) / rl;
  }
  require(outward > 0, name, "the triangles are oriented inward (normals point towards the bone)",
          "flip the triangle winding of this part");
  // Closure points (2013 §4.1, Fig. 3): on the axis, s beyond each joint, normal outward.
  auto nearest = [&](const Vec3d& joint) {
    double s = std::numeric_limits<double>::infinity();
    for (const Vec3d& p : v) s = std::min(s, norm(p - joint));
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
  auto hrbf = std::make_shared<const Hrbf>(out.samples, o.hrbf, name);
  Box3d sbox;
  for (const HrbfSample& s : hrbf->samples()) {
    sbox.extend(s.position);
    out.r = std::max(out.r, segment_distance(s.position, len));
  }
  // Support box: samples grown by margin × r, grown further (up to 8×) until d >= r on all its
  // faces (d is not a true distance: |∇d| may fall below 1 away from the samples).
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
  if (o.sample_grid) {
    GridFieldOptions go;
    go.resolution = o.grid_resolution;
    out.grid = std::make_shared<const GridField>(*out.local, out.local->support(), go);
  }
  return out;
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
