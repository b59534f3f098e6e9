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
///   "joints": { "LeftForeArm": { "operator": "bulge", "relaxation": 0.5, "spec": "my_bulge.json" } },
///   "fit": { "samples": 50, "cull_h": 0.05, "grid_resolution": 32, "seed": 1,
///            "opening_offset": 0.1, "field": "hrbf",
///            "distance": { "cells_per_feature": 3, "max_resolution": 64, "overlap_rings": 1 } },
///   "operators": { "resolution": 128, "slices": 128, "contact_spec": "my_contact.json",
///                  "bulge_spec": "my_bulge.json" },
///   "tracker": { "max_iterations": 100, "tolerance": 1e-5, "sigma": 1.0, "contact_angle_deg": 55,
///                "initial_newton_steps": 10, "smoothing_steps": 5, "beta_diffusion_steps": 3,
///                "relaxation": "jacobi" },
///   "projector": { "sigma": 0.35, "max_iterations": 50, "contact_angle_deg": 55, "initial": "dqs" },
///   "ddm": { "smoothing_steps": 3, "lambda": 3, "kappa": 1, "alpha": 0, "variant": "v0", "prune": 1e-3 },
///   "cor": { "sigma": 0.1, "fallback": "lbs" },
///   "substeps": { "paper_rule": true, "fold_rule": true, "min_step_rad": 0.05, "max_step_rad": 0 } }
/// ```
/// `fit.field`: "hrbf" (2013 §4.1, the default) or "distance" (each part's field built from its
/// own closed surface, implicit::DistanceFitOptions under `fit.distance`;
/// docs/decisions/part-fields-from-the-mesh.md).
/// `tree`: "auto" (the method's paper), "2013" or "2014". `default_operator`: "auto" (2014:
/// contact, 2013: blend), "union", "blend", "bulge" or "contact". `tracker.relaxation`: "jacobi"
/// (2014, the default), "global" (docs/decisions/global-tangent-solve.md), "cg" or "energy"
/// (track::Relaxation; the energy solve's keys `tracker.energy_*`, track::EnergySolveOptions;
/// docs/decisions/tracker-one-energy.md).
///
/// Designed operators (docs/operators.md, "Using a designed operator in skinning"):
/// `operators.contact_spec` / `operators.bulge_spec` name an operator spec file
/// (isokit-operator-spec JSON, e.g. from isokit-opdesigner) used instead of the built-in preset by
/// every contact / bulge joint; `joints.NAME.spec` names one for that joint alone (its operator
/// must resolve to contact or bulge). Relative paths resolve against the setup file's folder. With
/// a spec file, the operator's controller is the spec's own (designing the controller is part of
/// designing the operator; `operators.contact_controller` / `bulge_controller` apply to the
/// presets only), and the grid's resolution and slices are the setup's `operators.resolution` /
/// `slices` (as for the presets; the spec's own are replaced). Grids are checked
/// (operators::check_operator) and kept in the operator disk cache (operators/cache.h).
#pragma once

#include <array>
#include <map>
#include <string>

#include <optional>

#include <Eigen/Core>

#include "isokit/implicit/fit.h"
#include "isokit/operators/spec.h"
#include "isokit/skinning/cor.h"
#include "isokit/skinning/ddm.h"
#include "isokit/skinning/rig_io.h"
#include "isokit/track/projector2013.h"
#include "isokit/track/tracker.h"

