// SPDX-License-Identifier: MIT
#include "isokit/skinning/views.h"

#include <cmath>

#include "isokit/core/error.h"
#include "isokit/skinning/metrics.h"
#include "isokit/skinning/render.h"

namespace isokit::skinning {

namespace {

RenderOptions options_for(const Rig& rig, const track::Positions& positions, const RenderView& v, int size) {
  RenderOptions o;
  o.width = o.height = size;
  o.view_direction = v.view_direction;
  o.up = v.up;
  o.frame = v.box;
  // Interpenetration in red (the triangles bounding a region the skin encloses twice that it did
  // not at rest); triangles that only cross another (touching skins) in yellow.
  SelfIntersectionDetails d;
  SelfIntersectionOptions so;
  so.max_pairs = 20000;
  const bool crossing = count_self_intersections(positions, rig.triangles, &d, so) > 0;
  const std::vector<int> overlap = new_overlap_triangles(rig.rest, positions, rig.triangles);
  if (crossing || !overlap.empty()) {
    o.face_colors = Colors::Constant(rig.triangles.rows(), 3, 0.f);
    o.face_colors.rowwise() = o.base_color.transpose();
    for (const auto& p : d.pairs)
      for (int f : p) o.face_colors.row(f) << 0.95f, 0.8f, 0.2f;
    for (int f : overlap) o.face_colors.row(f) << 0.9f, 0.1f, 0.1f;
  }
  return o;
}

}  // namespace

std::vector<RenderView> bend_views(const Rig& rig, const std::vector<int>& partition,
                                   const std::vector<BendSpec>& bends, const std::vector<Pose>& poses,
                                   int frame, const BakeResult& reference) {
  std::vector<RenderView> views;
  const track::Positions& p = reference.frames.at(static_cast<std::size_t>(frame));
  const std::vector<Affine> world = world_transforms(rig, poses.at(static_cast<std::size_t>(frame)));
  for (const BendSpec& b : bends) {
    RenderView v;
    v.frame = frame;
    v.label = rig.joints[b.joint].name + " " + std::to_string(static_cast<int>(std::lround(b.degrees))) + "°";
    const int parent = rig.joints[b.joint].parent;
    for (Eigen::Index i = 0; i < p.rows(); ++i)
      if (partition[i] == b.joint || partition[i] == parent)
        v.box.extend(Eigen::Vector3d(p.row(i).cast<double>()));
    // Look along the bend axis (in world space at the frame), so the fold is seen in profile.
    Eigen::Vector3d axis = world[b.joint].linear() * Eigen::Vector3d::Unit(b.axis);
    if (axis.norm() < 1e-9) axis = Eigen::Vector3d(0, 0, -1);
    v.view_direction = -axis.normalized();
    const Eigen::Vector3d bone = world[b.joint].linear() * Eigen::Vector3d::UnitY();
    v.up = bone.cross(v.view_direction).norm() > 1e-6 ? Eigen::Vector3d(-bone.normalized())
                                                      : Eigen::Vector3d(0, 1, 0);
    views.push_back(v);
  }
  RenderView all;
  all.frame = frame;
  all.label = "whole mesh";
  all.view_direction = Eigen::Vector3d(-0.35, -0.25, -1).normalized();
  views.push_back(all);
  return views;
}

void write_comparison_sheet(const Rig& rig, const std::vector<BakeResult>& results,
                            const std::vector<RenderView>& views, const std::string& title,
                            const std::string& path, int cell) {
  std::vector<std::vector<Image>> grid;
  std::vector<std::string> rows, cols;
  for (const RenderView& v : views) cols.push_back(v.label + " (frame " + std::to_string(v.frame) + ")");
  for (const BakeResult& r : results) {
    rows.push_back(to_string(r.method));
    std::vector<Image> row;
    for (const RenderView& v : views) {
      const track::Positions& p = r.frames.at(static_cast<std::size_t>(v.frame));
      row.push_back(render_mesh(p, rig.triangles, options_for(rig, p, v, cell)));
    }
    grid.push_back(std::move(row));
  }
  write_contact_sheet(grid, rows, cols, title, path);
}

void write_frame_png(const Rig& rig, const track::Positions& positions, const RenderView& view,
                     const std::string& path, int size) {
  write_png(render_mesh(positions, rig.triangles, options_for(rig, positions, view, size)), path);
}

}  // namespace isokit::skinning
