// SPDX-License-Identifier: MIT
#include "isokit/skinning/setup.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <type_traits>

#include "isokit/core/error.h"
#include "isokit/operators/controller.h"

namespace isokit::skinning {

const char* to_string(JointOperator op) {
  switch (op) {
    case JointOperator::kUnion:
      return "union";
    case JointOperator::kBlend:
      return "blend";
    case JointOperator::kBulge:
      return "bulge";
    case JointOperator::kContact:
      return "contact";
    case JointOperator::kAuto:
      break;
  }
  return "auto";
}

const char* to_string(InitialSkinning s) {
  switch (s) {
    case InitialSkinning::kDdm:
      return "ddm";
    case InitialSkinning::kCor:
      return "cor";
    case InitialSkinning::kDqs:
      break;
  }
  return "dqs";
}

InitialSkinning initial_skinning_from_string(const std::string& s, const std::string& where) {
  for (InitialSkinning i : {InitialSkinning::kDqs, InitialSkinning::kDdm, InitialSkinning::kCor})
    if (s == to_string(i)) return i;
  throw InputError(where + ": unknown initial skinning '" + s + "'; use dqs, ddm or cor");
}

JointOperator joint_operator_from_string(const std::string& s, const std::string& where) {
  for (JointOperator op : {JointOperator::kAuto, JointOperator::kUnion, JointOperator::kBlend,
                           JointOperator::kBulge, JointOperator::kContact})
    if (s == to_string(op)) return op;
  throw InputError(where + ": unknown operator '" + s + "'; use auto, union, blend, bulge or contact");
}

JointOperator SkinSetup::operator_for(const std::string& joint, TreeKind t) const {
  auto it = joints.find(joint);
  JointOperator op = it != joints.end() ? it->second.op : JointOperator::kAuto;
  if (op == JointOperator::kAuto) op = default_operator;
  if (op == JointOperator::kAuto) op = t == TreeKind::k2013 ? JointOperator::kBlend : JointOperator::kContact;
  return op;
}

double MuscleSetup::scale_at(double bend_rad) const {
  const double deg = bend_rad * 180.0 / kPi;
  if (curve.empty()) return 1.0;
  if (deg <= curve.front().first) return curve.front().second;
  for (std::size_t k = 1; k < curve.size(); ++k)
    if (deg <= curve[k].first) {
      const double t = (deg - curve[k - 1].first) / (curve[k].first - curve[k - 1].first);
      return curve[k - 1].second + t * (curve[k].second - curve[k - 1].second);
    }
  return curve.back().second;
}

float SkinSetup::relaxation_for(const std::string& joint) const {
  auto it = joints.find(joint);
  return it != joints.end() ? it->second.relaxation : 1.0f;
}

namespace {

/// A joint's own spec needs a grid operator (contact or bulge). \throw InputError otherwise.
void require_grid_joint(const SpecFile& file, const std::string& joint, JointOperator op,
                        const std::string& why) {
  require(
      op == JointOperator::kContact || op == JointOperator::kBulge, file.key,
      "joint '" + joint + "' has an operator spec, but its operator is '" + to_string(op) + "'" + why +
          ", which has no grid",
      "set joints." + joint + ".operator to \"contact\" or \"bulge\", or remove joints." + joint + ".spec");
}

}  // namespace

const SpecFile* SkinSetup::spec_for(const std::string& joint, JointOperator op) const {
  auto it = joints.find(joint);
  if (it != joints.end() && it->second.spec) {
    require_grid_joint(*it->second.spec, joint, op, " (as resolved for this tree)");
    return &*it->second.spec;
  }
  if (op == JointOperator::kContact && contact_spec) return &*contact_spec;
  if (op == JointOperator::kBulge && bulge_spec) return &*bulge_spec;
  return nullptr;
}

namespace {

using nlohmann::json;

/// A JSON number as the arithmetic type T, checked: nlohmann's `get<T>` converts a number out
/// of T's range (1e300 into an int) with undefined behaviour (found while fuzzing, docs/fuzzing.md).
/// Integer keys take JSON integers only.
template <class T>
T checked_number(const json& v, const std::string& where) {
  using Lim = std::numeric_limits<T>;
  const std::string fix = "see the setup format in docs/skinning.md";
  if constexpr (std::is_integral_v<T>) {
    require(v.is_number_integer(), where, "must be an integer (got " + v.dump() + ")", fix);
    bool fits = false;
    if (v.is_number_unsigned())
      fits = v.get<std::uint64_t>() <= static_cast<std::uint64_t>(Lim::max());
    else if constexpr (std::is_signed_v<T>)
      fits = v.get<std::int64_t>() >= Lim::min() && v.get<std::int64_t>() <= Lim::max();
    else
      fits = v.get<std::int64_t>() >= 0 && static_cast<std::uint64_t>(v.get<std::int64_t>()) <= Lim::max();
    require(fits, where, "out of range (got " + v.dump() + ")", fix);
    return v.is_number_unsigned() ? static_cast<T>(v.get<std::uint64_t>())
                                  : static_cast<T>(v.get<std::int64_t>());
  } else {
    require(v.is_number(), where, "must be a number (got " + v.dump() + ")", fix);
    const double d = v.get<double>();
    require(std::isfinite(d) && std::abs(d) <= static_cast<double>(Lim::max()), where,
            "out of range (got " + v.dump() + ")", fix);
    return static_cast<T>(d);
  }
}

template <class T>
void read(const json& obj, const char* key, T& out, const std::string& where) {
  if (!obj.contains(key)) return;
  if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
    out = checked_number<T>(obj.at(key), where + "." + key);
  } else {
    try {
      out = obj.at(key).get<T>();
    } catch (const json::exception&) {
      throw InputError(where + "." + key + ": wrong type (" + obj.at(key).dump() +
                       "); see the setup format in docs/skinning.md");
    }
  }
}

void check_keys(const json& obj, std::initializer_list<const char*> keys, const std::string& where) {
  require(obj.is_object(), where, "must be a JSON object", "see the setup format in docs/skinning.md");
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    bool known = false;
    std::string list;
    for (const char* k : keys) {
      known = known || it.key() == k;
      list += std::string(list.empty() ? "" : ", ") + k;
    }
    require(known, where + "." + it.key(), "unknown key", "valid keys: " + list);
  }
}

