// SPDX-License-Identifier: MIT
// isokit-opdesigner: generate, plot, compose and inspect composition operators (2014 §4), and
// design them interactively (`gui`).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <new>
#include <optional>
#include <string>

#include "isokit/core/error.h"
#include "isokit/core/stage.h"
#include "isokit/opdesigner/designer.h"
#include "isokit/operators/biharmonic.h"
#include "isokit/operators/checks.h"
#include "isokit/operators/io.h"
#include "isokit/studio/gui.h"

using namespace isokit;
using namespace isokit::operators;

namespace {

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : "|") + x;
  return s;
}

int run_generate(const std::string& preset, const std::string& spec_path, int res, int slices,
                 const std::string& backend, const std::string& out) {
  require(out.size() > 4 && out.substr(out.size() - 4) == ".npy", "--out",
          "must end in .npy (got '" + out + "')", "the spec is written beside it as .json");
  OperatorSpec spec;
  if (!spec_path.empty()) {
    spec = load_spec(spec_path);
  } else {
    require(!preset.empty(), "generate", "needs --preset or --spec", "e.g. --preset contact");
    spec = preset_spec(preset, 128);
  }
  if (res > 0) {
    spec.resolution = res;
    spec.slices = res;
  }
  if (slices > 0) spec.slices = slices;
  validate(spec, spec_path.empty() ? "preset '" + preset + "'" : spec_path);
  BiharmonicOptions o;
  o.backend = backend == "cholmod"
                  ? SparseBackend::kCholmod
                  : (backend == "sparselu" ? SparseBackend::kSparseLU : SparseBackend::kAuto);
  int last_pct = -1;
  o.progress = [&](int done, int total) {
    const int pct = 100 * done / total;
    if (pct / 10 != last_pct / 10 || done == total) {
      std::fprintf(stderr, "\rgenerate: slice %d/%d (%d%%)", done, total, pct);
      if (done == total) std::fprintf(stderr, "\n");
      last_pct = pct;
    }
  };
  const auto t0 = std::chrono::steady_clock::now();
  const Stage stage("generating a " + std::to_string(spec.slices) + " x " + std::to_string(spec.resolution) +
                    " x " + std::to_string(spec.resolution) + " operator grid");
  BiharmonicOperatorGenerator gen(spec, o);
  const GridOperator grid = gen.generate();
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  save_operator(out, spec, grid);
  std::printf("wrote %s and %s: %d slices of %dx%d (%s, %s, %d dynamic nodes) in %.3f s\n", out.c_str(),
              spec_path_for(out).c_str(), grid.nd(), grid.nf(), grid.nf(), gen.stats().backend.c_str(),
              gen.stats().scheme.c_str(), gen.stats().dynamic_nodes, secs);
  return 0;
}

int run_inspect(const std::string& path, bool quiet) {
  const StoredOperator op = load_operator(path);
  const double h = 1.0 / (op.grid.nf() - 1);
  std::printf("%s: '%s', %d slices of %dx%d, cell h = %.6f\n", path.c_str(), op.spec.name.c_str(),
              op.grid.nd(), op.grid.nf(), op.grid.nf(), h);
  if (!quiet)
    std::printf("%5s %8s %12s %12s %12s %12s %12s %10s %8s\n", "slice", "d", "bc_err", "axis_slope",
                "iso->prof", "prof->iso", "contact_err", "contact_len", "nonmono");
  SliceReport worst;
  int worst_mono = 0, bad = 0;
  std::string first_failure;
  for (int k = 0; k < op.grid.nd(); ++k) {
    const SliceReport r = inspect_slice(op.spec, op.grid, k);
    if (!quiet)
      std::printf("%5d %8.4f %12.3e %12.3e %12.3e %12.3e %12.3e %10.4f %8d\n", k, r.d, r.boundary_error,
                  r.axis_slope, r.iso_to_profile, r.profile_to_iso, r.contact_error, r.contact_length,
                  r.monotonicity_violations);
    worst.boundary_error = std::max(worst.boundary_error, r.boundary_error);
    worst.axis_slope = std::max(worst.axis_slope, r.axis_slope);
    worst.iso_to_profile = std::max(worst.iso_to_profile, r.iso_to_profile);
    worst.profile_to_iso = std::max(worst.profile_to_iso, r.profile_to_iso);
    worst.contact_error = std::max(worst.contact_error, r.contact_error);
    worst_mono = std::max(worst_mono, r.monotonicity_violations);
    worst.monotonicity_max_drop = std::max(worst.monotonicity_max_drop, r.monotonicity_max_drop);
    if (const auto failure = judge_slice(r)) {
      if (bad == 0) first_failure = failure->message();
      ++bad;
    }
  }
  std::printf(
      "worst: bc_err %.3e, axis_slope %.3e, iso->profile %.3e (%.2f cells), profile->iso %.3e (%.2f cells), "
      "contact_err %.3e, max non-monotone node pairs per slice %d (largest drop %.3e)\n",
      worst.boundary_error, worst.axis_slope, worst.iso_to_profile, worst.iso_to_profile / h,
      worst.profile_to_iso, worst.profile_to_iso / h, worst.contact_error, worst_mono,
      worst.monotonicity_max_drop);
  std::printf("%s\n",
              bad == 0
                  ? "checks: ok (bc <= 1e-5, 0.5 iso-line within one cell of the profile)"
                  : ("checks: " + std::to_string(bad) + " slice(s) FAIL; first: " + first_failure).c_str());
  return bad == 0 ? 0 : 3;
}

