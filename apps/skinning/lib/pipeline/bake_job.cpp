// SPDX-License-Identifier: MIT
#include "isokit/skinning/bake_job.h"

#include <cstdio>
#include <filesystem>

#include "isokit/core/error.h"
#include "isokit/skinning/rig_io.h"

namespace isokit::skinning {

namespace {

std::string bend_description(const AnimationRequest& request, double max_step_rad) {
  std::string text;
  for (const std::string& b : request.bends) text += (text.empty() ? "--bend " : " --bend ") + b;
  text += " (" + std::to_string(request.frames) + " frames)";
  if (max_step_rad > 0) text += ", tracking sub-steps <= " + format_number(max_step_rad) + " rad";
  return text;
}

void make_parent(const std::string& path) {
  const std::filesystem::path p(path);
  if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path());
}

std::string frame_ply_name(std::size_t frame) {
  char name[64];
  std::snprintf(name, sizeof name, "/frame_%04zu.ply", frame);
  return name;
}

}  // namespace

void check_animation_request(const AnimationRequest& request) {
  const int sources =
      int(!request.clip.empty()) + int(!request.bends.empty()) + int(!request.pose_script.empty());
  if (sources != 1) throw InputError("bake: give exactly one of --clip, --bend or --pose-script");
}

Animation make_animation(const Rig& rig, const AnimationRequest& request, double max_step_rad) {
  check_animation_request(request);
  Animation a;
  if (!request.bends.empty()) {
    for (const std::string& b : request.bends) a.bends.push_back(parse_bend(b, rig));
    a.poses = bend_animation(rig, a.bends, request.frames);
    a.description = bend_description(request, max_step_rad);
  } else if (!request.clip.empty()) {
    a.poses = clip_animation(rig, request.clip);
    a.description = "clip " + request.clip;
  } else {
    a.poses = pose_script_animation(rig, request.pose_script);
    a.description = "pose script " + request.pose_script;
  }
  return a;
}

std::vector<std::string> fit_warnings(const FittedRig& fitted, const SkinSetup& setup) {
  const Rig& rig = fitted.rig();
  std::vector<std::string> out;
  for (const BonePart& b : fitted.bones())
    if (!b.fitted && !b.error.empty() && b.error != "no vertices")
      out.push_back("joint '" + rig.joints[b.joint].name + "' has no primitive: " + b.error);
  if (setup.fold_repair_min_part_vertices <= 0) return out;
  int small = 0;
  const BonePart* smallest = nullptr;
  for (const BonePart& b : fitted.bones())
    if (b.fitted && b.vertices < setup.fold_repair_min_part_vertices) {
      ++small;
      if (!smallest || b.vertices < smallest->vertices) smallest = &b;
    }
  if (smallest)
    out.push_back(std::to_string(small) + " of " + std::to_string(fitted.fitted_count()) +
                  " primitives come from parts of fewer than " +
                  std::to_string(setup.fold_repair_min_part_vertices) + " vertices (smallest: '" +
                  rig.joints[smallest->joint].name + "', " + std::to_string(smallest->vertices) +
                  "): the mesh under-resolves these limbs; the implicit methods may thin or bloat them and "
                  "the fold repair leaves them out (docs/skinning.md, \"Low-poly rigs\"); --method dqs is "
                  "the safer choice for such a rig");
  return out;
}

int peak_frame(const std::vector<Pose>& poses) {
  int peak = 0;
  double best = -1;
  for (std::size_t f = 0; f < poses.size(); ++f) {
    const double a = max_rotation_between(poses[0], poses[f]);
    if (a > best) {
      best = a;
      peak = static_cast<int>(f);
    }
  }
  return peak;
}

const BakeResult& main_result(const std::vector<BakeResult>& results, Method method) {
  for (const BakeResult& r : results)
    if (r.method == method) return r;
  throw InputError(std::string("bake: no result of method ") + to_string(method));
}

std::vector<std::string> write_bake_outputs(const Rig& rig, const std::vector<BakeResult>& results,
                                            const BakeResult& main, const ReportContext& context,
                                            const std::vector<RenderView>& views, const BakeOutputs& outputs) {
  std::vector<std::string> written;
  if (!outputs.glb.empty()) make_parent(outputs.glb);
  if (!outputs.metrics.empty()) make_parent(outputs.metrics);
  if (!outputs.glb.empty()) {
    write_baked_glb(rig, main.frames, context.fps, outputs.glb);
    written.push_back(outputs.glb + " (" + std::to_string(main.frames.size()) + " frames)");
  }
  if (!outputs.metrics.empty()) {
    write_text_file(outputs.metrics, metrics_json(rig, results, context));
    written.push_back(outputs.metrics);
  }
  if (!outputs.render_dir.empty()) {
    const std::string& dir = outputs.render_dir;
    std::filesystem::create_directories(dir);
    write_comparison_sheet(rig, results, views, rig.name + " — " + context.animation, dir + "/contact_sheet.png");
    for (const BakeResult& r : results)
      for (std::size_t k = 0; k < views.size(); ++k)
        write_frame_png(rig, r.frames.at(static_cast<std::size_t>(views[k].frame)), views[k],
                        dir + "/" + to_string(r.method) + "_view" + std::to_string(k) + ".png");
    written.push_back(dir + "/contact_sheet.png and one PNG per method and view");
  }
  if (!outputs.ply_dir.empty()) {
    std::filesystem::create_directories(outputs.ply_dir);
    for (std::size_t f = 0; f < main.frames.size(); ++f)
      write_ply(outputs.ply_dir + frame_ply_name(f), main.frames[f], rig.triangles);
    written.push_back(outputs.ply_dir + "/frame_*.ply (" + std::to_string(main.frames.size()) + " frames)");
  }
  return written;
}

}  // namespace isokit::skinning