namespace isokit::skinning {

/// Operator at a joint (between a bone and its parent): `union` = max, `blend` = 2013 Appendix A
/// gradient blend (controller `blend2013`), `bulge` = 2014 `g_db` bulge-in-contact (controller
/// `bulge`; the bone and its parent form a bulge pair at the bottom of a 2014 tree), `contact` =
/// 2014 `g_dc` (controller `contact`).
enum class JointOperator { kAuto, kUnion, kBlend, kBulge, kContact };

enum class TreeKind { kAuto, k2013, k2014 };

/// The geometric skinning a method starts from (setup key `projector.initial`).
enum class InitialSkinning { kDqs, kDdm, kCor };

/// An operator spec file named by the setup, loaded and validated when the setup is read.
struct SpecFile {
  std::string key;   ///< the setup key that named it, for messages ("s.json.operators.contact_spec")
  std::string path;  ///< resolved: a relative path is joined to the setup file's folder
  operators::OperatorSpec spec;  ///< as in the file (SkinField applies the setup's resolution and slices)
};

/// Settings of one joint (setup key `joints.NAME`).
struct JointSettings {
  /// Operator between the joint's bone and its parent's; kAuto: `SkinSetup::default_operator`.
  JointOperator op{JointOperator::kAuto};
  /// Relaxation mask of the joint's vertices (2014 Fig. 11), in [0, 1], as the painted mask
  /// (Rig::relax_mask; a vertex takes the smaller of the two): 0 = moved rigidly with the joint,
  /// neither projected nor relaxed; 1 (default) = tracked; between = pulled toward the rigid
  /// position with weight 1 − m (IsoSurfaceTracker::set_anchor_stiffness). Until this release 0
  /// meant "no tangential move, still projected" (docs/skinning.md, "Rigid parts and the
  /// relaxation mask").
  float relaxation{1.0f};
  /// The joint's own grid operator (key `joints.NAME.spec`), replacing the preset and
  /// `SkinSetup::contact_spec` / `bulge_spec`; the joint's operator must be contact or bulge.
  std::optional<SpecFile> spec;
};

/// Animation sub-stepping (2014 §5.2; setup key `substeps`): an animation step is split into
/// equal sub-steps so that no joint rotates by more than the limits below in one sub-step. The
/// paper's rule reads two ways; both are applied (docs/skinning.md, "Decision: sub-steps near a
/// closed fold").
struct SubstepOptions {
  /// At most a third of the joint's current bending angle (its rotation away from rest, floored
  /// at `3 * min_step_rad`). 2014 §5.2. Default on.
  bool paper_rule{true};
  /// At most a third of the angle left before the joint's bones fold onto each other (π minus
  /// the bending angle, floored the same way). Not in the papers. Default on.
  bool fold_rule{true};
  /// Radians, > 0: floor of both rules' angles (so steps out of the rest pose stay finite).
  double min_step_rad{0.05};
  /// Radians, ≥ 0: largest rotation of a joint per sub-step; 0 = no limit (`--max-step-rad`).
  double max_step_rad{0.0};
  int max_substeps{1000};  ///< ≥ 1: most sub-steps per animation step
};

/// A muscle (2014 Fig. 10: "an extra implicit primitive with its associated bone to mimic the
/// contraction of a bicep by applying a scaling proportional to the arm bending angle"; setup
/// key `muscles`, docs/skinning.md "Muscles"): an ellipsoid carried rigidly by a bone and scaled
/// along chosen axes by a curve of one joint's bend angle, composed with its bone's part like a
/// child part (the implicit methods; LBS and DQS ignore it).
struct MuscleSetup {
  std::string name;                 ///< for messages and `info`
  std::string bone;                 ///< the joint whose bone carries it (a fitted part)
  std::string driver;               ///< the joint whose bend angle (from its parent) drives the scale
  Eigen::Vector3d center{0, 0, 0};  ///< centre at rest, in the rig's rest space
  /// Direction of the first semi-axis at rest (normalised; the other two are completed
  /// deterministically). Zero (default): from the bone's joint toward its first child.
  Eigen::Vector3d axis{0, 0, 0};
  Eigen::Vector3d radii{1, 1, 1};                 ///< semi-axes at rest, rest-space units, > 0
  std::array<bool, 3> scaled{false, true, true};  ///< axes the curve scales (key `scale_axes`, default "yz")
  /// Scale factor (> 0) against the bend in degrees, knots ascending in [0, 180]: linear between
  /// knots, constant outside (key `curve`: [[degrees, factor], ...]). Default: 1 everywhere.
  std::vector<std::pair<double, double>> curve{{0.0, 1.0}};
  JointOperator op{JointOperator::kBlend};  ///< "blend" (2013 gradient blend, default) or "union"

