// SPDX-License-Identifier: MIT
/// \file
/// The skinning pipeline: a rig (with weights, or heat weights computed on load), its fitted
/// implicit skin, and the four methods compared on the same animation:
/// - `lbs`: linear blend skinning;
/// - `dqs`: dual-quaternion skinning (Kavan et al. 2008);
/// - `implicit2013`: DQS, then the 2013 projector on the 2013 tree (Implicit Skinning §5);
/// - `tracking2014`: incremental tracking on the 2014 tree (2014 §5): each vertex moved by its
///   partition joint's rigid delta, Newton projection, tangential ARAP relaxation with
///   DQS-blended target rotations, contact smoothing; animation steps split by sub-stepping;
/// - `ddm`: Direct Delta Mush (Le & Lewis 2019; ddm.h), after a per-rig precomputation;
/// - `cor`: skinning with optimized centers of rotation (Le & Hodgins 2016; cor.h), after a
///   per-rig precomputation.
/// Every method's frames are measured with the same field (the 2014 tree) and the same
/// geometric metrics (metrics.h, docs/QUALITY.md).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "isokit/skinning/animation.h"
#include "isokit/skinning/cor.h"
#include "isokit/skinning/ddm.h"
#include "isokit/skinning/metrics.h"
#include "isokit/skinning/rig.h"
#include "isokit/skinning/setup.h"
#include "isokit/skinning/skin_field.h"

namespace isokit::skinning {

/// A rig from `procedural:<spec>` (procedural.h) or a file (rig_io.h, clips sampled at `fps`);
/// heat-diffusion weights (weights.h) are computed when it has none. `warnings` (optional)
/// receives the loader's warnings (LoadReport::warnings); `mask` says where a file keeps the
/// relaxation mask (SkinSetup::mask). \throw InputError naming the file / spec and the item.
Rig open_rig(const std::string& spec, double fps = 30, const Progress& progress = {},
             std::vector<std::string>* warnings = nullptr, const MaskSource& mask = {});

/// Fixed order (benchmarks index it): the four original methods, then the geometric ones added.
enum class Method { kLbs, kDqs, kImplicit2013, kTracking2014, kDdm, kCor };

const char* to_string(Method m);

/// The method used where none is named: `isokit-skin bake` and `view`, `Skinner.bake` in Python,
/// the Blender add-on and isokit-batch. It is the implicit method with the highest total of the
/// real-rig evaluation against the best geometric method (`make eval`, then
/// bench/eval/score_vs_geometric.py, which warns when the score puts another method first):
/// docs/decisions/default-method-follows-the-score.md.
constexpr Method kDefaultMethod = Method::kImplicit2013;

/// \throw InputError listing the methods for an unknown name.
Method method_from_string(const std::string& s);
std::vector<Method> all_methods();

struct FrameStats {
  double ms{0};       ///< deformation time of the frame (all sub-steps; no metrics)
  int substeps{1};    ///< tracking2014 sub-steps (2014 §5.2)
  int iterations{0};  ///< tracker iterations (sum over sub-steps) or projector steps
  /// Vertex updates: tracker active-set sizes summed over iterations and sub-steps
  /// (tracking2014), or vertices × projector steps (implicit2013).
  double vertex_updates{0};
  /// Field evaluations of the tracker (tracking2014, summed over sub-steps; fewer than the vertex
  /// updates with lazy evaluation), or vertices × projector steps (implicit2013).
  double field_evaluations{0};
  int lost_vertices{0};  ///< vertices without a usable gradient (left in place by the tracker)
  int axis_guard_moves{
      0};  ///< vertices put back across their bone's axis (`AxisGuard`, summed over sub-steps)
  /// Vertices moved by the tracker's orientation repair (summed over sub-steps).
  int oriented_vertices{0};
  /// Calls of the tracker (tracking2014: one per sub-step) or of the projector (implicit2013:
  /// one per frame); 0 for lbs and dqs.
  int tracker_calls{0};
  /// Of those, the calls that stopped at the iteration cap without converging
  /// (`TrackStats::converged` false: `TrackerOptions::max_iterations`,
  /// `ProjectorOptions::max_iterations`).
  int capped_calls{0};
  /// The frame was abandoned for a newer pose (FrameBaker::set_interrupt): its positions are a
  /// starting guess at the sub-step reached, not a result.
  bool abandoned{false};
  /// The iterations of each of those calls (TrackStats::iterations), in call order.
  std::vector<int> call_iterations;
  FrameMetrics metrics;  ///< all quality metrics (field ones with the 2014 tree)
};

struct BakeResult {
  Method method{Method::kDqs};
  std::vector<track::Positions> frames;  ///< welded positions per frame
  std::vector<FrameStats> stats;
  FrameMetrics worst;        ///< worst over frames
  double rest_recovery{-1};  ///< last frame vs rest / bbox diagonal, when the last pose is the rest pose
  double mean_ms{0};
  double vertex_iterations_per_second{0};  ///< vertex updates per second of deformation time
  /// Seconds of the method's own precomputation on this rig (ddm, cor, and implicit2013 started
  /// from them; `Skinner::ddm` / `cor`), as measured when it was made, even when this bake took
  /// it from the process cache; 0 for the other methods. The fit is `FittedRig::fit_seconds`.
  double setup_seconds{0};
};

struct BakeOptions {
  bool metrics{true};
  bool self_intersections{true};  ///< exact count per frame (the slowest metric)
  std::size_t grain{1024};        ///< parallel grain (0 = serial, same results)
};

class Skinner;

/// A bake one frame at a time (the viewer, live previews): the state of `Skinner::bake` kept
/// between calls, so that the frames of `next` over a list of poses equal `bake`'s over the same
/// list, bit for bit (`bake` runs on it). The tracking starts from the rest mesh at the rest pose.
/// The skinner must outlive it.
class FrameBaker {
 public:
  /// \throw InputError as Skinner::bake (a field that cannot be built).
  FrameBaker(Skinner& skinner, Method method, const BakeOptions& options = {});
  ~FrameBaker();
  FrameBaker(const FrameBaker&) = delete;
  FrameBaker& operator=(const FrameBaker&) = delete;

