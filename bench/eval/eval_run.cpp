// SPDX-License-Identifier: MIT
#include "eval_run.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <map>
#include <new>
#include <set>
#include <thread>

#include "eval_joints.h"
#include "eval_rows.h"
#include "isokit/core/error.h"
#include "isokit/core/stage.h"
#include "isokit/skinning/bake_job.h"

using namespace isokit::skinning;
namespace fs = std::filesystem;
using isokit::eval::EvalOptions;
using isokit::eval::Row;

namespace {

/// An error's one-line text: a std::bad_alloc (no message of its own) says the stage it ended.
std::string error_text(const std::exception& e) {
  std::string why =
      dynamic_cast<const std::bad_alloc*>(&e) != nullptr ? isokit::out_of_memory_message() : e.what();
  isokit::Stage::clear_failed();
  return why;
}

using Args = EvalOptions;

/// One animation of a rig: its poses and the joints its close-ups show.
struct EvalAnimation {
  std::string name;
  std::vector<Pose> poses;
  std::vector<BendSpec> views;
  bool is_bend{false};
};

/// The state of a run: the rows so far and where they are written.
struct Run {
  Args args;
  std::vector<Row> rows;
  std::chrono::steady_clock::time_point start{std::chrono::steady_clock::now()};
};

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

void note(const Run& run, const std::string& text) {
  std::fprintf(stderr, "[%7.1f s] %s\n", seconds_since(run.start), text.c_str());
  std::fflush(stderr);
}

bool is_rig_file(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext == ".glb" || ext == ".gltf" || ext == ".fbx" || ext == ".dae";
}

/// The rigs of the run: `--rig`, every rig file of each `--rigs` folder (sorted), filtered by
/// `--only`; without either, ../shared/data/rigs (when it exists) and ../shared/data/Fox.glb.
std::vector<std::string> rig_list(const Args& a) {
  std::vector<std::string> folders = a.folders, rigs = a.rigs;
  if (folders.empty() && rigs.empty()) {
    if (fs::is_directory("../shared/data/rigs")) folders.push_back("../shared/data/rigs");
    if (fs::exists("../shared/data/Fox.glb")) rigs.push_back("../shared/data/Fox.glb");
  }
  std::vector<std::string> found;
  for (const std::string& f : folders) {
    std::set<std::string> sorted;
    for (const fs::directory_entry& e : fs::directory_iterator(f))
      if (e.is_regular_file() && is_rig_file(e.path())) sorted.insert(e.path().string());
    found.insert(found.end(), sorted.begin(), sorted.end());
  }
  found.insert(found.end(), rigs.begin(), rigs.end());
  std::vector<std::string> out;
  for (const std::string& r : found) {
    const bool keep = a.only.empty() || std::any_of(a.only.begin(), a.only.end(), [&](const std::string& o) {
                        return r.find(o) != std::string::npos;
                      });
    if (keep) out.push_back(r);
  }
  return out;
}

/// `s` with every character other than letters, digits, `_`, `-` and `.` replaced by `_`.
std::string file_name(std::string s) {
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-' && c != '.') c = '_';
  return s;
}

/// A short name for files and rows: the file stem, or the procedural spec's name.
std::string rig_label(const std::string& spec) {
  return file_name(spec.rfind("procedural:", 0) == 0 ? spec.substr(11) : fs::path(spec).stem().string());
}

bool wanted(const Args& a, const std::string& animation) {
  return a.clips.empty() || std::find(a.clips.begin(), a.clips.end(), animation) != a.clips.end();
}

/// Every edge of the mesh in exactly two triangles.
bool mesh_is_closed(const Rig& rig) {
  std::map<std::pair<int, int>, int> edges;
  for (Eigen::Index f = 0; f < rig.triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = rig.triangles(f, k), b = rig.triangles(f, (k + 1) % 3);
      ++edges[{std::min(a, b), std::max(a, b)}];
    }
  return std::all_of(edges.begin(), edges.end(), [](const auto& e) { return e.second == 2; });
}

}  // namespace

