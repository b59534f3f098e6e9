// SPDX-License-Identifier: MIT
// Software rasterizer for offscreen skin renders: deferred shading over a supersampled z-buffer.
// Triangles are binned into bands of pixel rows; each band (in parallel) is z-buffered with its
// triangles in input order, then each covered sample is shaded once from the winning triangle and
// the samples are averaged into pixels. The result does not depend on the thread count.
#include "isokit/skinning/render.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "isokit/core/error.h"
#include "isokit/core/math.h"
#include "isokit/core/parallel.h"
#include "isokit/skinning/metrics.h"
#include "metrics/metrics_check.h"

namespace isokit::skinning {
namespace {

constexpr int kBandPixelRows = 8;  // pixel rows per band (rasterized and shaded together)

bool finite(const Eigen::Vector3d& v) {
  return v.allFinite();
}

double cube(double x) {
  return x * x * x;
}

/// `floor(v)` or `ceil(v)` clamped to [lo, hi] without overflowing the int conversion.
int floor_in(double v, int lo, int hi) {
  return static_cast<int>(std::clamp(std::floor(v), double(lo), double(hi)));
}
int ceil_in(double v, int lo, int hi) {
  return static_cast<int>(std::clamp(std::ceil(v), double(lo), double(hi)));
}

void check_options(const RenderOptions& o) {
  require(o.width >= 1 && o.width <= 16384 && o.height >= 1 && o.height <= 16384,
          "RenderOptions width/height",
          "must be in [1, 16384] (got " + std::to_string(o.width) + "x" + std::to_string(o.height) + ")",
          "pass a positive image size");
  require(o.supersample >= 1 && o.supersample <= 8, "RenderOptions.supersample",
          "must be in [1, 8] (got " + std::to_string(o.supersample) + ")", "use 1 (none) to 4");
  require(finite(o.view_direction) && o.view_direction.norm() > 0, "RenderOptions.view_direction",
          "must be a finite non-zero vector", "pass the direction the camera looks along");
  require(
      finite(o.up) && o.up.norm() > 0 && o.view_direction.normalized().cross(o.up.normalized()).norm() > 1e-6,
      "RenderOptions.up", "must be finite, non-zero and not parallel to view_direction",
      "pass an up vector across the view, e.g. (0, 1, 0) for a view along -z");
  require(o.field_of_view_deg > 0 && o.field_of_view_deg < 180, "RenderOptions.field_of_view_deg",
          "must be in (0, 180) (got " + format_number(o.field_of_view_deg) + ")", "use e.g. 30");
  require(o.margin >= 0 && o.margin < 1, "RenderOptions.margin",
          "must be in [0, 1) (got " + format_number(o.margin) + ")", "use e.g. 0.05");
  require(o.wire_width_px >= 0 && std::isfinite(o.wire_width_px), "RenderOptions.wire_width_px",
          "must be finite and >= 0 (got " + format_number(o.wire_width_px) + ")", "use e.g. 1");
}

std::uint8_t to_byte(double v) {
  return static_cast<std::uint8_t>(std::clamp(v, 0.0, 1.0) * 255.0 + 0.5);
}

/// Edge function: twice the signed area of (a, b, p) in sample space (y down).
inline double edge(double ax, double ay, double bx, double by, double px, double py) {
  return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}

}  // namespace

Eigen::Vector3d Camera::project(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d d = p - eye;
  const double z = d.dot(forward);
  if (!(z > 0)) return {0, 0, z};
  return {0.5 * width + focal_px * d.dot(right) / z, 0.5 * height - focal_px * d.dot(up) / z, z};
}

Camera frame_camera(const RenderOptions& o, const Eigen::AlignedBox3d& box) {
  check_options(o);
  require(!box.isEmpty() && finite(box.min()) && finite(box.max()), "frame_camera: box",
          "must be a finite, non-empty box", "pass the bounding box of the meshes to frame");
  Camera cam;
  cam.width = o.width;
  cam.height = o.height;
  cam.forward = o.view_direction.normalized();
  cam.right = cam.forward.cross(o.up).normalized();
  cam.up = cam.right.cross(cam.forward);
  cam.focal_px = 0.5 * o.height / std::tan(0.5 * o.field_of_view_deg * kPi / 180);
  const Eigen::Vector3d centre = box.center();
  const double diag = box.diagonal().norm();
  const double half_w = (1 - o.margin) * 0.5 * o.width;
  const double half_h = (1 - o.margin) * 0.5 * o.height;
  // Smallest distance along -forward from which every corner projects inside the shrunk image
  // and lies in front of the camera: focal |x| / (d + z) <= half_w, same for y, d + z > 0.
  double dist = diag > 0 ? 0 : 1;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d c = box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(k)) - centre;
    const double x = std::abs(c.dot(cam.right)), y = std::abs(c.dot(cam.up)), z = c.dot(cam.forward);
    dist = std::max({dist, cam.focal_px * x / half_w - z, cam.focal_px * y / half_h - z, 0.01 * diag - z});
  }
  cam.eye = centre - dist * cam.forward;
  return cam;
}

