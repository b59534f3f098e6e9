// SPDX-License-Identifier: MIT
// isokit-skin: implicit skinning of rigged characters from the command line.
//   isokit-skin info RIG [--fit [--setup S.json]]
//   isokit-skin bake RIG --method M [--clip NAME [--clip-file F] | --bend J:AXIS:DEG ... |
//                    --pose-script P.json] (none: the rig's only clip)
//                    [--frames N] [--fps N] [--max-step-rad R] [--setup S.json] --out OUT.glb
//                    [--metrics M.json] [--render DIR] [--ply DIR] [--pc2 OUT.pc2]
//   isokit-skin demo [--out DIR] [--vertices N] [--frames N] [--max-step-rad R]
// RIG is a glTF/FBX/COLLADA file or procedural:cylinder | procedural:finger |
// procedural:humanoid?vertices=13000.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <new>
#include <optional>
#include <thread>

#include "isokit/core/error.h"
#include "isokit/core/math.h"
#include "isokit/core/stage.h"
#include "isokit/skinning/bake_job.h"
#include "isokit/skinning/fit_quality.h"
#include "isokit/skinning/grid_operators.h"
#include "isokit/skinning/procedural.h"
#include "isokit/skinning/rigid_pieces.h"
#ifdef ISOKIT_HAVE_VIEWER
#include "isokit/viewer/gui.h"
#endif

using namespace isokit::skinning;
using isokit::format_number;
using isokit::kPi;
using isokit::require;
using isokit::Stage;

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

// Separate parts, open borders, non-manifold and inconsistently oriented edges: reported, never
// refused.
void print_surface(const Rig& rig) {
  const SurfaceReport s = inspect_surface(rig.rest, rig.triangles);
  const bool closed = s.boundary_edges == 0 && s.nonmanifold_edges == 0;
  std::printf(
      "surface: %d separate part(s), %d open border edge(s), %d non-manifold edge(s), %d non-manifold "
      "vertex(es), %d edge(s) with inconsistent orientation; %s\n",
      s.components, s.boundary_edges, s.nonmanifold_edges, s.nonmanifold_vertices, s.inconsistent_edges,
      closed ? (s.volume >= 0 ? "closed, oriented outward" : "closed, inside out") : "not closed");
}

/// The rigid pieces (rigid_pieces.h): components that follow one transform.
void print_rigid_pieces(const Rig& rig) {
  const std::vector<RigidPiece> pieces = find_rigid_pieces(rig);
  std::size_t vertices = 0;
  for (const RigidPiece& p : pieces) vertices += p.vertices.size();
  std::printf("rigid pieces: %zu (%zu of %lld vertices)\n", pieces.size(), vertices,
              static_cast<long long>(rig.rest.rows()));
  for (std::size_t k = 0; k < pieces.size() && k < 40; ++k) {
    const RigidPiece& p = pieces[k];
    std::string on;
    for (std::size_t i = 0; i < p.joints.size(); ++i)
      on += (i ? " + " : "") + rig.joints[static_cast<std::size_t>(p.joints[i])].display_name() +
            (p.joints.size() > 1 ? " " + format_number(p.weights[i]) : "");
    std::printf("  %3zu  %6zu vertices %6d triangles  on %s\n", k, p.vertices.size(), p.triangles,
                on.c_str());
  }
  if (pieces.size() > 40) std::printf("  ... (%zu more)\n", pieces.size() - 40);
}

/// The painted relaxation mask (Rig::relax_mask): how many vertices are rigid (0) and pulled (< 1).
void print_mask(const Rig& rig) {
  if (rig.relax_mask.empty()) {
    std::printf("relaxation mask: none (every vertex tracked)\n");
    return;
  }
  const auto rigid = std::count(rig.relax_mask.begin(), rig.relax_mask.end(), 0.0f);
  const auto pulled = std::count_if(rig.relax_mask.begin(), rig.relax_mask.end(),
                                    [](float m) { return m > 0.0f && m < 1.0f; });
  std::printf("relaxation mask: %lld rigid, %lld pulled toward their bone, of %zu vertices\n",
              static_cast<long long>(rigid), static_cast<long long>(pulled), rig.relax_mask.size());
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
  print_surface(rig);
  print_rigid_pieces(rig);
  print_mask(rig);
  std::printf("joints: %zu\n", rig.joints.size());
  const std::vector<Eigen::Vector3d> p = rest_joint_positions(rig);
  for (std::size_t j = 0; j < rig.joints.size(); ++j) {
    const Joint& jt = rig.joints[j];
    const std::string note = jt.file_name.empty() ? "" : "  (named '" + jt.file_name + "' in the file)";
    std::printf("  %3zu %-24s parent %3d  at (%.3f, %.3f, %.3f)%s\n", j, jt.name.c_str(), jt.parent, p[j].x(),
                p[j].y(), p[j].z(), note.c_str());
  }
  std::printf("clips: %zu\n", rig.clips.size());
  for (const Clip& c : rig.clips)
    std::printf("  %-24s %zu frames at %.1f fps\n", c.name.c_str(), c.frame_count(), c.fps);
}