/// The spec file named by `obj[key]` (a relative path is joined to `base_dir`), loaded.
SpecFile read_spec_file(const json& obj, const char* key, const std::string& where,
                        const std::string& base_dir) {
  std::string path;
  read(obj, key, path, where);
  SpecFile f;
  f.key = where + "." + key;
  require(!path.empty(), f.key, "is empty",
          "give the path of an isokit-operator-spec JSON file (isokit-opdesigner writes them)");
  namespace fs = std::filesystem;
  f.path = fs::path(path).is_relative() && !base_dir.empty()
               ? (fs::path(base_dir) / path).lexically_normal().string()
               : path;
  // A regular file only: a folder or a device (/dev/zero) would fail late or never.
  std::error_code ec;
  require(
      fs::is_regular_file(f.path, ec), f.key, "'" + f.path + "' is not a readable file",
      "give the path of an isokit-operator-spec JSON file; a relative path is relative to the setup file's "
      "folder");
  try {
    f.spec = operators::load_spec(f.path);
  } catch (const InputError& e) {
    throw InputError(f.key + ": " + e.what());
  }
  return f;
}

/// `tree`: "auto", "2013" or "2014".
TreeKind tree_from_json(const json& j, const std::string& source) {
  std::string tree = "auto";
  read(j, "tree", tree, source);
  if (tree == "2013") return TreeKind::k2013;
  if (tree == "2014") return TreeKind::k2014;
  require(tree == "auto", source + ".tree", "unknown tree '" + tree + "'", "use auto, 2013 or 2014");
  return TreeKind::kAuto;
}

/// Section `joints`: operator and relaxation per joint name.
void read_joints(const json& js, const std::string& source, const std::string& base_dir, SkinSetup& s) {
  require(js.is_object(), source + ".joints", "must be an object keyed by joint name",
          "see docs/skinning.md");
  for (auto it = js.begin(); it != js.end(); ++it) {
    const std::string w = source + ".joints." + it.key();
    check_keys(it.value(), {"operator", "relaxation", "spec"}, w);
    JointSettings js_;
    std::string op = "auto";
    read(it.value(), "operator", op, w);
    js_.op = joint_operator_from_string(op, w + ".operator");
    read(it.value(), "relaxation", js_.relaxation, w);
    require(js_.relaxation >= 0 && js_.relaxation <= 1, w + ".relaxation",
            "must be in [0, 1] (got " + format_number(js_.relaxation) + ")",
            "0 = rigid with the joint, 1 = tracked (between: pulled toward the rigid position)");
    if (it.value().contains("spec")) {
      js_.spec = read_spec_file(it.value(), "spec", w, base_dir);
      if (js_.op == JointOperator::kUnion || js_.op == JointOperator::kBlend)
        require_grid_joint(*js_.spec, it.key(), js_.op, "");
      if (js_.op == JointOperator::kAuto &&
          (s.default_operator == JointOperator::kUnion || s.default_operator == JointOperator::kBlend))
        require_grid_joint(*js_.spec, it.key(), s.default_operator, " (default_operator)");
    }
    s.joints[it.key()] = js_;
  }
}

/// A storage key (`fit.grid_storage`, `operators.storage`): "fixed16" or "float32".
/// `also`: other accepted values, named in the message.
void read_storage(const json& o, const char* key, implicit::GridStorage& out, const std::string& w,
                  const std::string& also = "") {
  if (!o.contains(key)) return;
  const json& k = o.at(key);
  require(k.is_string() && (k == "fixed16" || k == "float32"), w + "." + key,
          "must be " + also + "\"fixed16\" or \"float32\" (got " + k.dump() + ")",
          "use " + also + "\"fixed16\" (half the memory) or \"float32\" (the reference)");
  out = k == "fixed16" ? implicit::GridStorage::fixed16 : implicit::GridStorage::float32;
}

