// SPDX-License-Identifier: MIT
// The capsule fallback of a part whose HRBF cannot be bounded (fit.h, `fit_capsule`).
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "isokit/core/error.h"
#include "isokit/implicit/fit.h"
#include "isokit/implicit/fit_quality.h"
#include "isokit/implicit/primitives.h"

namespace isokit::implicit {

namespace {

/// The capsule on the segment `a`–`b` (world) whose radius is the median distance of the part's
/// vertices to the segment, sampled into a grid.
FittedPart capsule_on(const MeshPart& part, const Vec3d& a, const Vec3d& b, int resolution,
                      GridStorage storage) {
  FittedPart out;
  out.local_to_world = bone_frame(a, b);
  const double len = norm(b - a);
  std::vector<double> dist;
  for (const Vec3d& v : part.vertices) {
    const Vec3d l = out.local_to_world.apply_inverse(v);
    dist.push_back(norm(l - Vec3d{0, 0, std::clamp(l.z, 0.0, len)}));
  }
  std::nth_element(dist.begin(), dist.begin() + std::ptrdiff_t(dist.size() / 2), dist.end());
  const double radius = std::max(dist[dist.size() / 2], 1e-3 * len);
  out.r = radius;
  const CapsuleField capsule({0, 0, 0}, {0, 0, float(len)}, float(radius), float(radius));
  GridFieldOptions go;
  go.resolution = resolution;
  go.storage = storage;
  out.grid = std::make_shared<const GridField>(capsule, capsule.support(), go);
  return out;
}

/// The vertices' principal-axis segment: through their centroid, spanning their extent along
/// the axis less `shrink` at each end (at least 1e-3 of the extent long).
void principal_segment(const std::vector<Vec3d>& v, double shrink, Vec3d& a, Vec3d& b) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const Vec3d& p : v) c += Eigen::Vector3d(p.x, p.y, p.z);
  c /= double(v.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Vec3d& p : v)
    cov += (Eigen::Vector3d(p.x, p.y, p.z) - c) * (Eigen::Vector3d(p.x, p.y, p.z) - c).transpose();
  const Eigen::Vector3d axis = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(2);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const Vec3d& p : v) {
    const double u = (Eigen::Vector3d(p.x, p.y, p.z) - c).dot(axis);
    lo = std::min(lo, u);
    hi = std::max(hi, u);
  }
  const double mid = 0.5 * (lo + hi), half = std::max(0.5 * (hi - lo) - shrink, 5e-4 * (hi - lo));
  const Eigen::Vector3d pa = c + axis * (mid - half), pb = c + axis * (mid + half);
  a = {pa.x(), pa.y(), pa.z()};
  b = {pb.x(), pb.y(), pb.z()};
}

double score(const FittedPart& f, const MeshPart& part) {
  const FitDistances d = fit_distances(*f.field(), f.local_to_world, part.vertices, part.triangles);
  return d.to_surface_p95 + d.from_surface_p95;
}

}  // namespace

FittedPart fit_capsule(const MeshPart& part, const PartFitOptions& o) {
  const std::string& name = part.name;
  require(!part.vertices.empty(), name, "the sub-mesh is empty", "assign vertices to this bone");
  Box3d box;
  for (const Vec3d& p : part.vertices) {
    require(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z), name + ": vertex",
            "is not finite", "remove NaN/inf vertices");
    box.extend(p);
  }
  const double extent = norm(box.size());
  require(extent > 0, name, "all vertices lie on one point", "give the part real triangles");
  std::vector<FittedPart> tries;
  if (norm(part.bone_end - part.bone_start) > 1e-6 * extent)
    tries.push_back(capsule_on(part, part.bone_start, part.bone_end, o.grid_resolution, o.grid_storage));
  Vec3d a, b;
  principal_segment(part.vertices, 0, a, b);
  const double r0 = capsule_on(part, a, b, 8, o.grid_storage).r;  // the radius before shrinking the ends
  principal_segment(part.vertices, r0, a, b);
  tries.push_back(capsule_on(part, a, b, o.grid_resolution, o.grid_storage));
  if (tries.size() == 1 || part.triangles.empty()) return tries.back();
  return score(tries[0], part) <= score(tries[1], part) ? tries[0] : tries[1];
}

}  // namespace isokit::implicit
