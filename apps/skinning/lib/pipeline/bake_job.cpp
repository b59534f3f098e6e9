// SPDX-License-Identifier: MIT
#include "isokit/skinning/bake_job.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "isokit/core/error.h"
#include "isokit/skinning/rig_io.h"
#if defined(ISOKIT_HAVE_CUDA)
#include "isokit/implicit/cuda/device_eval.h"
#endif

namespace isokit::skinning {

namespace {

std::string bend_description(const AnimationRequest& request, double max_step_rad) {
  std::string text;
  for (const std::string& b : request.bends) text += (text.empty() ? "--bend " : " --bend ") + b;
  text += " (" + std::to_string(request.frames) + " frames)";
  if (max_step_rad > 0) text += ", tracking sub-steps <= " + format_number(max_step_rad) + " rad";
  return text;
}

void make_folder(const std::filesystem::path& dir, const std::string& path) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  require(!ec, path, "cannot create the folder '" + dir.string() + "' (" + ec.message() + ")",
          "choose a path in a writable folder");
}

void make_parent(const std::string& path) {
  const std::filesystem::path p(path);
  if (p.has_parent_path()) make_folder(p.parent_path(), path);
}

std::string frame_ply_name(std::size_t frame) {
  char name[64];
  std::snprintf(name, sizeof name, "/frame_%04zu.ply", frame);
  return name;
}

}  // namespace

void check_animation_request(const AnimationRequest& request) {
  const int sources = int(!request.clip.empty() || !request.clip_file.empty()) + int(!request.bends.empty()) +
                      int(!request.pose_script.empty());
  if (sources > 1) throw InputError("bake: give at most one of --clip, --bend or --pose-script");
  require(request.frames >= 3 && request.frames <= 100000, "bake: --frames",
          "must be in [3, 100000] (got " + std::to_string(request.frames) + ")",
          "give the number of frames of the bend (rest, peak, rest), e.g. 31");
}

namespace {

std::string joined(const std::vector<std::string>& names) {
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
  return list;
}

std::string default_clip(const Rig& rig) {
  if (rig.clips.size() == 1) return rig.clips.front().name;
  std::vector<std::string> names;
  for (const Clip& c : rig.clips) names.push_back(c.name);
  const std::string list = joined(names);
  require(!rig.clips.empty(), "bake: " + rig.name, "has no clip to play",
          "give --bend JOINT:AXIS:DEGREES or --pose-script P.json");
  throw InputError("bake: " + rig.name + ": has " + std::to_string(rig.clips.size()) +
                   " clips; choose one with --clip NAME (" + list + "), or give --bend or --pose-script");
}

// A clip of an animation file retargeted onto `rig`; the joints left unmatched as warnings.
Animation clip_file_animation(const Rig& rig, const AnimationRequest& request) {
  LoadOptions o;
  o.fps = request.fps;
  o.skeleton_only = true;
  const Rig source = load_rig(request.clip_file, o);
  const std::string name = request.clip.empty() ? default_clip(source) : request.clip;
  const auto clip =
      std::find_if(source.clips.begin(), source.clips.end(), [&](const Clip& c) { return c.name == name; });
  std::vector<std::string> names;
  for (const Clip& c : source.clips) names.push_back(c.name);
  require(clip != source.clips.end(), request.clip_file + ": --clip " + name, "no clip of that name",
          "choose one of: " + joined(names));
  RetargetReport report;
  Animation a;
  a.poses = retarget_clip(source, *clip, rig, &report).local;
  a.description = "clip " + name + " of " + request.clip_file + " (retargeted by joint name)";
  if (!report.unmatched_target.empty())
    a.warnings.push_back(std::to_string(report.unmatched_target.size()) +
                         " joint(s) of the rig have no namesake in " + request.clip_file +
                         " and stay rigid with their parent: " + joined(report.unmatched_target));
  if (!report.unmatched_source.empty())
    a.warnings.push_back(std::to_string(report.unmatched_source.size()) + " joint(s) of " +
                         request.clip_file +
                         " match no joint of the rig and are ignored: " + joined(report.unmatched_source));
  return a;
}

}  // namespace

