// SPDX-License-Identifier: MIT
#include "isokit/skinning/pipeline.h"
#include "isokit/skinning/rigid_pieces.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "isokit/core/error.h"
#include "isokit/core/mesh_quality.h"
#include "isokit/core/parallel.h"
#include "isokit/skinning/deform.h"
#include "isokit/skinning/procedural.h"
#include "isokit/skinning/rig_io.h"
#include "isokit/skinning/weights.h"
#include "isokit/track/projector2013.h"
#include "isokit/track/tracker.h"
#include "pipeline/geometric_cache.h"

namespace isokit::skinning {

const char* to_string(Method m) {
  switch (m) {
    case Method::kLbs:
      return "lbs";
    case Method::kDqs:
      return "dqs";
    case Method::kImplicit2013:
      return "implicit2013";
    case Method::kTracking2014:
      return "tracking2014";
    case Method::kDdm:
      return "ddm";
    case Method::kCor:
      return "cor";
  }
  return "?";
}

std::vector<Method> all_methods() {
  return {Method::kLbs,          Method::kDqs, Method::kImplicit2013,
          Method::kTracking2014, Method::kDdm, Method::kCor};
}

Method method_from_string(const std::string& s) {
  for (Method m : all_methods())
    if (s == to_string(m)) return m;
  throw InputError("--method: unknown method '" + s +
                   "'; use lbs, dqs, ddm, cor, implicit2013 or tracking2014");
}

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

bool same_pose(const Pose& a, const Pose& b) {
  for (std::size_t j = 0; j < a.size(); ++j)
    if (!a[j].matrix().isApprox(b[j].matrix(), 1e-9) &&
        (a[j].matrix() - b[j].matrix()).cwiseAbs().maxCoeff() > 1e-9)
      return false;
  return true;
}

/// Per triangle: 1 when its normal points along +∇f at its centroid (QUALITY.md "inverted").
std::vector<std::uint8_t> inverted_flags(const track::FieldFunction& f, const track::Positions& p,
                                         const track::Triangles& t) {
  const std::size_t n = static_cast<std::size_t>(t.rows());
  std::vector<Vec3f> c(n), g(n);
  std::vector<float> v(n);
  std::vector<std::uint8_t> contact(n, 0), out(n, 0);
  auto corner = [&](std::size_t k, int i) { return Vec3f{p(t(k, i), 0), p(t(k, i), 1), p(t(k, i), 2)}; };
  for (std::size_t k = 0; k < n; ++k) c[k] = triangle_centroid(corner(k, 0), corner(k, 1), corner(k, 2));
  parallel_for(n, 1024, [&](std::size_t b, std::size_t e) {
    f(c.data() + b, e - b, v.data() + b, g.data() + b, contact.data() + b);
    for (std::size_t k = b; k < e; ++k)
      out[k] = is_inverted(triangle_normal(corner(k, 0), corner(k, 1), corner(k, 2)), g[k]) ? 1 : 0;
  });
  return out;
}

}  // namespace

SkinReference metrics_reference(const Rig& rig) {
  SkinReference ref;
  ref.weights = rig.weights;
  ref.rest_skin = skinning_matrices(rig, rest_pose(rig));
  // Every rigid piece, whatever SkinSetup::rigid_pieces says: the metrics depend on the rig
  // alone, so that every method (and every setup) is measured on the same skin.
  for (const RigidPiece& p : find_rigid_pieces(rig))
    ref.rigid_vertices.insert(ref.rigid_vertices.end(), p.vertices.begin(), p.vertices.end());
  return ref;
}

Rig open_rig(const std::string& spec, double fps, const Progress& progress,
             std::vector<std::string>* warnings, const MaskSource& mask) {
  const std::string prefix = "procedural:";
  Rig rig;
  if (spec.rfind(prefix, 0) == 0) {
    rig = make_procedural(spec.substr(prefix.size()));
  } else {
    LoadOptions o;
    o.fps = fps;
    o.mask = mask;
    LoadReport report;
    rig = load_rig(spec, o, &report);
    if (warnings) *warnings = report.warnings;
  }
  if (rig.weights.empty()) {
    HeatWeightOptions h;
    if (progress) h.progress = [&](int done, int total) { progress("heat weights", done, total); };
    rig.weights = heat_weights(rig, h);
  }
  validate(rig);
  return rig;
}