/// Section `fit.distance`: the distance field of each part (implicit::DistanceFitOptions).
void read_distance_fit(const json& d, const std::string& w, implicit::DistanceFitOptions& o) {
  check_keys(d,
             {"cells_per_feature", "feature_percentile", "min_resolution", "max_resolution", "cap_height",
              "width_percentile", "overlap_rings", "overlap_sink", "smoothing_passes"},
             w);
  read(d, "cells_per_feature", o.cells_per_feature, w);
  read(d, "feature_percentile", o.feature_percentile, w);
  read(d, "min_resolution", o.min_resolution, w);
  read(d, "max_resolution", o.max_resolution, w);
  read(d, "cap_height", o.cap_height, w);
  read(d, "width_percentile", o.width_percentile, w);
  read(d, "overlap_rings", o.overlap_rings, w);
  read(d, "overlap_sink", o.overlap_sink, w);
  read(d, "smoothing_passes", o.smoothing_passes, w);
  implicit::check_distance_options(o, w);
}

/// Section `fit`: the fit of each part (implicit::PartFitOptions).
void read_fit(const json& f, const std::string& w, implicit::PartFitOptions& fit, double& capsule_match,
              double& max_fit_error) {
  check_keys(f,
             {"samples", "cull_h", "grid_resolution", "seed", "grid", "opening_offset", "closure",
              "cap_height", "capsule_match", "max_error", "field", "distance", "grid_storage"},
             w);
  if (f.contains("field")) {
    const json& k = f.at("field");
    require(
        k.is_string() && (k == "hrbf" || k == "distance"), w + ".field",
        "must be \"hrbf\" or \"distance\" (got " + k.dump() + ")",
        "use \"distance\" (the default: the part's own surface) or \"hrbf\" (2013 §4.1, the paper preset)");
    fit.field = k == "hrbf" ? implicit::PartFitOptions::FieldKind::hrbf
                            : implicit::PartFitOptions::FieldKind::distance;
  }
  if (f.contains("distance")) read_distance_fit(f.at("distance"), w + ".distance", fit.distance);
  read_storage(f, "grid_storage", fit.grid_storage, w);
  read(f, "capsule_match", capsule_match, w);
  require(std::isfinite(capsule_match) && capsule_match >= 0 && capsule_match <= 10, w + ".capsule_match",
          "must be in [0, 10] (got " + format_number(capsule_match) + ")",
          "use 0 (off, the default) or e.g. 0.5");
  read(f, "max_error", max_fit_error, w);
  require(std::isfinite(max_fit_error) && max_fit_error >= 0 && max_fit_error <= 100, w + ".max_error",
          "must be in [0, 100] (got " + format_number(max_fit_error) + ")",
          "use 0 (off, the default: keep every fit that solves) or 1");
  read(f, "samples", fit.target_samples, w);
  read(f, "cull_h", fit.cull_h, w);
  read(f, "grid_resolution", fit.grid_resolution, w);
  read(f, "seed", fit.seed, w);
  read(f, "grid", fit.sample_grid, w);
  read(f, "opening_offset", fit.opening_offset, w);
  require(fit.opening_offset >= 0 && fit.opening_offset <= 2, w + ".opening_offset",
          "must be in [0, 2] (got " + format_number(fit.opening_offset) + ")", "use 0.1 (the default)");
  if (f.contains("closure")) {
    const json& c = f.at("closure");
    require(c.is_string() && (c == "best" || c == "joints" || c == "border_caps"), w + ".closure",
            "must be \"best\", \"joints\" or \"border_caps\" (got " + c.dump() + ")",
            "use \"joints\" (2013 §4.1, the default) or \"best\"");
    using Closure = implicit::PartFitOptions::Closure;
    fit.closure = c == "joints" ? Closure::joints : c == "border_caps" ? Closure::border_caps : Closure::best;
  }
  read(f, "cap_height", fit.cap_height, w);
  require(std::isfinite(fit.cap_height) && fit.cap_height >= 0 && fit.cap_height <= 2, w + ".cap_height",
          "must be in [0, 2] (got " + format_number(fit.cap_height) + ")", "use 1 (the default)");
  require(fit.target_samples >= 4 && fit.target_samples <= 2000, w + ".samples", "must be in [4, 2000]",
          "the paper uses 50");
  require(fit.grid_resolution >= 4 && fit.grid_resolution <= 256, w + ".grid_resolution",
          "must be in [4, 256]", "the paper uses 32");
}