  /// The curve at `bend_rad` radians.
  double scale_at(double bend_rad) const;
};

struct SkinSetup {
  std::string source{"defaults"};  ///< file name for messages
  /// Composition tree; kAuto = each method's paper (2013 tree for implicit2013, 2014 tree for
  /// tracking2014). Setup key `tree`.
  TreeKind tree{TreeKind::kAuto};
  /// Operator of joints without their own; kAuto = contact in a 2014 tree, blend in a 2013 tree.
  /// Setup key `default_operator`.
  JointOperator default_operator{JointOperator::kAuto};
  std::map<std::string, JointSettings> joints;  ///< by joint name; absent joints: the defaults
  implicit::PartFitOptions fit{};               ///< fit per part (2013 §4.1: HRBF). Setup key `fit`
  /// A part whose HRBF fails keeps a fitted capsule (and its own joint's motion) instead of
  /// sharing a touching neighbour's primitive when the capsule's vertex → surface p95 is at most
  /// this many times its radius; 0 = off: such a part shares first, and a capsule is only the last
  /// resort (not in the papers; docs/skinning.md, "No vertex without a field"). In [0, 10];
  /// default 0. Setup key `fit.capsule_match`.
  double capsule_match{0};
  /// A part's HRBF whose error (`implicit::FittedPart::error`: vertex → surface plus surface →
  /// part p95) is above this many times its radius `r` counts as a failed fit: the next triangle
  /// filter is tried, then the part shares a touching neighbour's primitive, and the capsule is
  /// the last resort. Such a fit (a patch that is no limb, a part of a few triangles) bulges out
  /// of its part and holds other parts' vertices at rest. 0 = off (the papers: every fit that
  /// solves is kept). Not in the papers (docs/skinning.md, "Decision: rejecting poor fits": 1
  /// fits the shared rigs' parts closest, off by default because tracking got worse on them).
  /// In [0, 100]; default 0. Setup key `fit.max_error`.
  double max_fit_error{0};
  int operator_resolution{128};  ///< grid operator resolution per axis, [8, 1024] (2014 §6.1: 128)
  int operator_slices{128};      ///< grid operator slices, [8, 1024] (2014 §6.1: 128)
  /// How the field's program stores its grid operators (implicit::ProgramOptions): `fixed16`
  /// (not in the papers: 16-bit samples in 8 × 8 tiles, 2.1 bytes a sample instead of 4, each
  /// within half its tile's step of the float) or `float32` (the 2014 paper's float grids; the
  /// `paper` preset's). Empty (the default, setup key value "auto"): fixed16 for the 2013 tree,
  /// whose projector felt no difference on the real rigs, and float32 for the 2014 tree, whose
  /// tracker lost 7 checks with fixed16 (docs/decisions/field-evaluation-at-memory-speed.md).
  /// Setup key `operators.storage`.
  std::optional<implicit::GridStorage> operator_storage;
  /// The 2013 gradient-based blend (Appendix A) sampled into a grid of `operator_resolution`² ×
  /// `operator_slices` nodes and interpolated like the grid operators (true), as the 2013 paper
  /// stores its operators in 128³ textures (§6), or evaluated analytically at every point (false:
  /// a 64-step scan and 40 bisections, 371 ns against 16 ns). Default true; setup key
  /// `operators.blend_grid` (docs/skinning.md, "Decision: the 2013 blend as a grid").
  bool blend_grid{true};
  /// Caps a `bulge` joint's controller by the same controller of the joint's own bend angle β (the
  /// rotation between the two primitives relative to rest): `d = min(d_b(α), d_b(β))`, so at rest
  /// the node is the clean union. Not in the papers (docs/skinning.md, "Decision: the bulge
  /// gate"). Default on; setup key `operators.bulge_gate`.
  bool bulge_gate{true};
  /// Controller presets (operators::Controller::preset, docs/operators.md) of the contact and
  /// bulge operators. Setup keys `operators.contact_controller`, `operators.bulge_controller`.
  std::string contact_controller{"contact"};
  std::string bulge_controller{"bulge"};
  /// Designed operators replacing the presets of every contact / bulge joint without its own
  /// spec (keys `operators.contact_spec`, `operators.bulge_spec`). Default: none (the presets).
  std::optional<SpecFile> contact_spec, bulge_spec;
  track::TrackerOptions tracker{};      ///< the 2014 tracker. Setup key `tracker`
  track::ProjectorOptions projector{};  ///< the 2013 projection. Setup key `projector`
  /// implicit2013: the initial geometric skinning the 2013 projector corrects (2013 §6,
  /// "Influence of the initial geometric skinning solution": a smoother start without deep
  /// self-intersections corrects better). "dqs" (the paper's, default), "ddm" or "cor" (with the
  /// setup's `ddm` / `cor` options). Setup key `projector.initial`
  /// (docs/decisions/projector-initial-skinning.md).
  InitialSkinning projector_initial{InitialSkinning::kDqs};
  /// tracking2014: where the relaxation mask pulls a masked vertex (2014 Fig. 11). "dqs" (the
  /// default): its partition joint's rigid transform (a small part's vertex: its DQS position);
  /// "ddm" or "cor": its position by that method. A rigid piece's vertices keep their piece's
  /// transform either way. Setup key `tracker.anchor`
  /// (docs/decisions/projector-initial-skinning.md, "The tracker's anchors").
  InitialSkinning tracker_anchor{InitialSkinning::kDqs};
  DdmOptions ddm{};           ///< method `ddm` (Le & Lewis 2019). Setup key `ddm`
  CorOptions cor{};           ///< method `cor` (Le & Hodgins 2016). Setup key `cor`
  SubstepOptions substeps{};  ///< setup key `substeps`
  /// Where a rig file keeps its painted relaxation mask (setup key `mask`: `attribute`,
  /// `color_set`, `channel` "r" | "g" | "b" | "a"); read by open_rig. Default: the glTF attribute
  /// `_RELAX_MASK`.
  MaskSource mask{};
  /// Muscles (2014 Fig. 10; setup key `muscles`). Default: none.
  std::vector<MuscleSetup> muscles;
  /// tracking2014: put vertices that crossed their own bone's axis back on their side before each
  /// sub-step (`AxisGuard`; not in the papers; docs/skinning.md, "Decision: the axis guard").
  /// Default on; setup key `tracker.axis_guard`.
  bool axis_guard{true};
  /// implicit2013 and tracking2014: the rig's rigid pieces (`find_rigid_pieces`: components whose
  /// every vertex has the same influences) take the relaxation mask 0 — they move with their
  /// bone's transform exactly instead of being projected and relaxed; their fields stay in the
  /// composition, so the skin that touches them still meets them. Not in the papers (the paper
  /// preset turns it off). Default on (docs/decisions/rigid-pieces-on-by-default.md: 66 → 77
  /// criterion checks on `make eval`); setup key `tracker.rigid_pieces`.
  bool rigid_pieces{true};
  /// Each rigid piece (above) also has a field of its own in the composition: the distance field
  /// of its closed mesh (libimplicit `fit_part_distance`), carried by its bone and joined to that
  /// bone's part by union, so the skin meets the piece's exact shape. Setup key
  /// `tracker.piece_fields`; default false.
  bool piece_fields{false};
  /// tracking2014: the fold repair (TrackerOptions::fold_repair) leaves alone the vertices of
  /// parts with fewer vertices than this, ≥ 0 (0: no limit): a fold repair region holds 20 – 30
  /// vertices, so smaller parts are under-resolved and smoothing would erase them. Not in the
  /// papers (docs/skinning.md, "Known limits", low-poly rigs; 50 → 100 on 2026-12-02: the
  /// repairs on CesiumMan's 50 – 90-vertex parts made its walk's edge spikes). Default 100; setup
  /// key `tracker.fold_repair_min_part_vertices`.
  int fold_repair_min_part_vertices{100};
  /// implicit2013 and tracking2014: the relaxation mask (docs/skinning.md, "Rigid parts and the
  /// relaxation mask") of the vertices of parts with fewer than `small_part_vertices` vertices,
  /// which the part fields under-resolve; their anchors are their DQS positions. In [0, 1]; 1
  /// (default) = off, 0 = such parts are skinned by DQS. Not in the papers. Setup keys
  /// `tracker.small_part_mask`, `tracker.small_part_vertices` (≥ 0; default 100).
  float small_part_mask{1.0f};
  int small_part_vertices{100};