// `info --fit`: what the fit made of every joint: its vertices, the rule that gave them a field,
// the fit distances both ways and the rest vertices of other joints inside its primitive
// (docs/skinning.md, "Checking a fit").
// `info --fit`: the agreement of each part's own field and of the composed 2014 field with the
// rest mesh (what the tracker follows, docs/skinning.md "Checking a fit").
void print_agreement(const FitQuality& q, const FittedRig& fitted, Skinner& skinner) {
  const Rig& rig = fitted.rig();
  const double pct = q.diagonal > 0 ? 100.0 / q.diagonal : 0;
  std::printf(
      "agreement at rest (angle of -grad f to the vertex normal, degrees; distance to the 0.5 level, "
      "%%diag):\n");
  std::printf("  %-24s %-8s %6s %6s %6s %5s   %8s %8s %8s\n", "joint", "field", "p50", "p95", "max", " >60",
              "dist p50", "p95", "max");
  auto row = [&](const char* name, const char* kind, const isokit::implicit::FieldAgreement& a) {
    std::printf("  %-24s %-8s %6.1f %6.1f %6.1f %5d   %8.3f %8.3f %8.3f\n", name, kind, a.angle_p50,
                a.angle_p95, a.angle_max, a.over_limit, a.distance_p50 * pct, a.distance_p95 * pct,
                a.distance_max * pct);
  };
  for (const PartQuality& p : q.parts) {
    const BonePart& b = fitted.bones()[static_cast<std::size_t>(p.joint)];
    row(rig.joints[static_cast<std::size_t>(p.joint)].name.c_str(), to_string(b.rule), p.agreement);
  }
  const RestAgreement ra = rest_agreement(fitted, skinner.field(TreeKind::k2014));
  row("composed (2014 tree)", "", ra.composed);
  row("composed, visible", "", ra.visible);
  std::printf(
      "  inverted triangles at rest: %d of %d (%.2f %%); open panels: %d (%d vertices, left out); "
      "hidden vertices (inside another component): %d; unrelated vertices inside primitives: %d\n",
      ra.inverted_triangles, ra.triangles, ra.triangles ? 100.0 * ra.inverted_triangles / ra.triangles : 0.0,
      ra.open_panels, ra.panel_vertices, ra.hidden_vertices, ra.unrelated_inside);
}