/// Section `operators`: grid operators and their controllers.
void read_operators(const json& o, const std::string& w, const std::string& base_dir, SkinSetup& s) {
  check_keys(o,
             {"resolution", "slices", "bulge_gate", "blend_grid", "contact_controller", "bulge_controller",
              "contact_spec", "bulge_spec", "storage"},
             w);
  if (o.contains("storage") && o.at("storage") == "auto") {
    s.operator_storage.reset();
  } else if (o.contains("storage")) {
    implicit::GridStorage storage{};
    read_storage(o, "storage", storage, w, "\"auto\" (the default), ");
    s.operator_storage = storage;
  }
  if (o.contains("contact_spec")) s.contact_spec = read_spec_file(o, "contact_spec", w, base_dir);
  if (o.contains("bulge_spec")) s.bulge_spec = read_spec_file(o, "bulge_spec", w, base_dir);
  read(o, "resolution", s.operator_resolution, w);
  read(o, "bulge_gate", s.bulge_gate, w);
  read(o, "blend_grid", s.blend_grid, w);
  read(o, "contact_controller", s.contact_controller, w);
  read(o, "bulge_controller", s.bulge_controller, w);
  const std::vector<std::string> presets = operators::Controller::preset_names();
  std::string list;
  for (const auto& n : presets) list += (list.empty() ? "" : ", ") + n;
  for (const auto& [key, name] :
       {std::pair<std::string, std::string>{"contact_controller", s.contact_controller},
        {"bulge_controller", s.bulge_controller}})
    require(std::find(presets.begin(), presets.end(), name) != presets.end(), w + "." + key,
            "unknown controller '" + name + "'", "use one of " + list);
  read(o, "slices", s.operator_slices, w);
  require(s.operator_resolution >= 8 && s.operator_resolution <= 1024, w + ".resolution",
          "must be in [8, 1024]", "the paper uses 128");
  require(s.operator_slices >= 8 && s.operator_slices <= 1024, w + ".slices", "must be in [8, 1024]",
          "the paper uses 128");
  const long long cells =
      static_cast<long long>(s.operator_slices) * s.operator_resolution * s.operator_resolution;
  require(cells <= operators::kMaxOperatorCells, w + ".slices x resolution^2",
          "is " + std::to_string(cells) + " cells, more than the " +
              std::to_string(operators::kMaxOperatorCells) + " an operator grid may have (512 MiB)",
          "lower the resolution or the slices (the paper uses 128 x 128 x 128)");
}

/// Section `tracker`, the repairs: fold repair and orientation repair (track::TrackerOptions).
void read_tracker_repairs(const json& t, const std::string& w, SkinSetup& s) {
  read(t, "fold_repair_rounds", s.tracker.fold_repair.rounds, w);
  read(t, "fold_repair_steps", s.tracker.fold_repair.steps, w);
  read(t, "fold_repair_rings", s.tracker.fold_repair.rings, w);
  read(t, "fold_repair_max_fraction", s.tracker.fold_repair.max_fraction, w);
  read(t, "fold_repair_min_part_vertices", s.fold_repair_min_part_vertices, w);
  require(s.fold_repair_min_part_vertices >= 0, w + ".fold_repair_min_part_vertices", "must be >= 0",
          "use e.g. 50 (0: no limit)");
  require(s.tracker.fold_repair.max_fraction >= 0 && s.tracker.fold_repair.max_fraction <= 1,
          w + ".fold_repair_max_fraction", "must be in [0, 1]", "use e.g. 0.1");
  require(s.tracker.fold_repair.rounds >= 0 && s.tracker.fold_repair.steps >= 0 &&
              s.tracker.fold_repair.rings >= 0,
          w + ".fold_repair_*", "must be >= 0", "use e.g. 8 rounds of 5 steps over 2 rings (0 rounds: off)");
  track::OrientationRepairOptions& r = s.tracker.orientation_repair;
  read(t, "orientation_repair_rounds", r.rounds, w);
  read(t, "orientation_repair_max_move", r.max_move, w);
  read(t, "orientation_repair_max_outward_move", r.max_outward_move, w);
  require(r.rounds >= 0, w + ".orientation_repair_rounds", "must be >= 0", "use e.g. 8 (0: off)");
  require(std::isfinite(r.max_move) && r.max_move > 0.f && r.max_move <= 4.f,
          w + ".orientation_repair_max_move", "must be in (0, 4] (edge lengths)", "use e.g. 0.5");
  require(std::isfinite(r.max_outward_move) && r.max_outward_move >= 0.f && r.max_outward_move <= r.max_move,
          w + ".orientation_repair_max_outward_move", "must be in [0, orientation_repair_max_move]",
          "use e.g. 0.125");
}

/// Section `tracker`: the 2014 tracker (track::TrackerOptions) and the axis guard.
/// Section `tracker`, the keys of what is not tracked: rigid pieces and small parts.
void read_tracker_rigid(const json& t, const std::string& w, SkinSetup& s) {
  read(t, "rigid_pieces", s.rigid_pieces, w);
  read(t, "piece_fields", s.piece_fields, w);
  read(t, "small_part_mask", s.small_part_mask, w);
  require(s.small_part_mask >= 0.f && s.small_part_mask <= 1.f, w + ".small_part_mask",
          "must be in [0, 1] (got " + format_number(s.small_part_mask) + ")",
          "1 = off, 0 = DQS on small parts");
  read(t, "small_part_vertices", s.small_part_vertices, w);
  require(s.small_part_vertices >= 0, w + ".small_part_vertices", "must be >= 0", "use e.g. 100");
}