/// `gui [SPEC] [--size WxH] [--script FILE] [--screenshot-dir DIR] [--report FILE] [--res N]`.
CLI::App* add_gui_command(CLI::App& app, studio::GuiOptions& o, std::string& size) {
  auto* gui =
      app.add_subcommand("gui", "the interactive operator design studio (GLFW + OpenGL + Dear ImGui)");
  gui->add_option("spec", o.spec_path, "operator spec JSON to open (default: --preset)");
  gui->add_option("--preset", o.preset, "preset to start from without a spec: " + join(preset_spec_names()));
  gui->add_option("--res", o.resolution, "override the grid resolution and slice count (e.g. 48 for tests)");
  gui->add_option("--size", size, "window size WxH (default 1280x800)");
  gui->add_option("--script", o.script_path,
                  "replay input events from a JSON script, then exit (headless tests)");
  gui->add_option("--screenshot-dir", o.screenshot_dir, "folder for the script's screenshots (default .)");
  gui->add_option("--report", o.report_path,
                  "JSON report at exit (default with --script: DIR/studio-report.json)");
  gui->add_option("--recent-files", o.recent_files,
                  "recent-files list: a JSON path, \"\" for none, or default");
  return gui;
}

int run_gui_command(studio::GuiOptions o, const std::string& size) {
  if (!size.empty()) {
    const auto x = size.find('x');
    const bool digits = x != std::string::npos && size.find('x', x + 1) == std::string::npos && x > 0 &&
                        x + 1 < size.size() && size.find_first_not_of("0123456789x") == std::string::npos &&
                        x + 6 >= size.size() && x <= 5;
    require(digits, "--size", "is not WxH (got '" + size + "')", "e.g. --size 1280x800");
    o.width = std::stoi(size.substr(0, x));
    o.height = std::stoi(size.substr(x + 1));
    require(o.width >= 320 && o.height >= 240 && o.width <= 8192 && o.height <= 8192, "--size",
            "must be between 320x240 and 8192x8192 (got '" + size + "')", "e.g. --size 1280x800");
  }
#ifdef ISOKIT_HAVE_GUI
  return studio::run_gui(o);
#else
  require(false, "isokit-opdesigner gui", "this build has no GUI (GLFW, OpenGL or imgui was not found)",
          "run scripts/install-deps.sh and reconfigure with -DISOKIT_GUI=ON");
  return 1;
#endif
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"isokit-opdesigner: design composition operators g(f1, f2; d) (Vaillant et al. 2014, §4)"};
  app.require_subcommand(1);

  std::string preset, spec_path, out, backend = "auto";
  int res = 0, slices = 0;
  auto* gen = app.add_subcommand("generate", "solve the biharmonic operator from a preset or a spec");
  gen->add_option("--preset", preset, "preset: " + join(preset_spec_names()));
  gen->add_option("--spec", spec_path, "operator spec JSON (overrides --preset)");
  gen->add_option("--res", res, "nodes per f axis and number of d slices (default 128, or the spec's)");
  gen->add_option("--slices", slices, "number of d slices (default: --res)");
  gen->add_option("--backend", backend, "sparse solver: auto|cholmod|sparselu");
  gen->add_option("--out", out, "output X.npy (X.json is written beside it)")->required();

  std::string in_path;
  double d = 0.5;
  auto* plot = app.add_subcommand("plot", "heat map of one slice with iso-lines and the profile");
  plot->add_option("operator", in_path, "X.npy (with X.json beside it)")->required();
  plot->add_option("--d", d, "operator parameter d in [0, 1]");
  plot->add_option("--out", out, "figure .png|.svg|.pdf")->required();

  double angle = 120, cd = -1;
  int pixels = 560;
  auto* comp = app.add_subcommand("compose", "compose two capsule fields at a joint with the operator");
  comp->add_option("operator", in_path, "X.npy (with X.json beside it)")->required();
  comp->add_option("--angle", angle, "joint bend angle in degrees (0 = straight)");
  auto* dopt = comp->add_option("--d", cd, "fixed d (default: the spec's controller d(alpha) per point)");
  comp->add_option("--pixels", pixels, "figure width");
  comp->add_option("--out", out, "figure .png|.svg|.pdf")->required();

  bool quiet = false;
  auto* insp = app.add_subcommand("inspect",
                                  "per-slice checks: boundary conditions, iso-line vs profile, monotonicity");
  insp->add_option("operator", in_path, "X.npy (with X.json beside it)")->required();
  insp->add_flag("--summary", quiet, "print only the worst values");

  studio::GuiOptions gui_options;
  std::string gui_size;
  auto* gui = add_gui_command(app, gui_options, gui_size);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (gen->parsed()) return run_generate(preset, spec_path, res, slices, backend, out);
    if (plot->parsed()) {
      opdesigner::plot_slice(load_operator(in_path), d, out);
      std::printf("wrote %s\n", out.c_str());
      return 0;
    }
    if (comp->parsed()) {
      opdesigner::ComposeOptions o;
      o.angle_deg = angle;
      if (dopt->count() > 0) o.d = cd;
      o.pixels = pixels;
      const auto st = opdesigner::compose(load_operator(in_path), o, out);
      std::printf("wrote %s: contact length %.4f, max d %.3f\n", out.c_str(), st.contact_length, st.max_d);
      return 0;
    }
    if (insp->parsed()) return run_inspect(in_path, quiet);
    if (gui->parsed()) return run_gui_command(gui_options, gui_size);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "isokit-opdesigner: error: %s\n", isokit::out_of_memory_message().c_str());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "isokit-opdesigner: error: %s\n", e.what());
    return 1;
  }
  return 1;
}