FitQuality print_fit(const FittedRig& fitted) {
  const Rig& rig = fitted.rig();
  const FitQuality q = fit_quality(fitted);
  std::vector<const PartQuality*> part(rig.joints.size(), nullptr);
  for (const PartQuality& p : q.parts) part[static_cast<std::size_t>(p.joint)] = &p;
  std::printf("primitives: %d of %zu joints (fit %.2f s); vertices without a field: %d of %lld\n",
              fitted.fitted_count(), rig.joints.size(), fitted.fit_seconds(), q.vertices_without_field,
              static_cast<long long>(rig.rest.rows()));
  std::printf("  %-24s %8s %-11s %8s %3s  %-15s %-15s %-11s %s\n", "joint", "vertices", "rule", "r", "cl",
              "vert->surf p95", "surf->vert p95", "max / r", "inside: related / unrelated");
  std::printf("  %-24s %8s %-11s %8s %3s  %-15s %-15s %-11s\n", "", "", "", "", "", "  / max (%diag)",
              "  / max (%diag)", "  v->s s->v");
  const double pct = q.diagonal > 0 ? 100.0 / q.diagonal : 0;
  for (const BonePart& b : fitted.bones()) {
    const char* name = rig.joints[static_cast<std::size_t>(b.joint)].name.c_str();
    if (const PartQuality* p = part[static_cast<std::size_t>(b.joint)]) {
      const isokit::implicit::FitDistances& d = p->distances;
      std::printf("  %-24s %8d %-11s %8.3g %3d  %6.2f / %-6.2f %6.2f / %-6.2f %5.2f %5.2f  %d / %d\n", name,
                  b.vertices, to_string(b.rule), b.fit.r, b.fit.closure_points, d.to_surface_p95 * pct,
                  d.to_surface_max * pct, d.from_surface_p95 * pct, d.from_surface_max * pct,
                  d.to_surface_max / p->r, d.from_surface_max / p->r, p->coverage.related,
                  p->coverage.unrelated);
    } else {
      const std::string to =
          b.merged_into >= 0 ? " -> " + rig.joints[static_cast<std::size_t>(b.merged_into)].name : "";
      std::printf("  %-24s %8d %-11s%s\n", name, b.vertices, to_string(b.rule), to.c_str());
      if (b.rule != FitRule::no_vertices) std::printf("  %-24s   (%s)\n", "", b.error.c_str());
    }
  }
  std::printf(
      "  worst part: vertex->surface p95 %.2f %%, max %.2f %%; surface->vertex p95 %.2f %%, max %.2f %% of "
      "the\n"
      "  diagonal (%.4g); unrelated vertices inside primitives at rest: %d\n"
      "  (cl: closure points; related: vertices of the primitives next to it in the tree; unrelated: of any\n"
      "   other joint; many unrelated vertices mean a primitive reaching where it should not)\n",
      100 * q.worst_to_surface_p95(), 100 * q.worst_to_surface_max(), 100 * q.worst_from_surface_p95(),
      100 * q.worst_from_surface_max(), q.diagonal, q.unrelated_inside());
  return q;
}

// `info --fit`: the operator of every fitted joint in both trees (no grid is generated):
// union, blend, a preset, or a designed operator with its spec file and cache key.
void print_operators(const FittedRig& fitted, const SkinSetup& setup) {
  const Rig& rig = fitted.rig();
  std::printf("operators (setup %s):\n  %-24s %-40s %s\n", setup.source.c_str(), "joint",
              "2014 tree (tracking2014)", "2013 tree (implicit2013)");
  for (const BonePart& b : fitted.bones()) {
    if (!b.fitted) continue;
    const std::string& name = rig.joints[static_cast<std::size_t>(b.joint)].name;
    std::string ops[2];
    int i = 0;
    for (TreeKind t : {TreeKind::k2014, TreeKind::k2013}) {
      try {
        ops[i++] = describe_joint_operator(setup, name, setup.operator_for(name, t));
      } catch (const isokit::InputError& e) {  // a joint spec on a blend joint of the 2013 tree
        ops[i++] = std::string("error: ") + e.what();
      }
    }
    std::printf("  %-24s %-40s %s\n", name.c_str(), ops[0].c_str(), ops[1].c_str());
  }
  // Muscles (2014 Fig. 10): the same in both trees.
  for (const MuscleSetup& m : setup.muscles) {
    const double peak = std::max_element(m.curve.begin(), m.curve.end(), [](const auto& a, const auto& b) {
                          return a.second < b.second;
                        })->second;
    std::printf("  muscle %-17s on %s, %s, scaled up to %s by the bend of %s\n", m.name.c_str(),
                m.bone.c_str(), m.op == JointOperator::kUnion ? "union" : "blend",
                format_number(peak).c_str(), m.driver.c_str());
  }
}

/// Everything the command line sets.
struct Args {
  std::string rig;
  bool info_fit{false};
  std::string info_setup;
  std::string method{to_string(kDefaultMethod)}, setup, device{"cpu"};
  AnimationRequest animation;
  double fps{30}, max_step{0};
  bool compare{false}, no_self{false};
  BakeOutputs outputs;
  std::string demo_out{"out/demo"};
  int demo_vertices{13000}, demo_frames{31};
  // The demo caps tracking sub-steps at 0.05 rad (the reference step) on top of the 2014
  // rule: with the rule alone the knee's return path leaves thigh vertices trapped in the contact
  // operator's valley (docs/skinning.md, "Known limits").
  double demo_max_step{0.05};
};

constexpr const char* kRigHelp = "glTF/FBX/COLLADA file, or procedural:cylinder|finger|humanoid?vertices=N";
constexpr const char* kMaxStepHelp =
    "largest joint rotation per tracking sub-step (0 = the 2014 sub-step rule only, docs/skinning.md)";