/// Keys `tracker.energy_*`: the local–global solve's options (track::EnergySolveOptions).
void read_tracker_energy(const json& t, const std::string& w, track::EnergySolveOptions& e) {
  read(t, "energy_iso_weight", e.iso_weight, w);
  require(std::isfinite(e.iso_weight) && e.iso_weight > 0.f, w + ".energy_iso_weight", "must be > 0",
          "use 10 (the default)");
  read(t, "energy_tangent_weight", e.tangent_weight, w);
  require(std::isfinite(e.tangent_weight) && e.tangent_weight > 0.f && e.tangent_weight <= 1.f,
          w + ".energy_tangent_weight", "must be in (0, 1]", "use 0.01 (the default) or 1 (point targets)");
  read(t, "energy_anchor_weight", e.anchor_weight, w);
  require(std::isfinite(e.anchor_weight) && e.anchor_weight >= 0.f, w + ".energy_anchor_weight",
          "must be >= 0", "use 100 (the default)");
  read(t, "energy_contact_offset", e.contact_offset, w);
  require(std::isfinite(e.contact_offset) && e.contact_offset >= 0.f, w + ".energy_contact_offset",
          "must be >= 0 (edges)", "use 0.1 (the default)");
  read(t, "energy_max_search", e.max_search, w);
  require(std::isfinite(e.max_search) && e.max_search > 0.f, w + ".energy_max_search", "must be > 0 (edges)",
          "use 1 (the default)");
  read(t, "energy_anderson_window", e.anderson_window, w);
  require(e.anderson_window >= 0 && e.anderson_window <= 20, w + ".energy_anderson_window",
          "must be in [0, 20]", "use 5 (the default) or 0 (plain iterations)");
}

/// The keys section `tracker` may hold.
void check_tracker_keys(const json& t, const std::string& w) {
  check_keys(t,
             {"max_iterations",
              "tolerance",
              "sigma",
              "contact_angle_deg",
              "initial_newton_steps",
              "smoothing_steps",
              "beta_diffusion_steps",
              "angle_contacts",
              "relaxation",
              "lazy_evaluation",
              "fold_repair_rounds",
              "fold_repair_steps",
              "fold_repair_rings",
              "fold_repair_max_fraction",
              "fold_repair_min_part_vertices",
              "small_part_mask",
              "small_part_vertices",
              "orientation_repair_rounds",
              "orientation_repair_max_move",
              "orientation_repair_max_outward_move",
              "axis_guard",
              "rigid_pieces",
              "piece_fields",
              "chebyshev_rho",
              "active_set",
              "min_contact_damping",
              "fold_contacts",
              "free_vertex_angle_deg",
              "smoothing_keep_detail",
              "smoothing_tangential",
              "smoothing_reproject_steps",
              "iso_tolerance",
              "global_regularization",
              "energy_iso_weight",
              "energy_tangent_weight",
              "energy_anchor_weight",
              "energy_contact_offset",
              "energy_max_search",
              "energy_anderson_window",
              "anchor"},
             w);
}