namespace {

/// Rejects colour arrays whose row count matches neither nothing nor the mesh.
void check_colors(const track::Positions& positions, const track::Triangles& triangles,
                  const RenderOptions& o) {
  const auto nv = static_cast<std::size_t>(positions.rows());
  const auto nf = static_cast<std::size_t>(triangles.rows());
  require(o.vertex_colors.rows() == 0 || o.vertex_colors.rows() == positions.rows(),
          "RenderOptions.vertex_colors",
          "must have one row per vertex (" + std::to_string(nv) + ", got " +
              std::to_string(o.vertex_colors.rows()) + ")",
          "pass #V rows or none");
  require(o.face_colors.rows() == 0 || o.face_colors.rows() == triangles.rows(), "RenderOptions.face_colors",
          "must have one row per triangle (" + std::to_string(nf) + ", got " +
              std::to_string(o.face_colors.rows()) + ")",
          "pass #F rows or none");
}

/// The mesh as the camera sees it, and the lights: what shading a sample reads.
struct Scene {
  Scene(const track::Triangles& t, const RenderOptions& options, const Camera& camera)
      : triangles(t), o(options), cam(camera) {}

  const track::Triangles& triangles;
  const RenderOptions& o;
  Camera cam;
  int ss{1};                            ///< supersampling factor
  std::vector<Eigen::Vector3d> world;   ///< vertices, double
  std::vector<Eigen::Vector3d> screen;  ///< vertices in sample space: (x, y, 1/z)
  std::vector<std::uint8_t> valid;      ///< in front of the near plane and finite
  std::vector<Eigen::Vector3d> face_n;  ///< unit face normals
  std::vector<Eigen::Vector3d> vert_n;  ///< unit vertex normals (smooth shading only)
  Eigen::Vector3d key, head;            ///< light directions
  double half_wire{0};                  ///< half the wire width, in samples