CLI::App* add_info(CLI::App& app, Args& a) {
  auto* info = app.add_subcommand("info", "Meshes, vertices, joints, clips and weights of a rig");
  info->add_option("RIG", a.rig, kRigHelp)->required();
  info->add_flag("--fit", a.info_fit,
                 "also fit the primitives and report each joint's (vertices, r, closure points, and how "
                 "many rest vertices of other joints lie inside it)");
  info->add_option("--setup", a.info_setup,
                   "JSON setup file (its `mask` section; the fit options for --fit)");
  return info;
}

CLI::App* add_bake(CLI::App& app, Args& a) {
  auto* bake =
      app.add_subcommand("bake", "Deform a rig over an animation with one method and write the result");
  bake->add_option("RIG", a.rig, kRigHelp)->required();
  bake->add_option("--method", a.method, "lbs | dqs | ddm | cor | implicit2013 | tracking2014")
      ->capture_default_str();
  bake->add_option("--clip", a.animation.clip,
                   "animation clip of the file (or of --clip-file), by name; default: the only clip");
  bake->add_option(
      "--clip-file", a.animation.clip_file,
      "animation file (skeleton + clips, no mesh needed) whose clip is retargeted by joint name");
  bake->add_option("--bend", a.animation.bends,
                   "JOINT:AXIS:DEGREES — bend a joint about x|y|z of its local frame and back");
  bake->add_option("--pose-script", a.animation.pose_script, "JSON pose script (docs/skinning.md)");
  bake->add_option("--frames", a.animation.frames, "frames of a --bend animation (rest, peak, rest)")
      ->capture_default_str();
  bake->add_option("--fps", a.fps, "clip sampling / output frame rate")->capture_default_str();
  bake->add_option("--max-step-rad", a.max_step, kMaxStepHelp);
  bake->add_option("--device", a.device, "cpu | cuda (the CUDA tracker needs a CUDA build and a GPU)")
      ->capture_default_str();
  bake->add_option("--setup", a.setup, "JSON setup file: per-joint operators, relaxation, options");
  bake->add_option("--out", a.outputs.glb, "baked .glb (one morph target per frame)")->required();
  bake->add_option("--metrics", a.outputs.metrics, "write the quality metrics (QUALITY.md) as JSON");
  bake->add_option("--render", a.outputs.render_dir, "write PNG renders (peak frame) into this folder");
  bake->add_option("--ply", a.outputs.ply_dir, "write one PLY per frame into this folder");
  bake->add_option("--pc2", a.outputs.pc2,
                   "write the baked positions as a PC2 point cache (the file's vertex order; Blender's "
                   "Mesh Cache modifier, 3ds Max)");
  bake->add_flag("--compare", a.compare, "also run every other method (metrics and renders side by side)");
  bake->add_flag("--no-self-intersections", a.no_self,
                 "skip the exact self-intersection count (faster metrics)");
  return bake;
}

#ifdef ISOKIT_HAVE_VIEWER
/// `isokit-skin view`: the viewer window (docs/skinning.md, "The viewer").
CLI::App* add_view(CLI::App& app, isokit::viewer::ViewerGuiOptions& v) {
  auto* view = app.add_subcommand("view", "Pose a rig and watch its skin live (GLFW + OpenGL window)");
  view->add_option("RIG", v.rig, kRigHelp)->required();
  view->add_option("--clip", v.clip, "a clip of the file to play at start");
  view->add_option("--setup", v.setup, "JSON setup file");
  view->add_option("--method", v.method, "lbs | dqs | ddm | cor | implicit2013 | tracking2014")
      ->capture_default_str();
  view->add_option("--size", v.width, "window width in pixels")->capture_default_str();
  view->add_option(
          "--edit-slice-ms", v.edit_slice_ms,
          "an edited pose's skin is shown after this many ms of its solve, then when it is done (0 = whole)")
      ->check(CLI::Range(0.0, 1000.0))
      ->capture_default_str();
  view->add_option("--skin-wait-ms", v.skin_wait_ms,
                   "each frame waits up to this many ms for the last edit's skin (0 = never)")
      ->check(CLI::Range(0.0, 1000.0))
      ->capture_default_str();
  view->add_option("--script", v.script_path,
                   "headless: replay this JSON script of input events, then close");
  view->add_option("--screenshot-dir", v.screenshot_dir, "where the script's screenshots and report go");
  view->add_option("--report", v.report_path,
                   "the script's report (default SCREENSHOT_DIR/viewer-report.json)");
  return view;
}
#endif