Skinner::Skinner(Rig rig, SkinSetup setup, Progress progress)
    : rig_(std::move(rig)), setup_(std::move(setup)), progress_(std::move(progress)) {
  validate(rig_);
  require(!rig_.weights.empty(), rig_.name + ": weights", "the rig has no skin weights",
          "give weights (heat weights are computed by isokit-skin when a file has none)");
  fitted_ = std::make_unique<FittedRig>(rig_, setup_, progress_);
  evaluator_ = std::make_unique<FrameMetricsEvaluator>(rig_.rest, rig_.triangles, SelfIntersectionOptions{},
                                                       metrics_reference(rig_));
}

Skinner::~Skinner() = default;

SkinField& Skinner::field(TreeKind kind) {
  std::unique_ptr<SkinField>& f = kind == TreeKind::k2013 ? field2013_ : field2014_;
  if (!f) f = std::make_unique<SkinField>(*fitted_, setup_, kind, progress_);
  return *f;
}

const DirectDeltaMush& Skinner::ddm() {
  if (!ddm_) {
    if (progress_) progress_("ddm precomputation", 0, 1);
    ddm_ = cached_ddm(rig_, setup_.ddm);
  }
  return *ddm_;
}

const CorSkinning& Skinner::cor() {
  if (!cor_) {
    if (progress_) progress_("cor precomputation", 0, 1);
    cor_ = cached_cor(rig_, setup_.cor);
  }
  return *cor_;
}

FrameMetrics Skinner::measure(const Pose& pose, const track::Positions& positions, bool self_intersections,
                              const std::vector<std::uint8_t>* contact) {
  // The field metrics use the 2014 tree at their own poses (the tracker's pose is left alone).
  const SkinField& metrics_field = field(TreeKind::k2014);
  if (iso2014_.empty()) {
    const track::FieldFunction rest =
        metrics_field.function(metrics_field.pose_of(skinning_matrices(rig_, rest_pose(rig_))));
    iso2014_ = track::sample_iso_values(rest, rig_.rest);
    rest_inverted_ = inverted_flags(rest, rig_.rest, rig_.triangles);
  }
  const std::vector<Affine> skin = skinning_matrices(rig_, pose);
  FrameMetrics m = evaluator_->evaluate(positions, self_intersections, true, &skin);
  const track::FieldFunction f = metrics_field.function(metrics_field.pose_of(skin), true);
  const std::vector<std::uint8_t> inv = inverted_flags(f, positions, rig_.triangles);
  m.inverted_triangles = 0;
  m.new_inverted_triangles = 0;
  for (std::size_t k = 0; k < inv.size(); ++k) {
    m.inverted_triangles += inv[k];
    m.new_inverted_triangles += inv[k] && !rest_inverted_[k] ? 1 : 0;
  }
  const std::size_t n = static_cast<std::size_t>(positions.rows());
  std::vector<float> values(n);
  std::vector<Vec3f> grads(n), pts(n);
  std::vector<std::uint8_t> fc(n, 0);
  for (std::size_t v = 0; v < n; ++v) pts[v] = {positions(v, 0), positions(v, 1), positions(v, 2)};
  parallel_for(n, 1024, [&](std::size_t b, std::size_t e) {
    f(pts.data() + b, e - b, values.data() + b, grads.data() + b, fc.data() + b);
  });
  double mx = 0, sum = 0;
  int used = 0, contacts = 0;
  for (std::size_t v = 0; v < n; ++v) {
    const bool c = fc[v] || (contact && (*contact)[v]);
    contacts += c ? 1 : 0;
    if (c) continue;
    const double r = std::abs(double(values[v]) - double(iso2014_[v]));
    mx = std::max(mx, r);
    sum += r;
    ++used;
  }
  m.iso_residual_max = mx;
  m.iso_residual_mean = used ? sum / used : 0.0;
  m.contact_vertices = contacts;
  return m;
}