  /// Deforms the rest mesh to `pose` (local joint transforms), from the last frame's state;
  /// `stats` receives the frame's statistics and, with BakeOptions::metrics, its metrics.
  /// \throw InputError for a pose with the wrong joint count.
  track::Positions next(const Pose& pose, FrameStats* stats = nullptr);
  /// Caps the tracker's iterations per call of the next frames (tracking2014; count, ≥ 1; 0 = the
  /// setup's `tracker.max_iterations`, the default). \throw InputError for a negative cap.
  void set_iteration_cap(int cap);
  /// The tracker's interrupt for the next frames (tracking2014; IsoSurfaceTracker::set_interrupt;
  /// empty, the default: none): a live preview bounds its time per frame (kStop) and continues
  /// the solve with `next` at the same pose, or drops a frame for a newer pose (kAbandon: the
  /// frame ends at the sub-step where it was abandoned, FrameStats::abandoned; the next frame
  /// starts there). Frames cut short differ from `bake`'s.
  void set_interrupt(std::function<track::TrackInterrupt()> interrupt);
  /// The method's contact flags of the last frame (implicit methods), else null.
  const std::vector<std::uint8_t>* contacts() const;
  /// The vertices the last frame's iso residual leaves out (contact, smoothed and free vertices;
  /// empty for lbs and dqs): `Skinner::measure(pose, positions, ..., &this)` of a frame measured
  /// later equals the metrics of `next` with BakeOptions::metrics.
  std::vector<std::uint8_t> iso_exclusions() const;
  /// The relaxation mask per vertex in use (empty: every vertex tracked; lbs and dqs: empty).
  const std::vector<float>& mask() const;
  Method method() const;

 private:
  struct State;
  std::unique_ptr<State> s_;
};

/// What the skin-only metrics need of `rig` (metrics.h): its weights, the rest pose's skinning
/// matrices, and the vertices of every rigid piece (find_rigid_pieces, whatever the setup), so
/// that the metrics depend on the rig alone and every method is measured on the same skin.
SkinReference metrics_reference(const Rig& rig);

class Skinner {
 public:
  /// Validates the rig, computes heat weights when it has none, partitions and fits (progress
  /// on `progress`). \throw InputError naming the rig and the item.
  Skinner(Rig rig, SkinSetup setup = {}, Progress progress = {});
  ~Skinner();

  const Rig& rig() const { return rig_; }
  const SkinSetup& setup() const { return setup_; }
  const FittedRig& fitted() const { return *fitted_; }
  /// The composed field of a tree kind (built on first use).
  SkinField& field(TreeKind kind);
  /// The Direct Delta Mush / center-of-rotation precomputation of this rig with the setup's
  /// `ddm` / `cor` options, made on first use and kept in a process cache under a content key
  /// (rest mesh, triangles, weights, joint count, options), so skinners of the same rig share it.
  const DirectDeltaMush& ddm();
  const CorSkinning& cor();

  /// Runs `method` over `poses` (local joint transforms per frame). The tracking starts from the
  /// rest mesh at the rest pose and sub-steps into the first frame.
  BakeResult bake(Method method, const std::vector<Pose>& poses, const BakeOptions& options = {});

  /// Quality metrics of positions at a pose (field metrics with the 2014 tree).
  /// `contact`, when given, marks vertices excluded from the iso residual (besides the field's
  /// own contact flags).
  FrameMetrics measure(const Pose& pose, const track::Positions& positions, bool self_intersections,
                       const std::vector<std::uint8_t>* contact = nullptr);
  /// The geometric metrics' evaluator (its fold counter and skin triangles feed the overlays).
  const FrameMetricsEvaluator& metrics_evaluator() const { return *evaluator_; }

 private:
  Rig rig_;
  SkinSetup setup_;
  Progress progress_;
  std::unique_ptr<FittedRig> fitted_;
  std::unique_ptr<SkinField> field2013_, field2014_;
  std::shared_ptr<const DirectDeltaMush> ddm_;
  std::shared_ptr<const CorSkinning> cor_;
  std::unique_ptr<FrameMetricsEvaluator> evaluator_;
  std::vector<float> iso2014_;  ///< the metrics' iso-values (2014 tree at rest), sampled on first use
  std::vector<std::uint8_t> rest_inverted_;  ///< triangles already inverted w.r.t. the field at rest
};

}  // namespace isokit::skinning