CLI::App* add_demo(CLI::App& app, Args& a) {
  auto* demo = app.add_subcommand(
      "demo", "The procedural humanoid's elbow and knee bent to 150° and back, all methods");
  demo->add_option("--out", a.demo_out, "output folder")->capture_default_str();
  demo->add_option("--vertices", a.demo_vertices, "humanoid vertex count")->capture_default_str();
  demo->add_option("--frames", a.demo_frames, "frames (rest, 150°, rest)")->capture_default_str();
  demo->add_option("--max-step-rad", a.demo_max_step, kMaxStepHelp)->capture_default_str();
  return demo;
}

/// The demo as a bake: the humanoid's left elbow and knee, every method, written to one folder.
void make_demo(Args& a) {
  a.rig = "procedural:humanoid?vertices=" + std::to_string(a.demo_vertices);
  a.animation = AnimationRequest{};
  a.animation.bends = {"LeftForeArm:x:150", "LeftLeg:x:150"};
  a.animation.frames = a.demo_frames;
  a.outputs = BakeOutputs{a.demo_out + "/" + to_string(kDefaultMethod) + ".glb", a.demo_out + "/metrics.json",
                          a.demo_out, "", ""};
  a.max_step = a.demo_max_step;
}

/// Each numeric option's valid range (CLI11 reads the numbers; the ranges are checked here so that
/// every message has the same one-line form). --frames is checked with the animation request.
void check_numbers(const Args& a) {
  auto in_range = [](double x, double lo, double hi) { return std::isfinite(x) && x >= lo && x <= hi; };
  require(in_range(a.fps, 1e-3, 1000), "--fps",
          "must be in (0, 1000] frames per second (got " + format_number(a.fps) + ")",
          "give a frame rate such as 30");
  for (double step : {a.max_step, a.demo_max_step})
    require(in_range(step, 0, kPi), "--max-step-rad",
            "must be 0 (the 2014 rule only) or in (0, pi] radians (got " + format_number(step) + ")",
            "give e.g. 0.05, or 0");
  require(a.demo_vertices >= 3000 && a.demo_vertices <= 400000, "demo --vertices",
          "must be in [3000, 400000] (got " + std::to_string(a.demo_vertices) + ")", "give e.g. 13000");
  require(a.demo_frames >= 3 && a.demo_frames <= 100000, "demo --frames",
          "must be in [3, 100000] (got " + std::to_string(a.demo_frames) + ")", "give e.g. 31");
}

/// The rig, its loader warnings printed on stderr.
Rig open_and_warn(const Args& a, const Progress& progress, const MaskSource& mask) {
  const Stage stage("reading " + a.rig);
  std::vector<std::string> warnings;
  Rig rig = open_rig(a.rig, a.fps, progress, &warnings, mask);
  for (const std::string& w : warnings) std::fprintf(stderr, "  warning: %s\n", w.c_str());
  return rig;
}

int run_info(const Args& a, const Progress& progress) {
  const SkinSetup setup = a.info_setup.empty() ? SkinSetup{} : load_setup(a.info_setup);
  Rig rig = open_and_warn(a, progress, setup.mask);
  print_info(rig, a.rig);
  if (a.info_fit) {
    const Stage stage("fitting the part fields of " + a.rig);
    Skinner skinner(std::move(rig), setup, progress);
    const FitQuality q = print_fit(skinner.fitted());
    print_agreement(q, skinner.fitted(), skinner);
    print_operators(skinner.fitted(), skinner.setup());
  }
  return 0;
}

