// SPDX-License-Identifier: MIT
#include "field_eval.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "isokit/core/error.h"
#include "isokit/core/mesh_quality.h"
#include "isokit/core/parallel.h"
#include "mesh_geometry.h"
#include "points.h"

namespace isokit::track {

namespace detail {

void eval_field(const FieldFunction& field, const Vec3f* pts, std::size_t n, float* values, Vec3f* grads,
                std::uint8_t* contact, std::size_t grain) {
  parallel_for(n, grain, [&](std::size_t b, std::size_t e) {
    std::fill(contact + b, contact + e, std::uint8_t{0});
    field(pts + b, e - b, values + b, grads + b, contact + b);
  });
}

void refresh_values(const FieldFunction& field, const std::vector<Vec3f>& pts, const std::vector<int>& redo,
                    std::size_t grain, std::vector<float>& values, VertexFlags& flags) {
  std::vector<Vec3f> p(redo.size()), g(redo.size());
  std::vector<float> v(redo.size());
  std::vector<std::uint8_t> c(redo.size());
  for (std::size_t a = 0; a < redo.size(); ++a) p[a] = pts[redo[a]];
  eval_field(field, p.data(), p.size(), v.data(), g.data(), c.data(), grain);
  for (std::size_t a = 0; a < redo.size(); ++a) {
    values[redo[a]] = v[a];
    if (c[a]) flags.contact[redo[a]] = 1;
  }
}

void test_inverted(const FieldFunction& field, const std::vector<Vec3f>& pts, const Triangles& triangles,
                   const std::vector<int>& tris, std::size_t grain, std::vector<std::uint8_t>& inverted) {
  const std::size_t m = tris.size();
  std::vector<Vec3f> cen(m), g(m);
  std::vector<float> v(m);
  std::vector<std::uint8_t> c(m);
  auto corner = [&](std::size_t a, int k) { return pts[triangles(tris[a], k)]; };
  for (std::size_t a = 0; a < m; ++a) cen[a] = triangle_centroid(corner(a, 0), corner(a, 1), corner(a, 2));
  eval_field(field, cen.data(), m, v.data(), g.data(), c.data(), grain);
  for (std::size_t a = 0; a < m; ++a)
    inverted[static_cast<std::size_t>(tris[a])] =
        is_inverted(triangle_normal(corner(a, 0), corner(a, 1), corner(a, 2)), g[a]) ? 1 : 0;
}

std::vector<std::uint8_t> inverted_triangles(const FieldFunction& field, const std::vector<Vec3f>& pts,
                                             const Triangles& triangles, std::size_t grain,
                                             const std::vector<int>* candidates) {
  const std::size_t nf = static_cast<std::size_t>(triangles.rows());
  std::vector<int> all;
  if (!candidates) {
    all.resize(nf);
    for (std::size_t f = 0; f < nf; ++f) all[f] = static_cast<int>(f);
    candidates = &all;
  }
  std::vector<std::uint8_t> out(nf, 0);
  test_inverted(field, pts, triangles, *candidates, grain, out);
  return out;
}

std::vector<std::uint8_t> free_vertices(const FieldFunction& field, const std::vector<Vec3f>& rest,
                                        const Triangles& triangles, const TrackerOptions& options) {
  const std::size_t n = rest.size();
  std::vector<std::uint8_t> out(n, 0);
  if (options.free_vertex_angle_deg >= 180.f) return out;
  std::vector<float> values(n);
  std::vector<Vec3f> grads(n);
  std::vector<std::uint8_t> contact(n);
  eval_field(field, rest.data(), n, values.data(), grads.data(), contact.data(), options.grain);
  const std::vector<Vec3f> normals = area_weighted_normals(rest, triangles);
  const float cos_max = std::cos(options.free_vertex_angle_deg * kPiF / 180.f);
  const float min_g2 = options.min_gradient * options.min_gradient;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3f& g = grads[i];
    const float n2 = squared_norm(normals[i]), g2 = squared_norm(g);
    if (!(n2 > 0.f)) continue;  // no triangle: nothing to compare with
    // Inward normal -n against the inward field direction g: cos = -n·g / (|n| |g|).
    const bool usable = finite(g) && g2 > min_g2;
    out[i] = !usable || -dot(normals[i], g) < cos_max * std::sqrt(n2 * g2) ? 1 : 0;
  }
  return out;
}

}  // namespace detail

std::vector<float> sample_iso_values(const FieldFunction& field, const Positions& positions) {
  const std::vector<Vec3f> pts = detail::to_points(positions, "positions");
  const std::size_t n = pts.size();
  std::vector<float> values(n);
  std::vector<Vec3f> grads(n);
  std::vector<std::uint8_t> contact(n);
  detail::eval_field(field, pts.data(), n, values.data(), grads.data(), contact.data(), 0);
  for (std::size_t i = 0; i < n; ++i)
    require(std::isfinite(values[i]), "field value at vertex " + std::to_string(i), "is not finite",
            "check the field");
  return values;
}

}  // namespace isokit::track
