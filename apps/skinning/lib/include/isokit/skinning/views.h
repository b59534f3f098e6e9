// SPDX-License-Identifier: MIT
/// \file
/// Pictures of bakes: close-up views of bent joints and the contact sheet comparing methods
/// side by side (rows = methods, columns = views). Triangles bounding a new interpenetration (a
/// region the skin encloses twice and did not at rest, self_overlap.h) are drawn red; triangles
/// that only cross another one (skins touching on a contact surface) yellow.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "isokit/skinning/animation.h"
#include "isokit/skinning/pipeline.h"

namespace isokit::skinning {

/// One picture of a bake: which frame, framed how.
struct RenderView {
  std::string label;                         ///< column label in the contact sheet
  int frame{0};                              ///< frame of the bake
  Eigen::AlignedBox3d box;                   ///< region to frame (empty: the whole mesh)
  Eigen::Vector3d view_direction{0, 0, -1};  ///< as RenderOptions::view_direction
  Eigen::Vector3d up{0, 1, 0};               ///< as RenderOptions::up
};

/// For each bend: a close-up of its joint at `frame` (the vertices of the joint and its parent
/// in the first result's frame), seen perpendicular to the bend plane; then the whole mesh.
std::vector<RenderView> bend_views(const Rig& rig, const std::vector<int>& partition,
                                   const std::vector<BendSpec>& bends, const std::vector<Pose>& poses,
                                   int frame, const BakeResult& reference);

/// Renders every result at every view into one labelled PNG (`cell` pixels per image).
void write_comparison_sheet(const Rig& rig, const std::vector<BakeResult>& results,
                            const std::vector<RenderView>& views, const std::string& title,
                            const std::string& path, int cell = 360);

/// Renders one frame of one result to a PNG.
void write_frame_png(const Rig& rig, const track::Positions& positions, const RenderView& view,
                     const std::string& path, int size = 720);

}  // namespace isokit::skinning