namespace {

/// What one bake carries from frame to frame, per method.
struct BakeState {
  std::unique_ptr<track::IsoSurfaceTracker> tracker;  ///< tracking2014
  std::unique_ptr<AxisGuard> guard;                   ///< tracking2014, SkinSetup::axis_guard
  std::unique_ptr<track::Projector2013> projector;    ///< implicit2013
  const DirectDeltaMush* ddm{nullptr};  ///< ddm, implicit2013 started from it, tracking2014 anchored to it
  const CorSkinning* cor{nullptr};      ///< cor, or implicit2013 started from it
  SkinField* field{nullptr};            ///< the implicit methods' field
  track::Positions current;             ///< tracking2014: the last result
  Pose previous;                        ///< tracking2014: the last frame's pose
  std::vector<Affine> prev_skin;        ///< tracking2014: the last sub-step's matrices
  /// tracking2014 with TrackerOptions::relaxation kEnergy: the last sub-step's DQS positions
  /// (each sub-step starts from the last result moved by DQS's change)
  track::Positions prev_dqs;
  /// The relaxation mask per vertex (`vertex_mask`; empty: all 1) and its vertices below 1.
  std::vector<float> mask;
  std::vector<int> masked;
  std::vector<char> piece;   ///< per vertex: in a rigid piece (SkinSetup::rigid_pieces); empty: none
  track::Positions anchors;  ///< the masked vertices' rigid positions at the current sub-step
};

/// Per vertex, whether it is anchored at its DQS position when masked: in a rigid piece
/// (SkinSetup::rigid_pieces; 1) or in a part too small for its field (SkinSetup::small_part_mask;
/// 2). Empty when there is none.
std::vector<char> piece_vertices(const Skinner& sk) {
  std::vector<char> piece;
  const SkinSetup& setup = sk.setup();
  const std::size_t nv = static_cast<std::size_t>(sk.rig().rest.rows());
  if (setup.small_part_mask < 1.0f) {
    const std::vector<int>& partition = sk.fitted().partition();
    for (std::size_t v = 0; v < nv; ++v)
      if (sk.fitted().bones()[static_cast<std::size_t>(partition[v])].vertices < setup.small_part_vertices) {
        piece.resize(nv, 0);
        piece[v] = 2;
      }
  }
  if (!setup.rigid_pieces) return piece;
  for (const RigidPiece& p : find_rigid_pieces(sk.rig())) {
    piece.resize(nv, 0);
    for (int v : p.vertices) piece[static_cast<std::size_t>(v)] = 1;
  }
  return piece;
}

/// The relaxation mask per vertex (2014 Fig. 11): the painted mask (Rig::relax_mask) and the
/// joint's setup key, the smaller of the two, and 0 on the rigid pieces (`piece`).
/// Empty when every vertex is 1.
std::vector<float> vertex_mask(const Skinner& sk, const std::vector<char>& piece) {
  const Rig& rig = sk.rig();
  const SkinSetup& setup = sk.setup();
  const std::vector<int>& partition = sk.fitted().partition();
  const std::size_t nv = static_cast<std::size_t>(rig.rest.rows());
  std::vector<float> mask(nv, 1.0f);
  for (std::size_t v = 0; v < nv; ++v) {
    mask[v] = setup.relaxation_for(rig.joints[static_cast<std::size_t>(partition[v])].name);
    if (!rig.relax_mask.empty()) mask[v] = std::min(mask[v], rig.relax_mask[v]);
  }
  for (std::size_t v = 0; v < piece.size(); ++v)
    if (piece[v] == 1)
      mask[v] = 0.0f;
    else if (piece[v] == 2)
      mask[v] = std::min(mask[v], setup.small_part_mask);
  if (std::all_of(mask.begin(), mask.end(), [](float m) { return m >= 1.0f; })) mask.clear();
  return mask;
}

/// The masked vertices' rigid positions (2014 Fig. 11: "rigidly transformed according to their
/// nearest bone"): each moved by its partition joint's skinning matrix `skin`, a rigid piece's
/// vertex by its piece's one transform and a small part's vertex as DQS moves it (its position in
/// `skinned`); other rows untouched. With `anchor` (SkinSetup::tracker_anchor ddm / cor: that
/// method's positions), every masked vertex but a rigid piece's takes its row there instead.
void rigid_positions(const Skinner& sk, const BakeState& s, const std::vector<Affine>& skin,
                     const track::Positions& skinned, track::Positions& out, const track::Positions* anchor) {
  const std::vector<int>& partition = sk.fitted().partition();
  const track::Positions& rest = sk.rig().rest;
  if (out.rows() != rest.rows()) out = rest;
  for (int v : s.masked) {
    const char piece = s.piece.empty() ? 0 : s.piece[static_cast<std::size_t>(v)];
    if (anchor && piece != 1) {  // SkinSetup::tracker_anchor: ddm / cor
      out.row(v) = anchor->row(v);
      continue;
    }
    if (piece) {
      out.row(v) = skinned.row(v);
      continue;
    }
    const Eigen::Vector3d p = rest.row(v).cast<double>().transpose();
    out.row(v) = (skin[static_cast<std::size_t>(partition[static_cast<std::size_t>(v)])] * p)
                     .cast<float>()
                     .transpose();
  }
}

/// implicit2013 (no relaxation to carry a pull term): a masked vertex moves to its rigid position
/// blended with the projected one, `m · projected + (1 − m) · rigid`.
void blend_masked(const BakeState& s, const track::Positions& rigid, track::Positions& pos) {
  for (int v : s.masked) {
    const float m = s.mask[static_cast<std::size_t>(v)];
    pos.row(v) = pos.row(v) * m + rigid.row(v) * (1.0f - m);
  }
}

void check_pose(const Rig& rig, const Pose& p) {
  require(p.size() == rig.joints.size(), rig.name + ": animation", "a pose has the wrong joint count",
          "one local transform per joint");
}

void check_poses(const Rig& rig, const std::vector<Pose>& poses) {
  require(!poses.empty(), rig.name + ": animation", "has no frames", "give a clip, --bend or a pose script");
  for (const Pose& p : poses) check_pose(rig, p);
}

/// The 2014 tracker on the rest mesh (2014 §5): iso-values sampled at rest, the rest field given
/// (triangles inverted at rest, free vertices) and the fold-repair mask of parts too small for its
/// smoothing (docs/skinning.md, "Low-poly rigs"); start_bake adds the relaxation mask.
std::unique_ptr<track::IsoSurfaceTracker> make_tracker(const Skinner& sk, const SkinField& field,
                                                       std::size_t grain) {
  const Rig& rig = sk.rig();
  const SkinSetup& setup = sk.setup();
  const std::vector<int>& partition = sk.fitted().partition();
  const int nv = static_cast<int>(rig.rest.rows());
  std::vector<float> iso = track::sample_iso_values(field.function(), rig.rest);
  track::TrackerOptions to = setup.tracker;
  to.grain = grain;
  auto tracker = std::make_unique<track::IsoSurfaceTracker>(rig.rest, rig.triangles, std::move(iso), to);
  tracker->set_rest_field(field.function());
  if (setup.fold_repair_min_part_vertices > 0) {
    std::vector<std::uint8_t> movable(static_cast<std::size_t>(nv));
    for (int v = 0; v < nv; ++v)
      movable[v] = sk.fitted().bones()[static_cast<std::size_t>(partition[v])].vertices >=
                           setup.fold_repair_min_part_vertices
                       ? 1
                       : 0;
    tracker->set_fold_repair_mask(std::move(movable));
  }
  return tracker;
}

/// Stage 1 of a 2014 sub-step (2014 §5): each vertex moved by its partition joint's rigid delta
/// from the last sub-step's matrices to `skin` (the whole delta where the joint's scale changed).
void move_by_rigid_deltas(const std::vector<int>& partition, const std::vector<Affine>& prev_skin,
                          const std::vector<Affine>& skin, std::size_t grain, track::Positions& current) {
  std::vector<Eigen::Matrix<double, 3, 4>> delta(skin.size());
  for (std::size_t j = 0; j < skin.size(); ++j) {
    // A joint whose stretch changed (scale keys) moves its vertices by the whole delta.
    const bool rescaled =
        (stretch_part(skin[j]) - stretch_part(prev_skin[j])).cwiseAbs().maxCoeff() > kStretchTolerance;
    delta[j] = rescaled ? (skin[j] * prev_skin[j].inverse()).matrix().topRows<3>()
                        : (rigid_part(skin[j]) * rigid_part(prev_skin[j]).inverse()).matrix().topRows<3>();
  }
  parallel_for(static_cast<std::size_t>(current.rows()), grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v) {
      const Eigen::Vector4d p(current(v, 0), current(v, 1), current(v, 2), 1.0);
      current.row(static_cast<Eigen::Index>(v)) = (delta[partition[v]] * p).cast<float>().transpose();
    }
  });
}