  /// The operator chosen for `joint` (resolving kAuto with the tree kind).
  JointOperator operator_for(const std::string& joint, TreeKind tree) const;
  float relaxation_for(const std::string& joint) const;
  /// The spec file of `joint` with operator `op`: the joint's own, else the setup's for a contact
  /// or bulge joint; nullptr for the preset. 	hrow InputError when the joint has its own spec
  /// but `op` is union or blend (the message names the joint and the fix).
  const SpecFile* spec_for(const std::string& joint, JointOperator op) const;
};

const char* to_string(JointOperator op);
const char* to_string(InitialSkinning s);
/// \throw InputError naming `where` for a name other than dqs, ddm, cor.
InitialSkinning initial_skinning_from_string(const std::string& s, const std::string& where);
JointOperator joint_operator_from_string(const std::string& s, const std::string& where);

/// The `paper` preset (setup key `"preset": "paper"`, applied before the other keys, which may
/// override it): the 2013 fit and the 2014 tracker alone, every isokit addition off —
/// `fit.closure` joints, `fit.max_error` 0, `fit.capsule_match` 0; tracker: `chebyshev_rho` 0
/// (plain Jacobi), `active_set` false, `lazy_evaluation` false, `min_contact_damping` 1 (no
/// contact damping), `fold_contacts` false, fold repair and orientation repair 0 rounds, contact
/// smoothing 2 β-diffusion and 3 smoothing steps (2013 §5), `free_vertex_angle_deg` 180 (every
/// vertex held to its iso-value), `axis_guard` false; operators:
/// `bulge_gate` false; sub-steps: the 2014 rule without `fold_rule`. Kept as they are, because
/// the papers give no value or the code has no paper-only path: the iteration cap (100) and
/// tolerance, the 10 initial Newton steps, the Newton step clamp (`max_step`), the cotangent
/// clamp, the vertex order (no result change) and the failed-fit rules (a part whose HRBF does
/// not solve shares a neighbour's primitive, else a capsule). docs/skinning.md, "The paper
/// preset".
void apply_paper_preset(SkinSetup& setup);

/// Parses a setup (validated; spec files are loaded). Relative spec paths resolve against
/// `base_dir` (empty: the current directory). \throw InputError naming `source`, the key and the
/// fix (a spec file's own errors are prefixed with the key that named it).
SkinSetup setup_from_json(const std::string& text, const std::string& source,
                          const std::string& base_dir = "");
/// Spec paths relative to the setup file's folder. \throw InputError naming the file when it
/// cannot be read or is invalid.
SkinSetup load_setup(const std::string& path);

}  // namespace isokit::skinning
