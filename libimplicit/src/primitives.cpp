// SPDX-License-Identifier: MIT
#include "isokit/implicit/primitives.h"

#include <cmath>

#include "isokit/core/error.h"

namespace isokit::implicit {
namespace {

bool finite(const Vec3f& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

void check_radii(const char* what, float radius, float support_width) {
  require(std::isfinite(radius) && radius > 0.f, std::string(what) + " radius",
          "must be finite and > 0 (got " + format_number(radius) + ")", "pass a positive radius");
  require(std::isfinite(support_width) && support_width > 0.f, std::string(what) + " support_width",
          "must be finite and > 0 (got " + format_number(support_width) + ")",
          "pass a positive support width, or 0 for the default (= radius)");
}

Box3f grown(Box3f b, float by) {
  b.lo = b.lo - Vec3f{by, by, by};
  b.hi = b.hi + Vec3f{by, by, by};
  return b;
}

}  // namespace

SphereField::SphereField(const Vec3f& center, float radius, float support_width) {
  require(finite(center), "SphereField center", "must be finite", "pass finite coordinates");
  if (support_width == 0.f) support_width = radius;
  check_radii("SphereField", radius, support_width);
  params_ = {center, radius, support_width};
}

Box3f SphereField::support() const {
  Box3f b;
  b.extend(params_.center);
  return grown(b, params_.radius + params_.support_width);
}

CapsuleField::CapsuleField(const Vec3f& a, const Vec3f& b, float radius, float support_width) {
  require(finite(a) && finite(b), "CapsuleField endpoints", "must be finite", "pass finite coordinates");
  if (support_width == 0.f) support_width = radius;
  check_radii("CapsuleField", radius, support_width);
  params_ = {a, b, radius, support_width};
}

Box3f CapsuleField::support() const {
  Box3f box;
  box.extend(params_.a);
  box.extend(params_.b);
  return grown(box, params_.radius + params_.support_width);
}

}  // namespace isokit::implicit
