// SPDX-License-Identifier: MIT
/// \file
/// The skinning setup: per-joint composition operators and relaxation, and every option of the
/// pipeline, with the papers' defaults. Read from a JSON setup file (`load_setup`); every key is
/// optional. Format (version 1):
///
/// ```json
/// { "version": 1,
///   "tree": "auto",
///   "default_operator": "auto",
///   "joints": { "LeftForeArm": { "operator": "bulge", "relaxation": 0.5 } },
///   "fit": { "samples": 50, "cull_h": 0.05, "grid_resolution": 32, "seed": 1,
///            "opening_offset": 0.1 },
///   "operators": { "resolution": 128, "slices": 128 },
///   "tracker": { "max_iterations": 100, "tolerance": 1e-5, "sigma": 1.0, "contact_angle_deg": 55,
///                "initial_newton_steps": 10, "smoothing_steps": 5, "beta_diffusion_steps": 3,
///                "relaxation": "jacobi" },
///   "projector": { "sigma": 0.35, "max_iterations": 50, "contact_angle_deg": 55 },
///   "substeps": { "paper_rule": true, "fold_rule": true, "min_step_rad": 0.05, "max_step_rad": 0 } }
/// ```
/// `tree`: "auto" (the method's paper), "2013" or "2014". `default_operator`: "auto" (2014:
/// contact, 2013: blend), "union", "blend", "bulge" or "contact". `tracker.relaxation`: "jacobi"
/// or "cg" (track::Relaxation).
#pragma once

#include <map>
#include <string>

#include "isokit/implicit/fit.h"
#include "isokit/track/projector2013.h"
#include "isokit/track/tracker.h"

namespace isokit::skinning {

/// Operator at a joint (between a bone and its parent): `union` = max, `blend` = 2013 Appendix A
/// gradient blend (controller `blend2013`), `bulge` = 2014 `g_db` bulge-in-contact (controller
/// `bulge`; the bone and its parent form a bulge pair at the bottom of a 2014 tree), `contact` =
/// 2014 `g_dc` (controller `contact`).
enum class JointOperator { kAuto, kUnion, kBlend, kBulge, kContact };

enum class TreeKind { kAuto, k2013, k2014 };

struct JointSettings {
  JointOperator op{JointOperator::kAuto};
  float relaxation{1.0f};  ///< tracker relaxation mask of the joint's vertices (2014 §5, [0, 1])
};

/// Animation sub-stepping (2014 §5.2): a step is split so that no joint rotates by more than a
/// third of its current bending angle (`paper_rule`; the bending angle is floored at
/// `3 * min_step_rad` so steps near the rest pose stay finite), nor (`fold_rule`) by more than a
/// third of the angle left before its bones fold onto each other (π minus the bending angle,
/// floored the same way), and by no more than `max_step_rad` (> 0 enables it; `--max-step-rad`).
/// The paper's sentence reads both ways; `fold_rule` keeps the steps small where a fold closes
/// (docs/skinning.md, "sub-steps").
struct SubstepOptions {
  bool paper_rule{true};
  bool fold_rule{true};
  double min_step_rad{0.05};
  double max_step_rad{0.0};
  int max_substeps{1000};
};

struct SkinSetup {
  std::string source{"defaults"};  ///< file name for messages
  TreeKind tree{TreeKind::kAuto};
  JointOperator default_operator{JointOperator::kAuto};
  std::map<std::string, JointSettings> joints;
  implicit::PartFitOptions fit{};
  int operator_resolution{128};  ///< 2014 §6.1: 128 × 128 × 128 operator grids
  int operator_slices{128};
  /// A `bulge` joint's controller is capped by the same controller of the joint's own bend angle
  /// (the rotation between the two primitives relative to rest): `d = min(d_b(α), d_b(β))`. Not
  /// in the papers: without it the bulge operator is active inside the limb at rest, where the
  /// two primitives' caps overlap with gradients more than 90° apart, and skin that slides into
  /// that internal valley during a bend stays there (docs/skinning.md, "Decision: the bulge
  /// gate"). Setup key `operators.bulge_gate`.
  bool bulge_gate{true};
  /// Controller presets (operators::Controller::preset) of the contact and bulge operators; setup
  /// keys `operators.contact_controller`, `operators.bulge_controller` ("bulge2013" = the bulge
  /// controller before 2026-12-01, at 1 from 90°: docs/operators.md).
  std::string contact_controller{"contact"};
  std::string bulge_controller{"bulge"};
  track::TrackerOptions tracker{};
  track::ProjectorOptions projector{};
  SubstepOptions substeps{};
  /// tracking2014: put vertices that crossed their own bone's axis back on their side before each
  /// sub-step (`AxisGuard`; not in the papers). Setup key `tracker.axis_guard`.
  bool axis_guard{true};
  /// tracking2014: the fold repair (TrackerOptions::fold_repair) leaves alone the vertices of
  /// parts with fewer vertices than this (0: no limit). A fold repair region (an inverted
  /// triangle and two rings) holds 20 – 30 vertices; a part under about twice that is
  /// under-resolved and smoothing would erase it (the 290-vertex Fox sample, 11 – 38 vertices per
  /// part: volume 0.92 → 0.18 – 0.34 in its Survey clip). Setup key
  /// `tracker.fold_repair_min_part_vertices`.
  int fold_repair_min_part_vertices{50};

  /// The operator chosen for `joint` (resolving kAuto with the tree kind).
  JointOperator operator_for(const std::string& joint, TreeKind tree) const;
  float relaxation_for(const std::string& joint) const;
};

const char* to_string(JointOperator op);
JointOperator joint_operator_from_string(const std::string& s, const std::string& where);

/// Parses a setup (validated). \throw InputError naming `source`, the key and the fix.
SkinSetup setup_from_json(const std::string& text, const std::string& source);
/// \throw InputError naming the file when it cannot be read or is invalid.
SkinSetup load_setup(const std::string& path);

}  // namespace isokit::skinning