  std::size_t corner(std::size_t f, int c) const {
    return static_cast<std::size_t>(triangles(static_cast<Eigen::Index>(f), c));
  }
};

/// Stage 1: vertices in sample space `(x, y, 1/z)`; invalid behind the near plane or non-finite.
void project_vertices(const track::Positions& positions, double near, Scene& s) {
  const auto nv = static_cast<std::size_t>(positions.rows());
  s.world.resize(nv);
  s.screen.resize(nv);
  s.valid.resize(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    s.world[v] = positions.row(static_cast<Eigen::Index>(v)).cast<double>().transpose();
    const Eigen::Vector3d p = s.cam.project(s.world[v]);
    s.valid[v] = finite(s.world[v]) && p.z() > near;
    s.screen[v] = {p.x() * s.ss, p.y() * s.ss, s.valid[v] ? 1 / p.z() : 0};
  }
}

/// Stage 2: face normals (area-weighted before normalising) and, for smooth shading, vertex
/// normals.
void compute_normals(Scene& s) {
  const std::size_t nv = s.world.size();
  const auto nf = static_cast<std::size_t>(s.triangles.rows());
  s.face_n.resize(nf);
  for (std::size_t f = 0; f < nf; ++f)
    s.face_n[f] = (s.world[s.corner(f, 1)] - s.world[s.corner(f, 0)])
                      .cross(s.world[s.corner(f, 2)] - s.world[s.corner(f, 0)]);
  if (s.o.shading == Shading::Smooth) {
    s.vert_n.assign(nv, Eigen::Vector3d::Zero());
    for (std::size_t f = 0; f < nf; ++f)
      if (s.face_n[f].allFinite())
        for (int c = 0; c < 3; ++c) s.vert_n[s.corner(f, c)] += s.face_n[f];
    for (auto& n : s.vert_n) n.normalize();  // zero stays zero
  }
  for (auto& n : s.face_n) n.normalize();
}

/// Deferred shading of one covered sample at `(px, py)` from its triangle `f`: perspective-correct
/// interpolation, Lambert (key + head light) over an ambient floor, rim, optional wireframe.
Eigen::Vector3d shade(const Scene& s, int f, double px, double py) {
  const RenderOptions& o = s.o;
  const auto fs = static_cast<std::size_t>(f);
  const std::size_t v[3] = {s.corner(fs, 0), s.corner(fs, 1), s.corner(fs, 2)};
  const Eigen::Vector3d& p0 = s.screen[v[0]];
  const Eigen::Vector3d& p1 = s.screen[v[1]];
  const Eigen::Vector3d& p2 = s.screen[v[2]];
  const double area = edge(p0.x(), p0.y(), p1.x(), p1.y(), p2.x(), p2.y());
  const double e[3] = {edge(p1.x(), p1.y(), p2.x(), p2.y(), px, py),
                       edge(p2.x(), p2.y(), p0.x(), p0.y(), px, py),
                       edge(p0.x(), p0.y(), p1.x(), p1.y(), px, py)};
  // Perspective-correct barycentrics.
  double q[3] = {e[0] / area * p0.z(), e[1] / area * p1.z(), e[2] / area * p2.z()};
  const double qs = q[0] + q[1] + q[2];
  for (double& x : q) x /= qs;
  const Eigen::Vector3d pos = q[0] * s.world[v[0]] + q[1] * s.world[v[1]] + q[2] * s.world[v[2]];
  const bool back = s.face_n[fs].dot(s.cam.eye - s.world[v[0]]) < 0;
  Eigen::Vector3d n = s.face_n[fs];
  if (o.shading == Shading::Smooth) {
    const Eigen::Vector3d sn = q[0] * s.vert_n[v[0]] + q[1] * s.vert_n[v[1]] + q[2] * s.vert_n[v[2]];
    if (sn.norm() > 1e-12) n = sn.normalized();
  }
  if (back) n = -n;
  Eigen::Vector3d color;
  if (o.face_colors.rows() > 0) {
    color = o.face_colors.row(f).cast<double>().transpose();
  } else if (o.vertex_colors.rows() > 0) {
    color = Eigen::Vector3d::Zero();
    for (int c = 0; c < 3; ++c)
      color += q[c] * o.vertex_colors.row(static_cast<Eigen::Index>(v[c])).cast<double>().transpose();
  } else {
    color = (back ? o.back_color : o.base_color).cast<double>();
  }
  const Eigen::Vector3d to_eye = (s.cam.eye - pos).normalized();
  const double diffuse = 0.7 * std::max(0.0, n.dot(s.key)) + 0.3 * std::max(0.0, n.dot(s.head));
  const double rim = o.rim * cube(1 - std::clamp(n.dot(to_eye), 0.0, 1.0));
  Eigen::Vector3d c = color * (o.ambient + (1 - o.ambient) * diffuse) + Eigen::Vector3d::Constant(rim);
  if (o.wireframe) {
    const double len[3] = {std::hypot(p2.x() - p1.x(), p2.y() - p1.y()),
                           std::hypot(p0.x() - p2.x(), p0.y() - p2.y()),
                           std::hypot(p1.x() - p0.x(), p1.y() - p0.y())};
    double d = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k)
      if (len[k] > 0) d = std::min(d, std::abs(e[k]) / len[k]);
    if (d <= s.half_wire) c = o.wire_color.cast<double>();
  }
  return c.cwiseMax(0.0).cwiseMin(1.0);
}