/// Bakes `methods` (the first one's result is written, unless `main` says otherwise).
int run_bake(const Args& a, const std::vector<Method>& methods, Method main, const Progress& progress) {
  check_device(device_from_string(a.device));
  check_animation_request(a.animation);
  check_bake_outputs(a.outputs);
  SkinSetup setup = [&] {
    const Stage stage("reading the setup " + a.setup);
    return a.setup.empty() ? SkinSetup{} : load_setup(a.setup);
  }();
  if (a.max_step > 0) setup.substeps.max_step_rad = a.max_step;
  std::fprintf(stderr, "isokit-skin: loading %s\n", a.rig.c_str());
  const auto t0 = std::chrono::steady_clock::now();
  const Rig rig = open_and_warn(a, progress, setup.mask);
  AnimationRequest request = a.animation;
  request.fps = a.fps;
  const Animation animation = [&] {
    const Stage stage("sampling the animation of " + a.rig);
    return make_animation(rig, request, setup.substeps.max_step_rad);
  }();
  for (const std::string& w : animation.warnings) std::fprintf(stderr, "  warning: %s\n", w.c_str());
  std::fprintf(stderr, "isokit-skin: %lld vertices, %zu joints; fitting\n",
               static_cast<long long>(rig.rest.rows()), rig.joints.size());
  std::optional<Stage> fitting(std::in_place, "fitting the part fields of " + a.rig);
  Skinner skinner(rig, setup, progress);
  fitting.reset();
  for (const std::string& w : fit_warnings(skinner.fitted(), setup))
    std::fprintf(stderr, "  warning: %s\n", w.c_str());
  std::fprintf(stderr, "isokit-skin: %d primitives fitted in %.2f s (setup %.2f s)\n",
               skinner.fitted().fitted_count(), skinner.fitted().fit_seconds(),
               std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  BakeOptions bo;
  bo.self_intersections = !a.no_self;
  std::vector<BakeResult> results;
  for (Method m : methods) {
    const Stage stage("baking " + a.rig + " with " + to_string(m));
    results.push_back(skinner.bake(m, animation.poses, bo));
    const BakeResult& r = results.back();
    std::fprintf(stderr,
                 "  %-13s %.2f ms/frame, worst: %d self-intersections, %d folded triangles (%d new), "
                 "%d inverted triangles (%d new)\n",
                 to_string(m), r.mean_ms, r.worst.self_intersections, r.worst.folded_triangles,
                 r.worst.folded_new, r.worst.inverted_triangles, r.worst.new_inverted_triangles);
  }
  const BakeResult& written = main_result(results, main);
  const ReportContext ctx{animation.description, a.fps, static_cast<int>(std::thread::hardware_concurrency()),
                          skinner.fitted().fit_seconds(),
                          rest_agreement(skinner.fitted(), skinner.field(TreeKind::k2014))};
  std::vector<RenderView> views;
  if (!a.outputs.render_dir.empty())
    views = bend_views(rig, skinner.fitted().partition(), animation.bends, animation.poses,
                       peak_frame(animation.poses), written);
  const Stage writing("writing the outputs of " + a.rig);
  for (const std::string& w : write_bake_outputs(rig, results, written, ctx, views, a.outputs))
    std::fprintf(stderr, "  wrote %s\n", w.c_str());
  std::printf("%s — %s, %lld vertices, %zu joints, %d threads\n\n", rig.name.c_str(),
              animation.description.c_str(), static_cast<long long>(rig.rest.rows()), rig.joints.size(),
              ctx.threads);
  std::printf("%s", comparison_table(results).c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"isokit-skin: implicit skinning (2013) and iso-surface tracking (2014) of rigged characters"};
  app.require_subcommand(1);
  Args a;
  const CLI::App* info = add_info(app, a);
  add_bake(app, a);
  const CLI::App* demo = add_demo(app, a);
#ifdef ISOKIT_HAVE_VIEWER
  isokit::viewer::ViewerGuiOptions view_options;
  const CLI::App* view = add_view(app, view_options);
#endif
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "isokit-skin: error: %s (see isokit-skin --help)\n", e.what());
    return 2;
  }
  try {
    check_numbers(a);
    const Progress progress = stderr_progress();
    if (*info) return run_info(a, progress);
#ifdef ISOKIT_HAVE_VIEWER
    if (*view) {
      view_options.height = view_options.width * 5 / 8;
      return isokit::viewer::run_viewer(view_options);
    }
#endif
    if (*demo) {
      make_demo(a);
      return run_bake(a, all_methods(), kDefaultMethod, progress);
    }
    std::vector<Method> methods{method_from_string(a.method)};
    if (a.compare)
      for (Method m : all_methods())
        if (m != methods[0]) methods.push_back(m);
    return run_bake(a, methods, methods[0], progress);
  } catch (const isokit::InputError& e) {
    std::fprintf(stderr, "\nisokit-skin: error: %s\n", e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    // Too large an input (a file's declared sizes are checked before allocating: this is the
    // machine's limit, or a derived size that no reader bounds).
    std::fprintf(stderr, "\nisokit-skin: error: %s\n", isokit::out_of_memory_message().c_str());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "\nisokit-skin: internal error: %s\n", e.what());
    return 3;
  }
}
