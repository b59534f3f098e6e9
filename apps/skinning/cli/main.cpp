// SPDX-License-Identifier: MIT
// isokit-skin: implicit skinning of rigged characters from the command line.
//   isokit-skin info RIG [--fit [--setup S.json]]
//   isokit-skin bake RIG --method M [--clip NAME | --bend J:AXIS:DEG ... | --pose-script P.json]
//                    [--frames N] [--fps N] [--max-step-rad R] [--setup S.json] --out OUT.glb
//                    [--metrics M.json] [--render DIR] [--ply DIR]
//   isokit-skin demo [--out DIR] [--vertices N] [--frames N] [--max-step-rad R]
// RIG is a glTF/FBX/COLLADA file or procedural:cylinder | procedural:finger |
// procedural:humanoid?vertices=13000.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <thread>

#include "isokit/core/error.h"
#include "isokit/skinning/animation.h"
#include "isokit/skinning/pipeline.h"
#include "isokit/skinning/report.h"
#include "isokit/skinning/rig_io.h"
#include "isokit/skinning/views.h"

using namespace isokit::skinning;

namespace {

/// Progress on stderr: one line per stage, updated in place.
Progress stderr_progress() {
  // Prints at every 10 % (and at the end) so logs stay short.
  return [](const std::string& stage, int done, int total) {
    if (total <= 0) return;
    const int step = std::max(1, total / 10);
    if (done % step != 0 && done != total) return;
    std::fprintf(stderr, "  %-28s %3d%% (%d/%d)\n", stage.c_str(), 100 * done / total, done, total);
    std::fflush(stderr);
  };
}

void print_info(const Rig& rig, const std::string& spec) {
  std::printf("rig: %s\n", spec.c_str());
  std::printf(
      "vertices (welded): %lld, triangles: %lld, output vertices: %zu\n",
      static_cast<long long>(rig.rest.rows()), static_cast<long long>(rig.triangles.rows()),
      rig.output.to_welded.empty() ? static_cast<std::size_t>(rig.rest.rows()) : rig.output.to_welded.size());
  int max_w = 0;
  double mean_w = 0;
  for (int v = 0; v + 1 < static_cast<int>(rig.weights.offsets.size()); ++v) {
    max_w = std::max(max_w, rig.weights.count(v));
    mean_w += rig.weights.count(v);
  }
  if (rig.rest.rows() > 0) mean_w /= double(rig.rest.rows());
  std::printf("weights per vertex: mean %.2f, max %d\n", mean_w, max_w);
  std::printf("joints: %zu\n", rig.joints.size());
  const std::vector<Eigen::Vector3d> p = rest_joint_positions(rig);
  for (std::size_t j = 0; j < rig.joints.size(); ++j)
    std::printf("  %3zu %-24s parent %3d  at (%.3f, %.3f, %.3f)\n", j, rig.joints[j].name.c_str(),
                rig.joints[j].parent, p[j].x(), p[j].y(), p[j].z());
  std::printf("clips: %zu\n", rig.clips.size());
  for (const Clip& c : rig.clips)
    std::printf("  %-24s %zu frames at %.1f fps\n", c.name.c_str(), c.local.size(), c.fps);
}

// `info --fit`: what the fit made of every joint.
void print_fit(const FittedRig& fitted) {
  const Rig& rig = fitted.rig();
  std::vector<PrimitiveCoverage> coverage(rig.joints.size());
  for (const PrimitiveCoverage& c : primitive_coverage(fitted))
    coverage[static_cast<std::size_t>(c.joint)] = c;
  std::printf("primitives: %d of %zu joints (fit %.2f s)\n", fitted.fitted_count(), rig.joints.size(),
              fitted.fit_seconds());
  std::printf("  %-24s %8s %7s %8s  %s\n", "joint", "vertices", "r", "closures",
              "inside at rest: related / unrelated");
  for (const BonePart& b : fitted.bones()) {
    const char* name = rig.joints[static_cast<std::size_t>(b.joint)].name.c_str();
    if (b.fitted) {
      const PrimitiveCoverage& c = coverage[static_cast<std::size_t>(b.joint)];
      std::printf("  %-24s %8d %7.3g %8d  %d / %d\n", name, b.vertices, b.fit.r, b.fit.closure_points,
                  c.related, c.unrelated);
    } else {
      std::printf("  %-24s no primitive: %s\n", name, b.error.c_str());
    }
  }
  std::printf(
      "  (related: vertices of the primitives next to it in the tree; unrelated: of any other\n"
      "   joint; many unrelated vertices mean a primitive reaching where it should not)\n");
}

int threads() {
  return static_cast<int>(std::thread::hardware_concurrency());
}

void make_parent(const std::string& path) {
  const std::filesystem::path p(path);
  if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path());
}