/// The energy solve's start (docs/tracking.md, "The energy solve"): the last result moved by
/// DQS's change since the last sub-step, so that the carry is smooth across joints (a rigid delta
/// per part tears the skin where two parts meet) and exact where DQS is: at rest it brings a
/// rest result back to rest.
void carry_by_dqs(BakeState& s, const track::Positions& dqs) {
  s.current += dqs - s.prev_dqs;
  s.prev_dqs = dqs;
}

/// One frame of tracking2014: the 2014 sub-step rule (§5.2), then per sub-step stage 1, the DQS
/// rotations as the ARAP targets, the axis guard and the tracker (stage 2).
void track_frame(const Skinner& sk, BakeState& s, const Pose& pose, std::size_t grain, FrameStats& st) {
  const Rig& rig = sk.rig();
  const int n = substeps(rig, s.previous, pose, sk.setup().substeps);
  st.substeps = n;
  std::vector<Mat3f> rotations;
  track::Positions scratch, anchor_skin;
  for (int k = 1; k <= n; ++k) {
    const Pose ps = k == n ? pose : interpolate(s.previous, pose, double(k) / n);
    const std::vector<Affine> skin = skinning_matrices(rig, ps);
    dual_quaternion_blend(rig.weights, skin, rig.rest, scratch, &rotations, grain);
    if (sk.setup().tracker.relaxation == track::Relaxation::kEnergy) {
      carry_by_dqs(s, scratch);
    } else {
      move_by_rigid_deltas(sk.fitted().partition(), s.prev_skin, skin, grain, s.current);
    }
    if (s.guard) st.axis_guard_moves += s.guard->apply(skin, s.current);
    s.field->set_pose(skin);
    track::TrackStats ts;
    if (s.masked.empty()) {
      ts = s.tracker->track(s.field->function(), rotations, s.current);
    } else {
      const bool geometric = s.ddm || s.cor;  // SkinSetup::tracker_anchor
      if (s.ddm) s.ddm->deform(skin, anchor_skin, grain);
      if (s.cor) s.cor->deform(skin, anchor_skin, grain);
      rigid_positions(sk, s, skin, scratch, s.anchors, geometric ? &anchor_skin : nullptr);
      ts = s.tracker->track(s.field->function(), rotations, s.current, s.anchors);
    }
    ++st.tracker_calls;
    st.capped_calls += ts.converged ? 0 : 1;
    st.call_iterations.push_back(ts.iterations);
    st.iterations += ts.iterations;
    st.vertex_updates += double(ts.vertex_updates);
    st.field_evaluations += double(ts.field_evaluations);
    st.lost_vertices = ts.lost_vertices;
    st.oriented_vertices += ts.oriented_vertices;
    s.prev_skin = skin;
    if (ts.abandoned) {  // the next frame starts from this sub-step
      st.abandoned = true;
      s.previous = ps;
      return;
    }
  }
  s.previous = pose;
}

