// SPDX-License-Identifier: MIT
// The energy tracker's precomputed model (weights, areas, the global step's factor) and its
// per-call state, with the stages of one call (energy_tracker.h; not installed).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "isokit/core/math.h"
#include "isokit/track/energy_tracker.h"
#include "isokit/track/field.h"
#include "isokit/track/mesh.h"

namespace isokit::track::detail {

using Mat3d = Mat3T<double>;

struct EnergyData;

/// The global step's matrix `(2 L + W + K)` over the unpinned vertices and its sparse Cholesky
/// factor (double precision; energy_system.cpp); with plane targets (tangent_weight < 1) the step
/// solves `(2 L + B + K)` over their 3 coordinates by conjugate gradients preconditioned by it.
class EnergySystem {
 public:
  EnergySystem();
  ~EnergySystem();
  EnergySystem(const EnergySystem&) = delete;
  EnergySystem& operator=(const EnergySystem&) = delete;

  /// Assembles and factors the matrix of `m` (its weights, Wi, Ki and unknowns). Returns whether it
  /// factored (not without unknowns). \throw InputError if the factorisation fails (not positive
  /// definite).
  bool factor(const EnergyData& m);
  /// Solves `(2 L + W + K) x = rhs` for the 3 coordinates: `rhs` is `unknowns by 3` (row-major),
  /// overwritten by the solution.
  void solve(double* rhs, int unknowns) const;
  /// Plane targets: solves `(2 L + B + K) x = rhs` (`rhs` and `x`: 3 · unknowns, interleaved per
  /// unknown) by conjugate gradients from the `x` given, preconditioned by the factor of
  /// `(2 L + W + K)` per coordinate. `normals` per vertex. Returns the iterations taken.
  int solve_planes(const EnergyData& m, const std::vector<Vec3d>& normals, const std::vector<double>& rhs,
                   std::vector<double>& x) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// What a tracker holds between calls, except the factor: inputs, rest-mesh precomputation, the
/// last call's outputs (copyable).
struct EnergyData {
  EnergyTrackerOptions options;
  std::size_t n{0};
  Triangles triangles;
  std::vector<float> iso;
  std::vector<Vec3d> rest;
  Adjacency adj;
  std::vector<double> w;      // wij aligned with adj.neighbors (row i)
  std::vector<double> w_rev;  // wji aligned with adj.neighbors (row i)
  std::vector<double> area;   // Ai / Ā (1 for a vertex without area)
  std::vector<double> iso_w;  // Wi
  std::vector<float> edge;    // mean rest edge length of each vertex
  double diagonal{0};         // rest bounding-box diagonal
  std::vector<float> stiffness;
  std::vector<double> anchor_w;  // Ki (0 for k = 0 and for pinned vertices)
  std::vector<int> unknown;      // per vertex: row in the global system, -1 when pinned
  std::vector<int> moving;       // the unpinned vertices, ascending
  std::vector<int> rotating;     // the vertices whose one-ring can move (unpinned or next to one)
  int unknowns{0};
  double energy_scale{0};  // Σi (Wi + Ki + Σj wij): E of unit moves (EnergyTrackerOptions::energy_tolerance)
  int pending_factorizations{0};              // since the last call (reported in its TrackStats)
  std::function<TrackInterrupt()> interrupt;  // EnergyTracker::set_interrupt
  VertexFlags flags;
  std::vector<double> energy_log;
  std::vector<int> reset_log;

  bool pinned(std::size_t i) const { return unknown[i] < 0; }
  /// Plane targets (EnergySolveOptions::tangent_weight < 1).
  bool planes() const { return options.tangent_weight < 1.f; }
  /// A target without a normal is a point target: Bi = Wi I whatever tangent_weight is.
  static bool point_target(const Vec3d& normal) { return normal.x == 0 && normal.y == 0 && normal.z == 0; }
  /// (xi − p)ᵀ Bi (xi − p) / Wi for a target p with normal `normal` (energy_tracker.h).
  double target_distance2(const Vec3d& xi, const Vec3d& p, const Vec3d& normal) const {
    const Vec3d d = xi - p;
    if (point_target(normal)) return squared_norm(d);
    const double eps = double(options.tangent_weight), dn = dot(normal, d);
    return eps * squared_norm(d) + (1.0 - eps) * dn * dn;
  }
};

/// The data and the factor of its matrix. A copy refactors (the factor is not shared: CHOLMOD's
/// solve writes to its workspace).
struct EnergyModel : EnergyData {
  EnergySystem system;