void read_tracker(const json& t, const std::string& w, SkinSetup& s) {
  check_tracker_keys(t, w);
  std::string anchor = to_string(s.tracker_anchor);
  read(t, "anchor", anchor, w);
  s.tracker_anchor = initial_skinning_from_string(anchor, w + ".anchor");
  if (t.contains("relaxation")) {
    std::string relaxation;
    read(t, "relaxation", relaxation, w);
    if (relaxation == "cg")
      s.tracker.relaxation = track::Relaxation::kConjugateGradient;
    else if (relaxation == "jacobi")
      s.tracker.relaxation = track::Relaxation::kJacobi;
    else if (relaxation == "energy")
      s.tracker.relaxation = track::Relaxation::kEnergy;
    else
      require(relaxation == "global", w + ".relaxation", "unknown solver '" + relaxation + "'",
              "use energy, jacobi (2014), global or cg");
    if (relaxation == "global") s.tracker.relaxation = track::Relaxation::kGlobal;
  }
  read_tracker_energy(t, w, s.tracker.energy);
  read(t, "max_iterations", s.tracker.max_iterations, w);
  read(t, "tolerance", s.tracker.tolerance, w);
  read(t, "sigma", s.tracker.sigma, w);
  read(t, "contact_angle_deg", s.tracker.contact_angle_deg, w);
  read(t, "initial_newton_steps", s.tracker.initial_newton_steps, w);
  read(t, "smoothing_steps", s.tracker.smoothing.smoothing_steps, w);
  read(t, "beta_diffusion_steps", s.tracker.smoothing.beta_diffusion_steps, w);
  read(t, "angle_contacts", s.tracker.angle_contacts, w);
  read(t, "lazy_evaluation", s.tracker.lazy_evaluation, w);
  read(t, "axis_guard", s.axis_guard, w);
  read_tracker_rigid(t, w, s);
  read(t, "chebyshev_rho", s.tracker.chebyshev_rho, w);
  require(std::isfinite(s.tracker.chebyshev_rho) && s.tracker.chebyshev_rho >= 0.f &&
              s.tracker.chebyshev_rho < 1.f,
          w + ".chebyshev_rho", "must be in [0, 1)", "use 0.995 (the default) or 0 (plain Jacobi, 2014)");
  read(t, "active_set", s.tracker.active_set, w);
  read(t, "min_contact_damping", s.tracker.min_contact_damping, w);
  require(std::isfinite(s.tracker.min_contact_damping) && s.tracker.min_contact_damping > 0.f &&
              s.tracker.min_contact_damping <= 1.f,
          w + ".min_contact_damping", "must be in (0, 1]", "use 0.25 (the default) or 1 (no damping)");
  read(t, "fold_contacts", s.tracker.fold_contacts, w);
  read(t, "free_vertex_angle_deg", s.tracker.free_vertex_angle_deg, w);
  require(std::isfinite(s.tracker.free_vertex_angle_deg) && s.tracker.free_vertex_angle_deg > 0.f &&
              s.tracker.free_vertex_angle_deg <= 180.f,
          w + ".free_vertex_angle_deg", "must be in (0, 180]",
          "use 60 (the default) or 180 (every vertex held to its iso-value, 2014)");
  read(t, "smoothing_keep_detail", s.tracker.smoothing.keep_detail, w);
  read(t, "smoothing_tangential", s.tracker.smoothing.tangential, w);
  read(t, "smoothing_reproject_steps", s.tracker.smoothing.reproject_steps, w);
  require(s.tracker.smoothing.reproject_steps >= 0 && s.tracker.smoothing.reproject_steps <= 100,
          w + ".smoothing_reproject_steps", "must be in [0, 100]", "use 0 (none, 2013) or a few");
  read(t, "iso_tolerance", s.tracker.iso_tolerance, w);
  require(std::isfinite(s.tracker.iso_tolerance) && s.tracker.iso_tolerance > 0.f, w + ".iso_tolerance",
          "must be > 0 (field units)", "use 1e-3 (the default)");
  read(t, "global_regularization", s.tracker.global_regularization, w);
  require(std::isfinite(s.tracker.global_regularization) && s.tracker.global_regularization > 0.f,
          w + ".global_regularization", "must be > 0", "use 1e-4 (the default)");
  read_tracker_repairs(t, w, s);
}

/// Section `ddm`: Direct Delta Mush (DdmOptions).
void read_ddm(const json& p, const std::string& w, DdmOptions& o) {
  check_keys(p, {"smoothing_steps", "lambda", "kappa", "alpha", "variant", "prune"}, w);
  read(p, "smoothing_steps", o.smoothing_steps, w);
  read(p, "lambda", o.lambda, w);
  read(p, "kappa", o.kappa, w);
  read(p, "alpha", o.alpha, w);
  read(p, "prune", o.prune, w);
  std::string variant = to_string(o.variant);
  read(p, "variant", variant, w);
  o.variant = ddm_variant_from_string(variant, w + ".variant");
  check_ddm_options(o, w);
}

/// Section `cor`: optimized centers of rotation (CorOptions).
void read_cor(const json& p, const std::string& w, CorOptions& o) {
  check_keys(p, {"sigma", "fallback"}, w);
  read(p, "sigma", o.sigma, w);
  std::string fallback = to_string(o.fallback);
  read(p, "fallback", fallback, w);
  o.fallback = cor_fallback_from_string(fallback, w + ".fallback");
  check_cor_options(o, w);
}

/// Section `projector`: the 2013 projection (track::ProjectorOptions) and its initial skinning.
void read_projector(const json& p, const std::string& w, track::ProjectorOptions& projector,
                    InitialSkinning& initial) {
  check_keys(p,
             {"sigma", "max_iterations", "contact_angle_deg", "tolerance", "smoothing_steps",
              "beta_diffusion_steps", "stall_steps", "progress", "secant", "secant_max_factor", "initial"},
             w);
  std::string init = to_string(initial);
  read(p, "initial", init, w);
  initial = initial_skinning_from_string(init, w + ".initial");
  read(p, "sigma", projector.sigma, w);
  read(p, "max_iterations", projector.max_iterations, w);
  read(p, "contact_angle_deg", projector.contact_angle_deg, w);
  read(p, "tolerance", projector.tolerance, w);
  read(p, "smoothing_steps", projector.smoothing.smoothing_steps, w);
  read(p, "beta_diffusion_steps", projector.smoothing.beta_diffusion_steps, w);
  read(p, "stall_steps", projector.stall_steps, w);
  require(projector.stall_steps >= 0 && projector.stall_steps <= 255, w + ".stall_steps",
          "must be in [0, 255] (got " + std::to_string(projector.stall_steps) + ")",
          "use 3, or 0 for none (2013)");
  read(p, "progress", projector.progress, w);
  require(projector.progress > 0.f && projector.progress <= 1.f, w + ".progress", "must be in (0, 1]",
          "use 0.9");
  read(p, "secant", projector.secant, w);
  read(p, "secant_max_factor", projector.secant_max_factor, w);
  require(projector.secant_max_factor > 0.f && projector.secant_max_factor <= 1.f, w + ".secant_max_factor",
          "must be in (0, 1]", "use 0.7");
}