/// The geometric skinning a method uses: ddm and cor their own, implicit2013 its
/// `projector.initial` (SkinSetup::projector_initial), tracking2014 its anchors'
/// (SkinSetup::tracker_anchor), the others none (kDqs).
InitialSkinning geometric_of(Method method, const SkinSetup& setup) {
  if (method == Method::kDdm) return InitialSkinning::kDdm;
  if (method == Method::kCor) return InitialSkinning::kCor;
  if (method == Method::kTracking2014) return setup.tracker_anchor;
  return method == Method::kImplicit2013 ? setup.projector_initial : InitialSkinning::kDqs;
}

/// implicit2013's initial skinning (2013 §6): DQS (the paper), DDM or CoR.
void initial_skin(const Skinner& sk, const BakeState& s, const std::vector<Affine>& skin, std::size_t grain,
                  track::Positions& pos) {
  if (s.ddm)
    s.ddm->deform(skin, pos, grain);
  else if (s.cor)
    s.cor->deform(skin, pos, grain);
  else
    dual_quaternion_blend(sk.rig().weights, skin, sk.rig().rest, pos, nullptr, grain);
}

/// Deforms the rest mesh to `pose` by the bake's method into `pos`; returns the method's contact
/// flags (the implicit methods), else null.
const std::vector<std::uint8_t>* deform(const Skinner& sk, Method method, BakeState& s, const Pose& pose,
                                        std::size_t grain, FrameStats& st, track::Positions& pos) {
  const Rig& rig = sk.rig();
  const std::vector<Affine> skin = skinning_matrices(rig, pose);
  switch (method) {
    case Method::kLbs:
      linear_blend(rig.weights, skin, rig.rest, pos, grain);
      return nullptr;
    case Method::kDqs:
      dual_quaternion_blend(rig.weights, skin, rig.rest, pos, nullptr, grain);
      return nullptr;
    case Method::kDdm:
      s.ddm->deform(skin, pos, grain);
      return nullptr;
    case Method::kCor:
      s.cor->deform(skin, pos, grain);
      return nullptr;
    case Method::kImplicit2013: {
      initial_skin(sk, s, skin, grain, pos);
      const track::Positions skinned = s.masked.empty() ? track::Positions{} : pos;
      s.field->set_pose(skin);
      const track::TrackStats ts = s.projector->project(s.field->function(), pos);
      if (!s.masked.empty()) {
        rigid_positions(sk, s, skin, skinned, s.anchors, nullptr);
        blend_masked(s, s.anchors, pos);
      }
      st.tracker_calls = 1;
      st.capped_calls = ts.converged ? 0 : 1;
      st.call_iterations = {ts.iterations};
      st.iterations = ts.iterations;
      st.vertex_updates = double(ts.vertex_updates);
      st.field_evaluations = double(ts.field_evaluations);
      st.lost_vertices = ts.lost_vertices;
      return &s.projector->flags().contact;
    }
    case Method::kTracking2014:
      track_frame(sk, s, pose, grain, st);
      pos = s.current;
      return &s.tracker->flags().contact;
  }
  return nullptr;
}

