// SPDX-License-Identifier: MIT
// Internal helpers shared by the 2014 tracker and the 2013 projector (not installed).
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "isokit/core/error.h"
#include "isokit/core/math.h"
#include "isokit/track/field.h"
#include "isokit/track/mesh.h"
#include "isokit/track/tracker.h"

namespace isokit::track::detail {

inline bool finite(const Vec3f& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

inline Vec3f row(const Positions& p, Eigen::Index i) {
  return {p(i, 0), p(i, 1), p(i, 2)};
}

/// Copies rows into a flat vector (throws InputError naming `what` and the vertex on NaN/inf).
std::vector<Vec3f> to_points(const Positions& p, const std::string& what);
void from_points(const std::vector<Vec3f>& pts, Positions& p);

/// A cache-friendly vertex order: the vertices sorted by the Morton code of their position
/// (21 bits per axis over the bounding box; ties by index). `order[k]` is the k-th vertex.
std::vector<int> spatial_order(const std::vector<Vec3f>& pts);

/// Mean rest length of each vertex's edges (global mean for isolated vertices).
std::vector<float> mean_edge_lengths(const std::vector<Vec3f>& rest, const Adjacency& adj);
float bbox_diagonal(const std::vector<Vec3f>& pts);

/// Index of neighbour `j` in the row of `i` (CSR), or -1.
int find_neighbor(const Adjacency& adj, int i, int j);

/// Cotangent weights aligned with adj.neighbors, clamped per corner to [0, max_cot]; a vertex
/// whose weights sum to 0 gets uniform weights 1. Also returns the per-vertex sums.
void cotangent_weights(const std::vector<Vec3f>& rest, const Triangles& triangles, const Adjacency& adj,
                       float max_cot, std::vector<float>& weights, std::vector<float>& sums);

/// Diffuses β from the contact flags and applies the Laplacian smoothing (double-buffered).
/// Returns the number of vertices with β > 0.
int contact_smoothing(const Adjacency& adj, const std::vector<std::uint8_t>& contact,
                      const SmoothingOptions& options, std::size_t grain, std::vector<Vec3f>& pts,
                      std::vector<float>& beta);

/// Fold repair (TrackerOptions::fold_repair): tests the triangles around the vertices with β > 0
/// (moved by the contact smoothing); the vertices of those inverted (and not `rest_inverted`),
/// grown by `rings` rings, take `steps` double-buffered Laplacian steps and get β = 1 and
/// `touched`; the triangles around them are tested again, up to `rounds` rounds. `lost` vertices,
/// and those with `movable[i] == 0` (when `movable` is not empty), stay where they are. Nothing is done when
/// the first round's vertices exceed `max_fraction` of the mesh. Every triangle it tests gets its
/// flag in `inverted` and `fresh[f] = 1` (`fresh` is resized to the triangles), reset to 0 when
/// one of its vertices moves afterwards: the final statistics need not test the fresh ones again.
/// Returns the number of vertices moved.
int fold_repair(const FieldFunction& field, const Triangles& triangles, const Adjacency& adj,
                const Adjacency& vertex_faces, const std::vector<std::uint8_t>& rest_inverted,
                const std::vector<std::uint8_t>& lost, const std::vector<std::uint8_t>& movable,
                const FoldRepairOptions& options, std::size_t grain, std::vector<Vec3f>& pts,
                std::vector<float>& beta, std::vector<std::uint8_t>& touched,
                std::vector<std::uint8_t>& inverted, std::vector<std::uint8_t>& fresh);

/// Orientation repair (TrackerOptions::orientation_repair): moves single vertices of the triangles
/// flagged in `inverted` (and not `rest_inverted`) so that fewer of their triangles are inverted,
/// never to a position where one of its triangles crosses another triangle; `lost` vertices and
/// those with `movable[i] == 0` (when `movable` is not empty) stay. Updates `inverted` for the
/// triangles around the moved vertices and returns the moved vertices (sorted).
std::vector<int> orientation_repair(const FieldFunction& field, const Triangles& triangles,
                                    const Adjacency& vertex_faces,
                                    const std::vector<std::uint8_t>& rest_inverted,
                                    const std::vector<std::uint8_t>& lost,
                                    const std::vector<std::uint8_t>& movable,
                                    const OrientationRepairOptions& options, std::vector<Vec3f>& pts,
                                    std::vector<std::uint8_t>& inverted);

/// Per triangle: 1 if its normal `(b - a) x (c - a)` points along `+∇f` at its centroid
/// (`dot > 0`; a zero gradient does not count), the definition of an inverted triangle.
/// With `candidates`, only the listed triangles are tested (the others get 0).
std::vector<std::uint8_t> inverted_triangles(const FieldFunction& field, const std::vector<Vec3f>& pts,
                                             const Triangles& triangles, std::size_t grain,
                                             const std::vector<int>* candidates = nullptr);

/// Contact / lost counts and iso residuals over the vertices with β == 0 that are neither contact
/// nor lost and have a finite value.
void vertex_stats(const std::vector<float>& values, const std::vector<float>& iso, const VertexFlags& flags,
                  TrackStats& stats);

/// Final statistics: residuals over vertices with β == 0 and a usable field value, contact
/// flags from the field (OR-ed into `contact`), inverted triangles (taken from `inverted` when
/// given: the flags of these very positions).
void final_stats(const FieldFunction& field, const std::vector<Vec3f>& pts, const Triangles& triangles,
                 const std::vector<float>& iso, std::size_t grain, VertexFlags& flags, TrackStats& stats,
                 const std::vector<std::uint8_t>* inverted = nullptr);

/// Triangles around each vertex, in CSR form (`neighbors` holds triangle indices).
Adjacency vertex_faces(const Triangles& triangles, std::size_t num_vertices);

/// Evaluates the field at the listed vertices: `values` updated, field contacts OR-ed into
/// `flags.contact`.
void refresh_values(const FieldFunction& field, const std::vector<Vec3f>& pts, const std::vector<int>& redo,
                    std::size_t grain, std::vector<float>& values, VertexFlags& flags);

/// Final statistics of the active-set tracker. `values` holds each vertex's value at its last
/// evaluation; the vertices marked `touched` (moved after the first evaluation, or smoothed) are
/// evaluated again at `pts`, the others keep that value (they moved by less than the tolerance
/// since). `inverted` holds the flags of the positions before the contact smoothing; the
/// triangles around a smoothed vertex (β > 0) are tested again, so the count is exact — except
/// those marked in `fresh` (tested at these very positions by the fold repair).
void final_stats_touched(const FieldFunction& field, const std::vector<Vec3f>& pts,
                         const Triangles& triangles, const Adjacency& vertex_faces,
                         const std::vector<float>& iso, std::vector<float>& values,
                         const std::vector<std::uint8_t>& touched, std::size_t grain, VertexFlags& flags,
                         TrackStats& stats, std::vector<std::uint8_t>& inverted,
                         const std::vector<std::uint8_t>* fresh = nullptr);

/// Calls the field over [0, n) in parallel chunks (each chunk one call).
void eval_field(const FieldFunction& field, const Vec3f* pts, std::size_t n, float* values, Vec3f* grads,
                std::uint8_t* contact, std::size_t grain);

/// The tangential ARAP system of one relaxation step (2014 §5.2, solved instead of one Jacobi
/// sweep): unknown displacements d_i of the listed vertices, the others held in place,
/// `(Σj wij / s_i) d_i - Σ_{j unknown} wij dj = Σj wij ((pj - pi) + tij)`, each row and d_i
/// restricted to the tangent plane of `normals[i]` unless `free3d[i]`. Per-vertex arrays are
/// indexed by vertex, `weights` and `targets` by directed edge.
struct TangentProblem {
  const Adjacency* adj{nullptr};
  const float* weights{nullptr};
  const float* weight_sums{nullptr};
  const Vec3f* targets{nullptr};
  const Vec3f* positions{nullptr};
  const Vec3f* normals{nullptr};
  const std::uint8_t* free3d{nullptr};
  const float* scale{nullptr};  ///< s_i in (0, 1]: mask × damping
  float tolerance{0};           ///< stop when every |r_i| / diag_i is below this (a Jacobi step)
  int max_iterations{100};
};

/// Jacobi-preconditioned conjugate gradient on `p` (filtered PCG). `local` has one entry per
/// vertex, all -1 (restored on return); `d` receives one displacement per unknown. Serial and
/// deterministic. Returns the CG iterations run.
int solve_tangential_cg(const TangentProblem& p, const std::vector<int>& unknowns, std::vector<int>& local,
                        std::vector<Vec3f>& d);

/// Every triangle's indices lie in [0, num_vertices) and are distinct; throws naming the triangle.
void validate_triangles(const Triangles& triangles, int num_vertices);
void validate_mesh(const Positions& rest, const Triangles& triangles, std::size_t iso_size);

/// Checks the per-call inputs shared by the tracker and the projector: one position per vertex
/// and a non-empty field function.
inline void validate_call(const Positions& positions, std::size_t n, const FieldFunction& field) {
  require(
      static_cast<std::size_t>(positions.rows()) == n, "initial positions",
      "have " + std::to_string(positions.rows()) + " rows, the mesh has " + std::to_string(n) + " vertices",
      "pass one position per vertex");
  require(static_cast<bool>(field), "field", "is empty", "pass a field function");
}

}  // namespace isokit::track::detail