void write_outputs(const Rig& rig, const std::vector<BakeResult>& results, const BakeResult& main_result,
                   const ReportContext& ctx, const std::string& glb, const std::string& metrics,
                   const std::string& render_dir, const std::vector<RenderView>& views,
                   const std::string& ply_dir) {
  if (!glb.empty()) make_parent(glb);
  if (!metrics.empty()) make_parent(metrics);
  if (!glb.empty()) {
    write_baked_glb(rig, main_result.frames, ctx.fps, glb);
    std::fprintf(stderr, "  wrote %s (%zu frames)\n", glb.c_str(), main_result.frames.size());
  }
  if (!metrics.empty()) {
    write_text_file(metrics, metrics_json(rig, results, ctx));
    std::fprintf(stderr, "  wrote %s\n", metrics.c_str());
  }
  if (!render_dir.empty()) {
    std::filesystem::create_directories(render_dir);
    write_comparison_sheet(rig, results, views, rig.name + " — " + ctx.animation,
                           render_dir + "/contact_sheet.png");
    for (const BakeResult& r : results)
      for (std::size_t k = 0; k < views.size(); ++k)
        write_frame_png(rig, r.frames.at(static_cast<std::size_t>(views[k].frame)), views[k],
                        render_dir + "/" + to_string(r.method) + "_view" + std::to_string(k) + ".png");
    std::fprintf(stderr, "  wrote %s/contact_sheet.png and one PNG per method and view\n",
                 render_dir.c_str());
  }
  if (!ply_dir.empty()) {
    std::filesystem::create_directories(ply_dir);
    for (std::size_t f = 0; f < main_result.frames.size(); ++f) {
      char name[64];
      std::snprintf(name, sizeof name, "/frame_%04zu.ply", f);
      write_ply(ply_dir + name, main_result.frames[f], rig.triangles);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"isokit-skin: implicit skinning (2013) and iso-surface tracking (2014) of rigged characters"};
  app.require_subcommand(1);

  std::string rig_spec;
  auto* info = app.add_subcommand("info", "Meshes, vertices, joints, clips and weights of a rig");
  info->add_option("RIG", rig_spec,
                   "glTF/FBX/COLLADA file, or procedural:cylinder|finger|humanoid?vertices=N")
      ->required();
  bool info_fit = false;
  std::string info_setup;
  info->add_flag("--fit", info_fit,
                 "also fit the primitives and report each joint's (vertices, r, closure points, and how "
                 "many rest vertices of other joints lie inside it)");
  info->add_option("--setup", info_setup, "JSON setup file for --fit");

  auto* bake =
      app.add_subcommand("bake", "Deform a rig over an animation with one method and write the result");
  std::string method = "tracking2014", clip, pose_script, setup_path, out, metrics, render_dir, ply_dir;
  std::vector<std::string> bends;
  int frames = 31;
  double fps = 30, max_step = 0;
  bool no_self = false, compare = false;
  bake->add_option("RIG", rig_spec,
                   "glTF/FBX/COLLADA file, or procedural:cylinder|finger|humanoid?vertices=N")
      ->required();
  bake->add_option("--method", method, "lbs | dqs | implicit2013 | tracking2014")->capture_default_str();
  bake->add_option("--clip", clip, "animation clip of the file, by name");
  bake->add_option("--bend", bends,
                   "JOINT:AXIS:DEGREES — bend a joint about x|y|z of its local frame and back");
  bake->add_option("--pose-script", pose_script, "JSON pose script (docs/skinning.md)");
  bake->add_option("--frames", frames, "frames of a --bend animation (rest, peak, rest)")
      ->capture_default_str();
  bake->add_option("--fps", fps, "clip sampling / output frame rate")->capture_default_str();
  bake->add_option(
      "--max-step-rad", max_step,
      "largest joint rotation per tracking sub-step (0 = the 2014 sub-step rule only, docs/skinning.md)");
  bake->add_option("--setup", setup_path, "JSON setup file: per-joint operators, relaxation, options");
  bake->add_option("--out", out, "baked .glb (one morph target per frame)")->required();
  bake->add_option("--metrics", metrics, "write the quality metrics (QUALITY.md) as JSON");
  bake->add_option("--render", render_dir, "write PNG renders (peak frame) into this folder");
  bake->add_option("--ply", ply_dir, "write one PLY per frame into this folder");
  bake->add_flag("--compare", compare, "also run the other three methods (metrics and renders side by side)");
  bake->add_flag("--no-self-intersections", no_self,
                 "skip the exact self-intersection count (faster metrics)");

  auto* demo = app.add_subcommand(
      "demo", "The procedural humanoid's elbow and knee bent to 150° and back, all methods");
  std::string demo_out = "out/demo";
  int demo_vertices = 13000, demo_frames = 31;
  demo->add_option("--out", demo_out, "output folder")->capture_default_str();
  demo->add_option("--vertices", demo_vertices, "humanoid vertex count")->capture_default_str();
  demo->add_option("--frames", demo_frames, "frames (rest, 150°, rest)")->capture_default_str();
  // The demo caps tracking sub-steps at 0.05 rad (the reference step) on top of the 2014
  // rule: with the rule alone the knee's return path leaves thigh vertices trapped in the contact
  // operator's valley (docs/skinning.md, "Known limits").
  double demo_max_step = 0.05;
  demo->add_option(
          "--max-step-rad", demo_max_step,
          "largest joint rotation per tracking sub-step (0 = the 2014 sub-step rule only, docs/skinning.md)")
      ->capture_default_str();

  CLI11_PARSE(app, argc, argv);

  try {
    const Progress progress = stderr_progress();
    if (*info) {
      Rig rig = open_rig(rig_spec, fps, progress);
      print_info(rig, rig_spec);
      if (info_fit) {
        const Skinner skinner(std::move(rig), info_setup.empty() ? SkinSetup{} : load_setup(info_setup),
                              progress);
        print_fit(skinner.fitted());
      }
      return 0;
    }
    SkinSetup setup = setup_path.empty() ? SkinSetup{} : load_setup(setup_path);
    std::vector<Method> methods;
    std::vector<std::string> bend_texts = bends;
    std::string out_glb = out, out_metrics = metrics, out_render = render_dir, out_ply = ply_dir;
    if (*demo) {
      rig_spec = "procedural:humanoid?vertices=" + std::to_string(demo_vertices);
      bend_texts = {"LeftForeArm:x:150", "LeftLeg:x:150"};
      frames = demo_frames;
      methods = all_methods();
      out_glb = demo_out + "/tracking2014.glb";
      out_metrics = demo_out + "/metrics.json";
      out_render = demo_out;
      max_step = demo_max_step;
      clip.clear();
      pose_script.clear();
    } else {
      methods = {method_from_string(method)};
      if (compare)
        for (Method m : all_methods())
          if (m != methods[0]) methods.push_back(m);
      const int sources = int(!clip.empty()) + int(!bends.empty()) + int(!pose_script.empty());
      if (sources != 1) throw isokit::InputError("bake: give exactly one of --clip, --bend or --pose-script");
    }
    if (max_step > 0) setup.substeps.max_step_rad = max_step;

    std::fprintf(stderr, "isokit-skin: loading %s\n", rig_spec.c_str());
    const auto t0 = std::chrono::steady_clock::now();
    Rig rig = open_rig(rig_spec, fps, progress);
    std::vector<BendSpec> bend_specs;
    for (const std::string& b : bend_texts) bend_specs.push_back(parse_bend(b, rig));
    std::vector<Pose> poses;
    std::string animation;
    if (!bend_specs.empty()) {
      poses = bend_animation(rig, bend_specs, frames);
      for (const std::string& b : bend_texts) animation += (animation.empty() ? "--bend " : " --bend ") + b;
      animation += " (" + std::to_string(frames) + " frames)";
      if (setup.substeps.max_step_rad > 0)
        animation += ", tracking sub-steps <= " + isokit::format_number(setup.substeps.max_step_rad) + " rad";
    } else if (!clip.empty()) {
      poses = clip_animation(rig, clip);
      animation = "clip " + clip;
    } else {
      poses = pose_script_animation(rig, pose_script);
      animation = "pose script " + pose_script;
    }
    std::fprintf(stderr, "isokit-skin: %lld vertices, %zu joints; fitting\n",
                 static_cast<long long>(rig.rest.rows()), rig.joints.size());
    Skinner skinner(rig, setup, progress);
    for (const BonePart& b : skinner.fitted().bones())
      if (!b.fitted && !b.error.empty() && b.error != "no vertices")
        std::fprintf(stderr, "  warning: joint '%s' has no primitive: %s\n", rig.joints[b.joint].name.c_str(),
                     b.error.c_str());
    // Under-resolved limbs (docs/skinning.md, "Low-poly rigs"): say so once.
    if (setup.fold_repair_min_part_vertices > 0) {
      int small = 0;
      const BonePart* smallest = nullptr;
      for (const BonePart& b : skinner.fitted().bones())
        if (b.fitted && b.vertices < setup.fold_repair_min_part_vertices) {
          ++small;
          if (!smallest || b.vertices < smallest->vertices) smallest = &b;
        }
      if (smallest)
        std::fprintf(
            stderr,
            "  warning: %d of %d primitives come from parts of fewer than %d vertices (smallest: '%s', %d): "
            "the mesh under-resolves these limbs; the implicit methods may thin or bloat them and the fold "
            "repair leaves them out (docs/skinning.md, \"Low-poly rigs\"); --method dqs is the safer "
            "choice for such a rig\n",
            small, skinner.fitted().fitted_count(), setup.fold_repair_min_part_vertices,
            rig.joints[smallest->joint].name.c_str(), smallest->vertices);
    }
    std::fprintf(stderr, "isokit-skin: %d primitives fitted in %.2f s (setup %.2f s)\n",
                 skinner.fitted().fitted_count(), skinner.fitted().fit_seconds(),
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    BakeOptions bo;
    bo.self_intersections = !no_self;
    std::vector<BakeResult> results;
    for (Method m : methods) {
      results.push_back(skinner.bake(m, poses, bo));
      const BakeResult& r = results.back();
      std::fprintf(stderr,
                   "  %-13s %.2f ms/frame, worst: %d self-intersections, %d inverted triangles (%d new)\n",
                   to_string(m), r.mean_ms, r.worst.self_intersections, r.worst.inverted_triangles,
                   r.worst.new_inverted_triangles);
    }
    // Main result: tracking2014 for the demo, else the chosen method.
    const BakeResult& main_result =
        results.front().method == methods.front() && !*demo ? results.front() : results.back();
    ReportContext ctx;
    ctx.animation = animation;
    ctx.fps = fps;
    ctx.threads = threads();
    ctx.fit_seconds = skinner.fitted().fit_seconds();
    int peak = 0;
    double best = -1;
    for (std::size_t f = 0; f < poses.size(); ++f) {
      const double a = max_rotation_between(poses[0], poses[f]);
      if (a > best) {
        best = a;
        peak = static_cast<int>(f);
      }
    }
    std::vector<RenderView> views;
    if (!out_render.empty())
      views = bend_views(rig, skinner.fitted().partition(), bend_specs, poses, peak, main_result);
    std::vector<BakeResult> ordered = results;
    write_outputs(rig, ordered, main_result, ctx, out_glb, out_metrics, out_render, views, out_ply);
    std::printf("%s — %s, %lld vertices, %zu joints, %d threads\n\n", rig.name.c_str(), animation.c_str(),
                static_cast<long long>(rig.rest.rows()), rig.joints.size(), ctx.threads);
    std::printf("%s", comparison_table(results).c_str());
    return 0;
  } catch (const isokit::InputError& e) {
    std::fprintf(stderr, "\nisokit-skin: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "\nisokit-skin: internal error: %s\n", e.what());
    return 3;
  }
}