/// Stage 3: triangles (all corners valid, touching the image) binned into bands of
/// `band_rows` sample rows, in input order within each band.
std::vector<std::vector<int>> bin_triangles(const Scene& s, int sw, int sh, int band_rows) {
  const auto nf = static_cast<std::size_t>(s.triangles.rows());
  const int bands = (sh + band_rows - 1) / band_rows;
  std::vector<std::vector<int>> band_faces(static_cast<std::size_t>(bands));
  for (std::size_t f = 0; f < nf; ++f) {
    const std::size_t a = s.corner(f, 0), b = s.corner(f, 1), c = s.corner(f, 2);
    if (!s.valid[a] || !s.valid[b] || !s.valid[c]) continue;
    const double ymin = std::min({s.screen[a].y(), s.screen[b].y(), s.screen[c].y()});
    const double ymax = std::max({s.screen[a].y(), s.screen[b].y(), s.screen[c].y()});
    const double xmin = std::min({s.screen[a].x(), s.screen[b].x(), s.screen[c].x()});
    const double xmax = std::max({s.screen[a].x(), s.screen[b].x(), s.screen[c].x()});
    if (ymax < 0 || ymin > sh || xmax < 0 || xmin > sw) continue;
    const int b0 = floor_in(ymin, 0, sh - 1) / band_rows;
    const int b1 = floor_in(ymax, 0, sh - 1) / band_rows;
    for (int band = b0; band <= b1; ++band)
      band_faces[static_cast<std::size_t>(band)].push_back(static_cast<int>(f));
  }
  return band_faces;
}

/// Stage 4: z-buffers the sample rows `[row0, row1)` (`sw` samples each) with `faces` in order:
/// per sample the largest 1/z (`depth`, 0 = empty) and its triangle (`face_id`, -1 = none).
void zbuffer_band(const Scene& s, const std::vector<int>& faces, int row0, int row1, int sw,
                  std::vector<float>& depth, std::vector<int>& face_id) {
  std::fill(depth.begin(), depth.end(), 0.0f);
  std::fill(face_id.begin(), face_id.end(), -1);
  for (int f : faces) {
    const auto& p0 = s.screen[s.corner(static_cast<std::size_t>(f), 0)];
    const auto& p1 = s.screen[s.corner(static_cast<std::size_t>(f), 1)];
    const auto& p2 = s.screen[s.corner(static_cast<std::size_t>(f), 2)];
    const double area = edge(p0.x(), p0.y(), p1.x(), p1.y(), p2.x(), p2.y());
    if (!(std::abs(area) > 0)) continue;
    const double inv_area = 1 / area;
    // Samples at (i + 0.5, j + 0.5) inside the closed triangle.
    const int i0 = ceil_in(std::min({p0.x(), p1.x(), p2.x()}) - 0.5, 0, sw);
    const int i1 = floor_in(std::max({p0.x(), p1.x(), p2.x()}) - 0.5, -1, sw - 1);
    const int j0 = ceil_in(std::min({p0.y(), p1.y(), p2.y()}) - 0.5, row0, row1);
    const int j1 = floor_in(std::max({p0.y(), p1.y(), p2.y()}) - 0.5, row0 - 1, row1 - 1);
    for (int j = j0; j <= j1; ++j) {
      const double py = j + 0.5;
      for (int i = i0; i <= i1; ++i) {
        const double px = i + 0.5;
        const double w0 = edge(p1.x(), p1.y(), p2.x(), p2.y(), px, py) * inv_area;
        const double w1 = edge(p2.x(), p2.y(), p0.x(), p0.y(), px, py) * inv_area;
        const double w2 = 1 - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        const auto iz = static_cast<float>(w0 * p0.z() + w1 * p1.z() + w2 * p2.z());
        const std::size_t sample = static_cast<std::size_t>(j - row0) * sw + i;
        if (iz > depth[sample]) {
          depth[sample] = iz;
          face_id[sample] = f;
        }
      }
    }
  }
}