/// The bake's state at the rest pose: the implicit methods' field at rest, the tracker or the
/// projector built on it.
void start_bake(Skinner& sk, Method method, const BakeOptions& options, BakeState& s) {
  const Rig& rig = sk.rig();
  const SkinSetup& setup = sk.setup();
  const Pose rest = rest_pose(rig);
  if (method == Method::kTracking2014) {
    s.field = &sk.field(setup.tree == TreeKind::k2013 ? TreeKind::k2013 : TreeKind::k2014);
    s.field->set_pose(skinning_matrices(rig, rest));
    s.tracker = make_tracker(sk, *s.field, options.grain);
    // The axis guard repairs the 2014 relaxation; one energy needs no repair pass.
    if (setup.axis_guard && setup.tracker.relaxation != track::Relaxation::kEnergy)
      s.guard = std::make_unique<AxisGuard>(sk.fitted());
  } else if (method == Method::kImplicit2013) {
    s.field = &sk.field(setup.tree == TreeKind::k2014 ? TreeKind::k2014 : TreeKind::k2013);
    s.field->set_pose(skinning_matrices(rig, rest));
    track::ProjectorOptions po = setup.projector;
    po.grain = options.grain;
    po.count_inverted = false;  // the metrics count inverted triangles
    s.projector = std::make_unique<track::Projector2013>(rig.rest, rig.triangles, s.field->function(), po);
  }
  const InitialSkinning geometric = geometric_of(method, setup);
  if (geometric == InitialSkinning::kDdm) s.ddm = &sk.ddm();
  if (geometric == InitialSkinning::kCor) s.cor = &sk.cor();
  s.current = rig.rest;
  s.prev_dqs = rig.rest;  // DQS at the rest pose
  s.previous = rest;
  s.prev_skin = skinning_matrices(rig, rest);
  if (method == Method::kTracking2014 || method == Method::kImplicit2013) {
    s.piece = piece_vertices(sk);
    s.mask = vertex_mask(sk, s.piece);
  }
  for (std::size_t v = 0; v < s.mask.size(); ++v)
    if (s.mask[v] < 1.0f) s.masked.push_back(static_cast<int>(v));
  if (s.tracker && !s.masked.empty()) {  // 2014 Fig. 11 as a term of the tracker's solve
    std::vector<float> stiffness(s.mask.size());
    for (std::size_t v = 0; v < s.mask.size(); ++v) stiffness[v] = 1.0f - s.mask[v];
    s.tracker->set_anchor_stiffness(std::move(stiffness));
  }
}

/// The vertices a frame's iso residual leaves out: the method's contact vertices and, with the
/// tracker, the vertices it smoothed (β > 0) and its free vertices (not held to their iso-values);
/// empty without contact flags (lbs, dqs).
std::vector<std::uint8_t> iso_exclusions(const std::vector<std::uint8_t>* contact,
                                         const track::IsoSurfaceTracker* tracker) {
  std::vector<std::uint8_t> excluded;
  if (contact) {
    excluded = *contact;
    if (tracker) {
      const track::VertexFlags& fl = tracker->flags();
      for (std::size_t v = 0; v < excluded.size(); ++v)
        excluded[v] |= fl.beta[v] > 0 || (!fl.free.empty() && fl.free[v]) ? 1 : 0;
    }
  }
  return excluded;
}