  EnergyModel() = default;
  explicit EnergyModel(const EnergyData& data) : EnergyData(data) {
    pending_factorizations += system.factor(*this);
  }
  /// Unknowns and Ki from `stiffness`, then a new factor.
  void refactor();
};

/// Builds the model: checks the inputs and options, precomputes weights and areas, factors.
/// \throw InputError as EnergyTracker's constructor.
void build_model(EnergyModel& m, const Positions& rest, const Triangles& triangles, std::vector<float> iso,
                 const EnergyTrackerOptions& options);
/// Every option in its documented range (energy_tracker.h).
void validate_energy_options(const EnergyTrackerOptions& o);

/// Where a vertex's target came from.
enum class TargetKind : std::uint8_t { kNone, kIso, kContact, kLost };

/// Per-vertex targets Pi with their misses |f − iso| (0: contact; infinite: none or lost) and
/// their kinds; also the candidates of one local step.
struct TargetSet {
  std::vector<Vec3d> point;
  std::vector<Vec3d> normal;  // unit normal of the target's plane (∇f/|∇f| at the vertex when it was
                              // found, or the contact surface's at a crease); 0: a point target
  std::vector<float> res;
  std::vector<TargetKind> kind;
};

/// One call's state: positions in double, targets, rotations, the last local step's field samples.
struct EnergyCall {
  EnergyCall(const EnergyModel& model, const FieldFunction& f) : m(model), field(f) {}
  const EnergyModel& m;
  const FieldFunction& field;
  std::vector<Vec3d> x, anchor;
  TargetSet targets;
  std::vector<Mat3d> rot;
  std::vector<float> value;  // f at x (last local step)
  std::vector<Vec3f> grad;   // ∇f at x (last local step)
  std::vector<std::uint8_t> field_contact, lost;
  int resets{0};                          // targets replaced by the bad-target rule in the last local step
  std::vector<std::uint8_t> reset_count;  // per vertex: resets in this call (energy_local.cpp)
  bool frozen_rotations_fitted{false};    // the rotations outside EnergyData::rotating are fitted
  TrackStats stats;
};

/// Local step (energy_local.cpp): field at x, rotations, search, guarded targets.
void local_step(EnergyCall& c);
/// Ri = argmin Σj wij ‖(xi − xj) − Ri (pi − pj)‖² over rotations (the SVD, reflections flipped;
/// isokit/core/rotation_fit.h), for every vertex at the call's first local step, then for
/// EnergyData::rotating only.
void fit_rotations(EnergyCall& c);
/// The bracketed search along ∇f from each moving vertex (field evaluated at x before).
void search_targets(EnergyCall& c, TargetSet& out);
/// Global step (energy_system.cpp): `next` = argmin over x of E(x, R, P) (pinned vertices at x);
/// returns the largest |next − x|.
double global_step(EnergyCall& c, std::vector<Vec3d>& next);
/// E(positions, R, P) summed in a fixed order (independent of the grain).
double energy(const EnergyCall& c, const std::vector<Vec3d>& positions);

/// Anderson acceleration of the fixed-point map x -> G(x) (one local and one global step) over
/// the last `window` iterates (Walker & Ni 2011; for local–global solvers Peng et al. 2018):
/// next = G(xk) − ΔG θ, θ = argmin ‖fk − ΔF θ‖, f = G(x) − x (energy_anderson.cpp).
class Anderson {
 public:
  explicit Anderson(int window) : window_(window) {}
  /// Forgets the history (the next step is the plain G(x)).
  void reset() { count_ = 0; }
  /// `x` (the unpinned coordinates, 3 per vertex) in, its plain step `g` = G(x); `x` out: the
  /// accelerated next iterate, or `g` itself without history or if the fit is not finite (then
  /// returns false).
  bool step(std::vector<double>& x, const std::vector<double>& g);

 private:
  int window_{0}, count_{0};
  std::vector<double> f_prev_, g_prev_;
  std::vector<std::vector<double>> df_, dg_;  // ring of the last `window_` differences
};

}  // namespace isokit::track::detail