namespace {

/// The bend-and-return of the elbows and knees (first), then every clip (first `max_frames`).
std::vector<EvalAnimation> animations_of(const Rig& rig, const Args& a) {
  std::vector<EvalAnimation> out;
  if (wanted(a, "bend")) {
    EvalAnimation bend;
    bend.name = "bend";
    bend.is_bend = true;
    bend.views = isokit::eval::fold_joints(rig, a.bend_degrees);
    if (!bend.views.empty()) bend.poses = bend_animation(rig, bend.views, a.bend_frames);
    out.push_back(std::move(bend));
  }
  for (const Clip& c : rig.clips) {
    if (!wanted(a, c.name)) continue;
    EvalAnimation clip;
    clip.name = c.name;
    clip.poses = clip_animation(rig, c.name);
    if (a.max_frames > 0 && clip.poses.size() > static_cast<std::size_t>(a.max_frames))
      clip.poses.resize(static_cast<std::size_t>(a.max_frames));
    clip.views = isokit::eval::moving_joints(rig, clip.poses, 2);
    out.push_back(std::move(clip));
  }
  return out;
}

/// What a bend-and-return bends, e.g. "bend LeftForeArm:x:120 LeftLeg:x:-120 (31 frames)".
std::string describe(const Rig& rig, const EvalAnimation& anim) {
  if (!anim.is_bend) return "clip " + anim.name + " (" + std::to_string(anim.poses.size()) + " frames)";
  std::string text = "bend";
  for (const BendSpec& b : anim.views)
    text += " " + rig.joints[static_cast<std::size_t>(b.joint)].name + ":" + "xyz"[b.axis] + ":" +
            isokit::format_number(b.degrees);
  return text + " (" + std::to_string(anim.poses.size()) + " frames)";
}

/// OUT/eval.json (every row so far, with date, commit and options) and OUT/eval.md.
void write_tables(const Run& run) {
  char date[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  nlohmann::json j{{"date", date},
                   {"commit", run.args.commit},
                   {"threads", std::thread::hardware_concurrency()},
                   {"default_method", to_string(kDefaultMethod)},
                   {"max_frames", run.args.max_frames},
                   {"bend_frames", run.args.bend_frames},
                   {"bend_degrees", run.args.bend_degrees},
                   {"seconds", seconds_since(run.start)},
                   {"rows", run.rows}};
  write_text_file(run.args.out + "/eval.json", j.dump(2) + "\n");
  std::string md = "Real-rig evaluation, " + std::string(date) +
                   (run.args.commit.empty() ? "" : ", commit " + run.args.commit) + "\n\n";
  write_text_file(run.args.out + "/eval.md", md + isokit::eval::markdown_table(run.rows));
}

/// Close-ups seen from outside the body: a view whose camera would stand on the side of the mesh's
/// centroid (looking through the torso at an arm) looks from the other side of its box. An up
/// vector along the view (a bone seen end-on, a joint turning about world y) becomes the world
/// axis most across the view.
std::vector<RenderView> outside_views(std::vector<RenderView> views, const BakeResult& reference) {
  for (RenderView& v : views) {
    if (v.up.cross(v.view_direction).norm() < 1e-3 * v.up.norm() * v.view_direction.norm()) {
      int across = 0;
      v.view_direction.cwiseAbs().minCoeff(&across);
      v.up = Eigen::Vector3d::Unit(across);
    }
    if (v.box.isEmpty()) continue;
    const isokit::track::Positions& p = reference.frames.at(static_cast<std::size_t>(v.frame));
    const Eigen::Vector3d centroid = p.cast<double>().colwise().mean().transpose();
    if (v.view_direction.dot(v.box.center() - centroid) > 0) v.view_direction = -v.view_direction;
  }
  return views;
}

/// Bakes every method; a method that fails becomes an error row and is left out of the results.
std::vector<BakeResult> bake_methods(Run& run, Skinner& skinner, const std::string& label,
                                     const EvalAnimation& anim) {
  BakeOptions options;
  options.self_intersections = run.args.self_intersections;
  std::vector<BakeResult> results;
  for (const std::string& name : run.args.methods) {
    const auto t0 = std::chrono::steady_clock::now();
    try {
      const isokit::Stage stage("baking " + label + " / " + anim.name + " with " + name);
      results.push_back(skinner.bake(method_from_string(name), anim.poses, options));
      note(run, "  " + label + " / " + anim.name + " / " + name + ": " +
                    isokit::format_number(results.back().mean_ms) + " ms/frame (" +
                    isokit::format_number(seconds_since(t0)) + " s with metrics)");
    } catch (const std::exception& e) {
      const std::string why = error_text(e);
      run.rows.push_back(isokit::eval::error_row(label, anim.name, name, why));
      note(run, "  " + label + " / " + anim.name + " / " + name + " failed: " + why);
    }
  }
  return results;
}

/// The frame a clip's sheet shows: where some method's new interpenetration (`self_overlap_new`)
/// is largest, so that the red of the sheet shows the worst of it; the frame farthest from the
/// first pose when no method interpenetrates.
int sheet_frame(const EvalAnimation& anim, const std::vector<BakeResult>& results) {
  int frame = -1;
  double worst = 0;
  for (const BakeResult& r : results)
    for (std::size_t k = 0; k < r.stats.size(); ++k) {
      const double v = r.stats[k].metrics.self_overlap_new;
      if (v > worst) worst = v, frame = static_cast<int>(k);
    }
  return frame >= 0 && !anim.is_bend ? frame : peak_frame(anim.poses);
}

/// The rows, the metrics JSON and the contact sheet of one animation of one rig.
void evaluate_animation(Run& run, Skinner& skinner, const std::string& label, const EvalAnimation& anim,
                        bool closed, const RestAgreement& agreement) {
  const Rig& rig = skinner.rig();
  if (anim.poses.empty()) {
    run.rows.push_back(isokit::eval::error_row(label, anim.name, "—", "no elbow, knee or limb chain found"));
    return;
  }
  const std::vector<BakeResult> results = bake_methods(run, skinner, label, anim);
  if (results.empty()) return;
  const std::string dir = run.args.out + "/" + label + "/";
  const ReportContext context{describe(rig, anim), run.args.fps, int(std::thread::hardware_concurrency()),
                              skinner.fitted().fit_seconds(), agreement};
  const std::string metrics = metrics_json(rig, results, context);
  write_text_file(dir + file_name(anim.name) + ".metrics.json", metrics);
  for (Row& r : isokit::eval::rows_from_metrics(nlohmann::json::parse(metrics), label, anim.name, closed))
    run.rows.push_back(std::move(r));
  if (!run.args.render) return;
  const std::vector<RenderView> views =
      outside_views(bend_views(rig, skinner.fitted().partition(), anim.views, anim.poses,
                               sheet_frame(anim, results), results.front()),
                    results.front());
  const std::string sheet =
      dir + (anim.is_bend ? std::string("contact_sheet") : file_name(anim.name)) + ".png";
  write_comparison_sheet(rig, results, views, label + " — " + context.animation, sheet);
}

}  // namespace

namespace {

Progress fit_progress(const Run& run, const std::string& label) {
  return [&run, label](const std::string& stage, int done, int total) {
    if (total > 0 && done == total && stage.rfind("bake", 0) != 0)
      note(run, "  " + label + ": " + stage + " done (" + std::to_string(total) + ")");
  };
}

/// Loads and fits one rig, then evaluates each of its animations; failures become rows.
void evaluate_rig(Run& run, const std::string& spec, std::size_t index, std::size_t count) {
  const std::string label = rig_label(spec);
  note(run, "[" + std::to_string(index + 1) + "/" + std::to_string(count) + "] " + spec + ": loading");
  std::unique_ptr<Skinner> skinner;
  std::vector<EvalAnimation> animations;
  try {
    const isokit::Stage stage("loading and fitting " + spec);
    SkinSetup setup = run.args.setup.empty() ? SkinSetup{} : load_setup(run.args.setup);
    Rig rig = open_rig(spec, run.args.fps, {}, nullptr, setup.mask);
    animations = animations_of(rig, run.args);
    note(run, "  " + label + ": " + std::to_string(rig.rest.rows()) + " vertices, " +
                  std::to_string(rig.joints.size()) + " joints, " + std::to_string(rig.clips.size()) +
                  " clips; fitting");
    skinner = std::make_unique<Skinner>(std::move(rig), std::move(setup), fit_progress(run, label));
  } catch (const std::exception& e) {
    const std::string why = error_text(e);
    run.rows.push_back(isokit::eval::error_row(label, "—", "—", why));
    note(run, "  " + label + " failed: " + why);
    write_tables(run);
    return;
  }
  const bool closed = mesh_is_closed(skinner->rig());
  // Once per rig: the rest mesh and field are those of every animation.
  const RestAgreement agreement = rest_agreement(skinner->fitted(), skinner->field(TreeKind::k2014));
  for (const EvalAnimation& anim : animations) {
    note(run, "  " + label + " / " + describe(skinner->rig(), anim));
    try {
      evaluate_animation(run, *skinner, label, anim, closed, agreement);
    } catch (const std::exception& e) {
      const std::string why = error_text(e);
      run.rows.push_back(isokit::eval::error_row(label, anim.name, "—", why));
      note(run, "  " + label + " / " + anim.name + " failed: " + why);
    }
    write_tables(run);
  }
}

}  // namespace

namespace isokit::eval {

std::vector<std::string> rigs_of(const EvalOptions& options) {
  return rig_list(options);
}

std::vector<Row> run_evaluation(const EvalOptions& options) {
  Run run;
  run.args = options;
  for (const std::string& m : run.args.methods) method_from_string(m);
  const std::vector<std::string> rigs = rig_list(run.args);
  if (rigs.empty()) throw isokit::InputError("isokit-eval: no rig found; give --rigs DIR or --rig FILE");
  for (std::size_t i = 0; i < rigs.size(); ++i) evaluate_rig(run, rigs[i], i, rigs.size());
  write_tables(run);
  const auto failed = std::count_if(run.rows.begin(), run.rows.end(), [](const Row& r) {
    return r.contains("error") && r["error"].is_string();
  });
  note(run, "done: " + std::to_string(run.rows.size()) + " rows (" + std::to_string(failed) + " failed) in " +
                run.args.out + "/eval.json and eval.md");
  return run.rows;
}

}  // namespace isokit::eval
