// SPDX-License-Identifier: MIT
/// \file
/// The biharmonic operator generator (2014 §4.2). For each slice `d` it solves `Δ²g = 0` on the
/// `nf x nf` grid over `(f1, f2) ∈ [0, 1]²`, discretised as the minimiser of `Σ (Δ_h g)²` over
/// the interior nodes (5-point Laplacian), with
/// - Dirichlet `g(f1, 0) = f1`, `g(0, f2) = f2`, `g(f1, 1) = g(1, f2) = 1` (2014 eq. 1),
/// - zero normal derivative on both axes, clamped as `g(h, f2) = g(0, f2)`, `g(f1, h) = g(f1, 0)`
///   (the node row next to each axis; the paper does not give a discretisation),
/// - `g = 0.5 + s · dist` at the nodes of every grid cell crossed by a profile curve (2014 eq. 2;
///   `dist` from SliceProfile::constraint_distance, `s` = spec.distance_slope).
///
/// Solver schemes (measured in docs/performance.md):
/// - kSchur: nodes constrained in every slice are eliminated once; nodes constrained in only some
///   slices (the "dynamic" set D, e.g. the growing contact line) are kept through a dense Schur
///   complement `S = M_DD - M_DF M_FF⁻¹ M_FD` and its inverse, computed once. A slice then costs
///   two sparse solves and a dense Cholesky of the smaller of D's free part (`S_ff`) and D's
///   constrained part (capacitance form with `(S⁻¹)_cc`).
/// - kRefactor: the matrix keeps one sparsity pattern for every slice (constrained nodes become
///   identity rows and columns, explicit zeros kept), so the symbolic analysis is done once and
///   each slice is a numeric factorisation + solve.
/// kAuto picks kSchur when |D| ≤ max_schur_nodes. Slices outside the precomputed sets (a `d`
/// between slices whose constraints differ) fall back to kRefactor.
/// \note CHOLMOD is hidden behind a pimpl; kSparseLU uses Eigen's SparseLU (also when isokit was
/// built without CHOLMOD).
/// \throw isokit::InputError (constructor) for an invalid spec or an unavailable backend.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "isokit/operators/grid_operator.h"
#include "isokit/operators/spec.h"

namespace isokit::operators {

/// Version of the generator's output: part of every operator cache key (cache.h), so grids
/// cached by an older generator are regenerated. Bump it whenever a change to the generator (its
/// discretisation, constraints, profile sampling) changes the grids it produces; changes that only
/// alter the cost (solver options, schemes) do not need a bump.
inline constexpr int kBiharmonicGeneratorVersion = 1;

/// Sparse factorisation: CHOLMOD (SuiteSparse) or Eigen's SparseLU; kAuto picks CHOLMOD when
/// isokit was built with it.
enum class SparseBackend { kAuto, kCholmod, kSparseLU };
/// How slices are solved (see the file comment); kAuto picks kSchur when |D| ≤ max_schur_nodes.
enum class SliceScheme { kAuto, kSchur, kRefactor };

/// How the 2014 §4.2 system is solved (the paper names no solver). The options change the cost,
/// not the operator: results agree up to rounding.
struct BiharmonicOptions {
  /// Sparse factorisation backend. Default kAuto.
  SparseBackend backend{SparseBackend::kAuto};
  /// Slice scheme. Default kAuto.
  SliceScheme scheme{SliceScheme::kAuto};
  /// kAuto's limit on the dynamic set |D|, in grid nodes (the Schur complement is a dense
  /// |D| x |D| matrix). Default 1500 (docs/operators.md). Ignored when edit_band_cells > 0.
  int max_schur_nodes{1500};
  /// Interactive editing band, in grid cells: > 0 makes every node within this many cells of a
  /// profile constraint (at any slice) dynamic, so solve_edited() re-solves edited profiles that
  /// stay inside the band with the Schur scheme, at a larger setup cost (docs/performance.md).
  /// Default 0: off.
  int edit_band_cells{0};
  /// Parallel tasks of generate(): the slices are split into this many chunks, each with its own
  /// factorisation. Default 0: one per hardware thread; 1: serial.
  int tasks{0};
  /// Called after each finished slice with (done, total), from worker threads (serialised).
  /// Default: none.
  std::function<void(int, int)> progress;
};

/// What a generator did (for benchmarks and the CLI).
struct GeneratorStats {
  std::string backend;      ///< "cholmod" or "sparselu"
  std::string scheme;       ///< "schur" or "refactor"
  int unknowns{0};          ///< free nodes before profile constraints
  int dynamic_nodes{0};     ///< |D|
  double setup_seconds{0};  ///< constructor (matrix, analysis, Schur complement)
};

class BiharmonicOperatorGenerator {
 public:
  /// Validates the spec and precomputes. \throw isokit::InputError on a bad spec or an
  /// unavailable backend.
  explicit BiharmonicOperatorGenerator(OperatorSpec spec, BiharmonicOptions options = {});
  ~BiharmonicOperatorGenerator();
  BiharmonicOperatorGenerator(const BiharmonicOperatorGenerator&) = delete;
  BiharmonicOperatorGenerator& operator=(const BiharmonicOperatorGenerator&) = delete;

  /// One slice at `d`: `nf * nf` values, `out[i1 * nf + i2] = g(i1 h, i2 h)`. Not thread-safe
  /// (uses the generator's own workspace).
  std::vector<float> solve_slice(double d);
  /// One slice at `d` of an *edited* spec (same resolution; e.g. a dragged control point):
  /// Schur scheme when its constraints stay inside the precomputed dynamic set (see
  /// options.edit_band_cells), else a numeric factorisation. Not thread-safe.
  /// \throw isokit::InputError for an invalid edited spec.
  std::vector<float> solve_edited(double d, const OperatorSpec& edited);
  /// True when the last solve_edited() used the Schur scheme.
  bool last_edit_was_schur() const { return last_edit_schur_; }
  /// All `spec.slices` slices (in parallel, see options.tasks).
  GridOperator generate();

  const OperatorSpec& spec() const;
  const GeneratorStats& stats() const;
  /// True when this build has CHOLMOD.
  static bool has_cholmod();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  bool last_edit_schur_{false};
};

/// One-off: builds a generator and generates the grid.
GridOperator generate_operator(const OperatorSpec& spec, const BiharmonicOptions& options = {});

}  // namespace isokit::operators