/// Stage 5: shades every sample of the rows `[row0, row1)` from its triangle (the background
/// where none) and averages them into the band's pixel rows of `image`.
void resolve_band(const Scene& s, const std::vector<int>& face_id, int row0, int row1, int sw, Image& image) {
  const RenderOptions& o = s.o;
  const int ss = s.ss;
  const Eigen::Vector3d background = o.background.cast<double>();
  const double inv_samples = 1.0 / (ss * ss);
  for (int y = row0 / ss; y < row1 / ss; ++y)
    for (int x = 0; x < o.width; ++x) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int sj = 0; sj < ss; ++sj)
        for (int si = 0; si < ss; ++si) {
          const int j = y * ss + sj, i = x * ss + si;
          const int f = face_id[static_cast<std::size_t>(j - row0) * sw + i];
          sum += f < 0 ? background : shade(s, f, i + 0.5, j + 0.5);
        }
      std::uint8_t* px = &image.rgba[(static_cast<std::size_t>(y) * o.width + x) * 4];
      for (int c = 0; c < 3; ++c) px[c] = to_byte(sum[c] * inv_samples);
      px[3] = 255;
    }
}

}  // namespace

Image render_mesh(const track::Positions& positions, const track::Triangles& triangles,
                  const RenderOptions& o) {
  check_options(o);
  detail::check_triangles(triangles, positions.rows(), "render_mesh");
  check_colors(positions, triangles, o);

  Image image;
  image.width = o.width;
  image.height = o.height;
  image.rgba.resize(static_cast<std::size_t>(o.width) * o.height * 4);
  const Eigen::AlignedBox3d box = o.frame.isEmpty() ? bounding_box(positions) : o.frame;
  if (box.isEmpty() || !finite(box.min()) || !finite(box.max())) {  // nothing to frame
    for (std::size_t i = 0; i < image.rgba.size(); i += 4) {
      for (int c = 0; c < 3; ++c) image.rgba[i + c] = to_byte(o.background[c]);
      image.rgba[i + 3] = 255;
    }
    return image;
  }
  Scene s(triangles, o, frame_camera(o, box));
  s.ss = o.supersample;
  const int sw = o.width * s.ss, sh = o.height * s.ss;
  project_vertices(positions, 1e-3 * (s.cam.eye - box.center()).norm(), s);
  compute_normals(s);
  s.key = (-0.35 * s.cam.right + 0.55 * s.cam.up - 0.75 * s.cam.forward).normalized();
  s.head = -s.cam.forward;
  s.half_wire = 0.5 * o.wire_width_px * s.ss;  // in samples

  // Each band: z-buffer its samples (triangles in input order), then shade and average them
  // into its pixel rows. Bands are independent, so threads cannot change the result.
  const int band_rows = kBandPixelRows * s.ss;
  const std::vector<std::vector<int>> band_faces = bin_triangles(s, sw, sh, band_rows);
  parallel_for(band_faces.size(), 1, [&](std::size_t band_begin, std::size_t band_end) {
    std::vector<float> depth(static_cast<std::size_t>(band_rows) * sw);  // 1/z, 0 = empty
    std::vector<int> face_id(depth.size());
    for (std::size_t band = band_begin; band < band_end; ++band) {
      const int row0 = static_cast<int>(band) * band_rows;
      const int row1 = std::min(sh, row0 + band_rows);
      zbuffer_band(s, band_faces[band], row0, row1, sw, depth, face_id);
      resolve_band(s, face_id, row0, row1, sw, image);
    }
  });
  return image;
}

}  // namespace isokit::skinning