Animation make_animation(const Rig& rig, const AnimationRequest& given, double max_step_rad) {
  check_animation_request(given);
  AnimationRequest request = given;
  if (!request.clip_file.empty()) return clip_file_animation(rig, request);
  if (request.clip.empty() && request.bends.empty() && request.pose_script.empty())
    request.clip = default_clip(rig);
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

Device device_from_string(const std::string& s) {
  if (s == "cpu") return Device::kCpu;
  if (s == "cuda") return Device::kCuda;
  throw InputError("--device: unknown device '" + s + "'; use cpu or cuda");
}

void check_device(Device device) {
  if (device == Device::kCpu) return;
#if defined(ISOKIT_HAVE_CUDA)
  if (!implicit::cuda::device_available())
    throw InputError(
        "--device cuda: no usable CUDA device (the CUDA runtime reports none); use --device cpu");
  throw InputError(
      "--device cuda: this build has no device tracker yet (only the device field evaluation; "
      "docs/skinning.md, \"Devices\"); use --device cpu");
#else
  throw InputError(
      "--device cuda: isokit-skin was built without the CUDA backend (nvcc was not found when it was "
      "configured); install the CUDA Toolkit and build again, or use --device cpu");
#endif
}

const BakeResult& main_result(const std::vector<BakeResult>& results, Method method) {
  for (const BakeResult& r : results)
    if (r.method == method) return r;
  throw InputError(std::string("bake: no result of method ") + to_string(method));
}

void check_bake_outputs(const BakeOutputs& outputs) {
  if (outputs.pc2.empty()) return;
  const std::string ext = std::filesystem::path(outputs.pc2).extension().string();
  require(ext == ".pc2" || ext == ".PC2", outputs.pc2, "extension must be .pc2",
          "name the point cache *.pc2");
  std::error_code ec;
  require(!std::filesystem::is_directory(outputs.pc2, ec), outputs.pc2, "is a folder",
          "give a file path such as out/bake.pc2");
}

std::vector<std::string> write_bake_outputs(const Rig& rig, const std::vector<BakeResult>& results,
                                            const BakeResult& main, const ReportContext& context,
                                            const std::vector<RenderView>& views,
                                            const BakeOutputs& outputs) {
  std::vector<std::string> written;
  check_bake_outputs(outputs);
  if (!outputs.glb.empty()) make_parent(outputs.glb);
  if (!outputs.metrics.empty()) make_parent(outputs.metrics);
  if (!outputs.pc2.empty()) make_parent(outputs.pc2);
  const std::string frames = " (" + std::to_string(main.frames.size()) + " frames)";
  if (!outputs.glb.empty()) {
    write_baked_glb(rig, main.frames, context.fps, outputs.glb);
    written.push_back(outputs.glb + frames);
  }
  if (!outputs.pc2.empty()) {
    write_pc2(rig, main.frames, outputs.pc2);
    written.push_back(outputs.pc2 + frames);
  }
  if (!outputs.metrics.empty()) {
    write_text_file(outputs.metrics, metrics_json(rig, results, context));
    written.push_back(outputs.metrics);
  }
  if (!outputs.render_dir.empty()) {
    const std::string& dir = outputs.render_dir;
    make_folder(dir, dir);
    write_comparison_sheet(rig, results, views, rig.name + " — " + context.animation,
                           dir + "/contact_sheet.png");
    for (const BakeResult& r : results)
      for (std::size_t k = 0; k < views.size(); ++k)
        write_frame_png(rig, r.frames.at(static_cast<std::size_t>(views[k].frame)), views[k],
                        dir + "/" + to_string(r.method) + "_view" + std::to_string(k) + ".png");
    written.push_back(dir + "/contact_sheet.png and one PNG per method and view");
  }
  if (!outputs.ply_dir.empty()) {
    make_folder(outputs.ply_dir, outputs.ply_dir);
    for (std::size_t f = 0; f < main.frames.size(); ++f)
      write_ply(outputs.ply_dir + frame_ply_name(f), main.frames[f], rig.triangles);
    written.push_back(outputs.ply_dir + "/frame_*.ply" + frames);
  }
  return written;
}

}  // namespace isokit::skinning