/// Section `mask`: where the rig file keeps the relaxation mask (MaskSource).
void read_mask(const json& m, const std::string& w, MaskSource& mask) {
  check_keys(m, {"attribute", "color_set", "channel"}, w);
  read(m, "attribute", mask.attribute, w);
  read(m, "color_set", mask.color_set, w);
  require(mask.color_set >= -1 && mask.color_set <= 7, w + ".color_set",
          "must be -1 .. 7 (got " + std::to_string(mask.color_set) + ")",
          "give the vertex-colour set that holds the mask (0 = the first), or -1 for none");
  std::string channel = "r";
  read(m, "channel", channel, w);
  const std::string names = "rgba";
  require(channel.size() == 1 && names.find(channel[0]) != std::string::npos, w + ".channel",
          "unknown channel '" + channel + "'", "use \"r\", \"g\", \"b\" or \"a\"");
  mask.channel = static_cast<int>(names.find(channel[0]));
}

/// A 3-vector key of a muscle.
Eigen::Vector3d read_vec3(const json& m, const char* key, const std::string& w) {
  std::vector<double> v;
  read(m, key, v, w);
  require(v.size() == 3, w + "." + key, "must be 3 numbers (got " + m.at(key).dump() + ")", "give [x, y, z]");
  for (double x : v)
    require(std::isfinite(x), w + "." + key, "has a value that is not finite", "give finite numbers");
  return {v[0], v[1], v[2]};
}

/// One entry of section `muscles` (MuscleSetup).
MuscleSetup read_muscle(const json& m, const std::string& w) {
  check_keys(m, {"name", "bone", "driver", "center", "axis", "radii", "scale_axes", "curve", "operator"}, w);
  MuscleSetup u;
  for (const char* key : {"bone", "driver", "center", "radii"})
    require(m.contains(key), w + "." + key, "is missing", "see docs/skinning.md, \"Muscles\"");
  read(m, "name", u.name, w);
  read(m, "bone", u.bone, w);
  read(m, "driver", u.driver, w);
  if (u.name.empty()) u.name = u.bone + " muscle";
  u.center = read_vec3(m, "center", w);
  if (m.contains("axis")) u.axis = read_vec3(m, "axis", w);
  u.radii = read_vec3(m, "radii", w);
  require(u.radii.minCoeff() > 0, w + ".radii", "must be > 0",
          "give the semi-axes at rest in the rig's units");
  if (m.contains("scale_axes")) {
    std::string axes;
    read(m, "scale_axes", axes, w);
    u.scaled = {false, false, false};
    for (char c : axes) {
      require(c == 'x' || c == 'y' || c == 'z', w + ".scale_axes", "unknown axis '" + std::string(1, c) + "'",
              "give a subset of \"xyz\" (x: the first semi-axis)");
      u.scaled[std::size_t(c - 'x')] = true;
    }
  }
  if (m.contains("curve")) {
    std::vector<std::vector<double>> knots;
    read(m, "curve", knots, w);
    require(!knots.empty(), w + ".curve", "is empty", "give [[degrees, factor], ...]");
    u.curve.clear();
    for (const std::vector<double>& k : knots) {
      require(k.size() == 2 && std::isfinite(k[0]) && std::isfinite(k[1]), w + ".curve",
              "each knot must be [degrees, factor]", "e.g. [[0, 1], [90, 1.4]]");
      require(
          k[0] >= 0 && k[0] <= 180 && k[1] > 0, w + ".curve",
          "knot [" + format_number(k[0]) + ", " + format_number(k[1]) + "] is outside [0, 180] x (0, inf)",
          "give bends in degrees and positive factors");
      require(u.curve.empty() || k[0] > u.curve.back().first, w + ".curve", "knots must ascend in degrees",
              "sort the knots by bend");
      u.curve.emplace_back(k[0], k[1]);
    }
  }
  std::string op = "blend";
  read(m, "operator", op, w);
  require(op == "blend" || op == "union", w + ".operator", "unknown operator '" + op + "'",
          "use \"blend\" (the default) or \"union\"");
  u.op = op == "union" ? JointOperator::kUnion : JointOperator::kBlend;
  return u;
}

/// Section `muscles`: a list of MuscleSetup.
void read_muscles(const json& list, const std::string& w, std::vector<MuscleSetup>& muscles) {
  require(list.is_array(), w, "must be a list of muscles", "see docs/skinning.md, \"Muscles\"");
  for (std::size_t i = 0; i < list.size(); ++i)
    muscles.push_back(read_muscle(list[i], w + "[" + std::to_string(i) + "]"));
}

