// SPDX-License-Identifier: MIT
// isokit-eval: the real-rig evaluation (eval_run.h, docs/skinning-real-rigs.md). Prints the
// Markdown table on stdout; progress on stderr; exit 0 when the run completes (failed rigs and
// bakes are rows), 2 for bad options.
#include <CLI/CLI.hpp>
#include <cstdio>

#include "eval_run.h"

namespace {

void add_options(CLI::App& app, isokit::eval::EvalOptions& a) {
  app.add_option("--rig", a.rigs, "a rig file or procedural:<spec> (repeatable)");
  app.add_option("--rigs", a.folders, "a folder: every .glb/.gltf/.fbx/.dae in it (repeatable)");
  app.add_option("--only", a.only, "keep the rigs whose path contains this (repeatable)");
  app.add_option("--clip", a.clips, "keep these animations only; 'bend' = the bend-and-return (repeatable)");
  app.add_option("--methods", a.methods, "methods to bake")->capture_default_str();
  app.add_option("--max-frames", a.max_frames, "first N frames of each clip (0 = all)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--bend-frames", a.bend_frames, "frames of the bend-and-return (rest, peak, rest)")
      ->capture_default_str()
      ->check(CLI::Range(3, 10000));
  app.add_option("--bend-degrees", a.bend_degrees, "peak angle of the bend-and-return")
      ->capture_default_str();
  app.add_option("--fps", a.fps, "clip sampling rate")->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--out", a.out, "output folder")->capture_default_str();
  app.add_option("--commit", a.commit, "commit recorded in the tables");
  app.add_option("--setup", a.setup, "a setup file for every rig (isokit-skin --setup; default: none)")
      ->check(CLI::ExistingFile);
  app.add_flag("!--no-render", a.render, "skip the contact sheets");
  app.add_flag("!--no-self-intersections", a.self_intersections, "skip the exact self-intersection counts");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "isokit-eval: every clip of every rig, plus elbow/knee bend-and-return, with dqs, ddm, cor, "
      "implicit2013 and tracking2014 (docs/skinning-real-rigs.md)"};
  isokit::eval::EvalOptions options;
  add_options(app, options);
  CLI11_PARSE(app, argc, argv);
  try {
    const std::vector<isokit::eval::Row> rows = isokit::eval::run_evaluation(options);
    std::printf("%s", isokit::eval::markdown_table(rows).c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "isokit-eval: error: %s\n", e.what());
    return 2;
  }
  return 0;
}