/// A frame's metrics (Skinner::measure).
FrameMetrics measure_frame(Skinner& sk, const Pose& pose, const track::Positions& pos,
                           const BakeOptions& options, const std::vector<std::uint8_t>* contact,
                           const track::IsoSurfaceTracker* tracker) {
  const std::vector<std::uint8_t> excluded = iso_exclusions(contact, tracker);
  return sk.measure(pose, pos, options.self_intersections, contact ? &excluded : nullptr);
}

}  // namespace

struct FrameBaker::State {
  Skinner* sk{nullptr};
  Method method{Method::kDqs};
  BakeOptions options;
  BakeState bake;
  const std::vector<std::uint8_t>* contact{nullptr};
};

FrameBaker::FrameBaker(Skinner& skinner, Method method, const BakeOptions& options)
    : s_(std::make_unique<State>()) {
  s_->sk = &skinner;
  s_->method = method;
  s_->options = options;
  start_bake(skinner, method, options, s_->bake);
}

FrameBaker::~FrameBaker() = default;

track::Positions FrameBaker::next(const Pose& pose, FrameStats* stats) {
  check_pose(s_->sk->rig(), pose);
  FrameStats st;
  const auto t0 = Clock::now();
  track::Positions pos;
  s_->contact = deform(*s_->sk, s_->method, s_->bake, pose, s_->options.grain, st, pos);
  st.ms = ms_since(t0);
  if (s_->options.metrics)
    st.metrics = measure_frame(*s_->sk, pose, pos, s_->options, s_->contact, s_->bake.tracker.get());
  if (stats) *stats = std::move(st);
  return pos;
}

void FrameBaker::set_iteration_cap(int cap) {
  require(cap >= 0, "frame baker iteration cap", "must be >= 0 (got " + std::to_string(cap) + ")",
          "use 0 for the setup's tracker.max_iterations");
  if (s_->bake.tracker)
    s_->bake.tracker->set_max_iterations(cap > 0 ? cap : s_->sk->setup().tracker.max_iterations);
}

void FrameBaker::set_interrupt(std::function<track::TrackInterrupt()> interrupt) {
  if (s_->bake.tracker) s_->bake.tracker->set_interrupt(std::move(interrupt));
}

std::vector<std::uint8_t> FrameBaker::iso_exclusions() const {
  return isokit::skinning::iso_exclusions(s_->contact, s_->bake.tracker.get());
}

const std::vector<std::uint8_t>* FrameBaker::contacts() const {
  return s_->contact;
}

const std::vector<float>& FrameBaker::mask() const {
  return s_->bake.mask;
}

Method FrameBaker::method() const {
  return s_->method;
}

BakeResult Skinner::bake(Method method, const std::vector<Pose>& poses, const BakeOptions& options) {
  check_poses(rig_, poses);
  BakeResult out;
  out.method = method;
  FrameBaker baker(*this, method, options);
  const InitialSkinning geometric = geometric_of(method, setup_);
  if (geometric == InitialSkinning::kDdm) out.setup_seconds = ddm().precompute_seconds();
  if (geometric == InitialSkinning::kCor) out.setup_seconds = cor().precompute_seconds();
  double total_ms = 0, vertex_iterations = 0;
  for (std::size_t f = 0; f < poses.size(); ++f) {
    FrameStats st;
    track::Positions pos = baker.next(poses[f], &st);
    total_ms += st.ms;
    vertex_iterations += st.vertex_updates;
    if (options.metrics) out.worst = f == 0 ? st.metrics : worst_of(out.worst, st.metrics);
    if (progress_)
      progress_(std::string("bake ") + to_string(method), static_cast<int>(f + 1),
                static_cast<int>(poses.size()));
    out.frames.push_back(std::move(pos));
    out.stats.push_back(std::move(st));
  }
  out.mean_ms = total_ms / double(poses.size());
  out.vertex_iterations_per_second = total_ms > 0 ? vertex_iterations / (total_ms * 1e-3) : 0;
  if (same_pose(poses.back(), rest_pose(rig_)))
    out.rest_recovery = max_displacement(out.frames.back(), rig_.rest) / bbox_diagonal(rig_.rest);
  return out;
}

}  // namespace isokit::skinning