/// Section `substeps`: animation sub-stepping (SubstepOptions, 2014 §5.2).
void read_substeps(const json& p, const std::string& w, SubstepOptions& substeps) {
  check_keys(p, {"paper_rule", "fold_rule", "min_step_rad", "max_step_rad", "max_substeps"}, w);
  read(p, "paper_rule", substeps.paper_rule, w);
  read(p, "fold_rule", substeps.fold_rule, w);
  read(p, "min_step_rad", substeps.min_step_rad, w);
  read(p, "max_step_rad", substeps.max_step_rad, w);
  read(p, "max_substeps", substeps.max_substeps, w);
  require(substeps.min_step_rad > 0 && std::isfinite(substeps.min_step_rad), w + ".min_step_rad",
          "must be > 0", "e.g. 0.05");
  require(substeps.max_step_rad >= 0 && std::isfinite(substeps.max_step_rad), w + ".max_step_rad",
          "must be >= 0 (0 = off)", "e.g. 0.05");
  require(substeps.max_substeps >= 1, w + ".max_substeps", "must be >= 1", "e.g. 1000");
}

}  // namespace

void apply_paper_preset(SkinSetup& s) {
  s.fit.field = implicit::PartFitOptions::FieldKind::hrbf;
  s.fit.closure = implicit::PartFitOptions::Closure::joints;
  s.fit.grid_storage = implicit::GridStorage::float32;  // 2013 §6's float textures
  s.operator_storage = implicit::GridStorage::float32;  // 2014 §4.2's float grids
  s.max_fit_error = 0;
  s.capsule_match = 0;
  track::TrackerOptions& t = s.tracker;
  t.relaxation = track::Relaxation::kJacobi;
  t.chebyshev_rho = 0.f;
  t.active_set = false;
  t.lazy_evaluation = false;
  t.min_contact_damping = 1.f;
  t.fold_contacts = false;
  t.fold_repair.rounds = 0;
  t.orientation_repair.rounds = 0;
  t.smoothing = {2, 3};
  t.free_vertex_angle_deg = 180.f;
  s.axis_guard = false;
  s.rigid_pieces = false;
  s.bulge_gate = false;
  s.substeps.paper_rule = true;
  s.substeps.fold_rule = false;
  s.projector.stall_steps = 0;
  s.projector.secant = false;
  s.projector.tolerance = 1e-4f;
}

SkinSetup setup_from_json(const std::string& text, const std::string& source, const std::string& base_dir) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for a number like 1e999
    throw InputError(source + ": not valid JSON (" + e.what() + "); fix the file");
  }
  SkinSetup s;
  s.source = source;
  check_keys(j,
             {"version", "preset", "tree", "default_operator", "joints", "fit", "operators", "tracker",
              "projector", "substeps", "mask", "muscles", "ddm", "cor"},
             source);
  if (j.contains("preset")) {
    const json& p = j.at("preset");
    require(p.is_string() && (p == "paper" || p == "isokit"), source + ".preset",
            "must be \"paper\" or \"isokit\" (got " + p.dump() + ")",
            "use \"paper\" (the papers' algorithms alone) or \"isokit\" (the defaults)");
    if (p == "paper") apply_paper_preset(s);
  }
  int version = 1;
  read(j, "version", version, source);
  require(version == 1, source + ".version", "unsupported (got " + std::to_string(version) + ")",
          "use version 1");
  s.tree = tree_from_json(j, source);
  std::string def = "auto";
  read(j, "default_operator", def, source);
  s.default_operator = joint_operator_from_string(def, source + ".default_operator");
  if (j.contains("joints")) read_joints(j.at("joints"), source, base_dir, s);
  if (j.contains("fit")) read_fit(j.at("fit"), source + ".fit", s.fit, s.capsule_match, s.max_fit_error);
  if (j.contains("operators")) read_operators(j.at("operators"), source + ".operators", base_dir, s);
  if (j.contains("tracker")) read_tracker(j.at("tracker"), source + ".tracker", s);
  if (j.contains("projector"))
    read_projector(j.at("projector"), source + ".projector", s.projector, s.projector_initial);
  if (j.contains("ddm")) read_ddm(j.at("ddm"), source + ".ddm", s.ddm);
  if (j.contains("cor")) read_cor(j.at("cor"), source + ".cor", s.cor);
  if (j.contains("substeps")) read_substeps(j.at("substeps"), source + ".substeps", s.substeps);
  if (j.contains("mask")) read_mask(j.at("mask"), source + ".mask", s.mask);
  if (j.contains("muscles")) read_muscles(j.at("muscles"), source + ".muscles", s.muscles);
  return s;
}

SkinSetup load_setup(const std::string& path) {
  std::ifstream in(path);
  require(bool(in), path, "cannot be read", "check the setup file path");
  std::stringstream ss;
  ss << in.rdbuf();
  return setup_from_json(ss.str(), path, std::filesystem::path(path).parent_path().string());
}

}  // namespace isokit::skinning
