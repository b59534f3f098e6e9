// SPDX-License-Identifier: MIT
// Geometric skin metrics: volume, edge distortion, displacement, per-frame evaluation.
#include "isokit/skinning/metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>

#include "isokit/core/error.h"
#include "isokit/core/mesh_quality.h"
#include "metrics/metrics_check.h"

namespace isokit::skinning {
namespace {

Eigen::Vector3d point(const track::Positions& p, Eigen::Index v) {
  return p.row(v).cast<double>().transpose();
}

/// Unique undirected edges `{a, b}` with `a < b`, sorted (repeated indices give no edge).
std::vector<std::array<int, 2>> unique_edges(const track::Triangles& triangles) {
  std::vector<std::uint64_t> keys;
  keys.reserve(static_cast<std::size_t>(triangles.rows()) * 3);
  for (Eigen::Index f = 0; f < triangles.rows(); ++f)
    for (int c = 0; c < 3; ++c) {
      const int a = triangles(f, c), b = triangles(f, (c + 1) % 3);
      if (a == b) continue;
      const auto lo = static_cast<std::uint32_t>(std::min(a, b));
      const auto hi = static_cast<std::uint32_t>(std::max(a, b));
      keys.push_back(std::uint64_t(lo) << 32 | hi);
    }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<std::array<int, 2>> edges(keys.size());
  for (std::size_t e = 0; e < keys.size(); ++e)
    edges[e] = {static_cast<int>(keys[e] >> 32), static_cast<int>(keys[e] & 0xffffffffu)};
  return edges;
}

std::vector<double> edge_lengths(const track::Positions& p, const std::vector<std::array<int, 2>>& edges) {
  std::vector<double> len(edges.size());
  for (std::size_t e = 0; e < edges.size(); ++e)
    len[e] = (point(p, edges[e][1]) - point(p, edges[e][0])).norm();
  return len;
}

EdgeDistortion distortion(const track::Positions& posed, const std::vector<std::array<int, 2>>& edges,
                          const std::vector<double>& rest_lengths) {
  EdgeDistortion d;
  double sum = 0;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    if (rest_lengths[e] == 0) {
      ++d.zero_rest_edges;
      continue;
    }
    const double len = (point(posed, edges[e][1]) - point(posed, edges[e][0])).norm();
    const double err = std::abs(len / rest_lengths[e] - 1);
    sum += err;
    ++d.edges;
    if (err > d.max || d.worst_edge[0] < 0) {
      d.max = err;
      d.worst_edge = edges[e];
    }
  }
  d.mean = d.edges > 0 ? sum / d.edges : 0;
  return d;
}

/// Larger of two values where NaN means "not computed".
double worse(double a, double b) {
  if (std::isnan(a)) return b;
  if (std::isnan(b)) return a;
  return std::max(a, b);
}
int worse(int a, int b) {
  return std::max(a, b);
}  // -1 = not computed

/// The rows of `triangles` whose component is closed.
track::Triangles closed_rows(const track::Triangles& triangles, const MeshClosure& closure) {
  std::vector<Eigen::Index> rows;
  for (Eigen::Index f = 0; f < triangles.rows(); ++f)
    if (closure.components[static_cast<std::size_t>(closure.component[static_cast<std::size_t>(f)])].closed())
      rows.push_back(f);
  track::Triangles out(static_cast<Eigen::Index>(rows.size()), 3);
  for (std::size_t i = 0; i < rows.size(); ++i)
    out.row(static_cast<Eigen::Index>(i)) = triangles.row(rows[i]);
  return out;
}

/// The rows of `triangles` with no corner in `excluded` (a per-vertex flag).
track::Triangles rows_without(const track::Triangles& triangles, const std::vector<char>& excluded) {
  std::vector<Eigen::Index> rows;
  for (Eigen::Index f = 0; f < triangles.rows(); ++f)
    if (!excluded[triangles(f, 0)] && !excluded[triangles(f, 1)] && !excluded[triangles(f, 2)])
      rows.push_back(f);
  track::Triangles out(static_cast<Eigen::Index>(rows.size()), 3);
  for (std::size_t i = 0; i < rows.size(); ++i)
    out.row(static_cast<Eigen::Index>(i)) = triangles.row(rows[i]);
  return out;
}

/// max(0, overlap − rest overlap) / rest enclosed volume (NaN when nothing is enclosed at rest).
double new_overlap_share(double overlap, const SelfOverlap& rest) {
  if (!(rest.enclosed > 0)) return FrameMetrics::kNotComputed;
  return std::max(0.0, overlap - rest.overlap) / rest.enclosed;
}

}  // namespace

double enclosed_volume(const track::Positions& positions, const track::Triangles& triangles) {
  detail::check_triangles(triangles, positions.rows(), "enclosed_volume");
  if (positions.rows() == 0) return 0;
  const Eigen::Vector3d centre = bounding_box(positions).center();
  double six_volume = 0;
  for (Eigen::Index f = 0; f < triangles.rows(); ++f) {
    const Eigen::Vector3d a = point(positions, triangles(f, 0)) - centre;
    const Eigen::Vector3d b = point(positions, triangles(f, 1)) - centre;
    const Eigen::Vector3d c = point(positions, triangles(f, 2)) - centre;
    six_volume += a.dot(b.cross(c));
  }
  return six_volume / 6;
}

EdgeDistortion edge_distortion(const track::Positions& rest, const track::Positions& posed,
                               const track::Triangles& triangles) {
  detail::check_same_vertex_count(rest, posed, "edge_distortion");
  detail::check_triangles(triangles, rest.rows(), "edge_distortion");
  const auto edges = unique_edges(triangles);
  return distortion(posed, edges, edge_lengths(rest, edges));
}

double max_displacement(const track::Positions& a, const track::Positions& b) {
  detail::check_same_vertex_count(a, b, "max_displacement");
  double worst = 0;
  for (Eigen::Index v = 0; v < a.rows(); ++v) worst = std::max(worst, (point(a, v) - point(b, v)).norm());
  return worst;
}

Eigen::AlignedBox3d bounding_box(const track::Positions& positions) {
  Eigen::AlignedBox3d box;  // empty
  for (Eigen::Index v = 0; v < positions.rows(); ++v) box.extend(point(positions, v));
  return box;
}

double bbox_diagonal(const track::Positions& positions) {
  return isokit::bbox_diagonal<double>(static_cast<std::size_t>(positions.rows()), [&](std::size_t v) {
    const auto r = static_cast<Eigen::Index>(v);
    return Vec3d{positions(r, 0), positions(r, 1), positions(r, 2)};
  });
}

FrameMetrics worst_of(const FrameMetrics& a, const FrameMetrics& b) {
  FrameMetrics w;
  w.self_intersections = worse(a.self_intersections, b.self_intersections);
  w.self_intersections_new = worse(a.self_intersections_new, b.self_intersections_new);
  w.degenerate_faces = worse(a.degenerate_faces, b.degenerate_faces);
  w.self_overlap = worse(a.self_overlap, b.self_overlap);
  w.self_overlap_new = worse(a.self_overlap_new, b.self_overlap_new);
  w.skin_overlap = worse(a.skin_overlap, b.skin_overlap);
  w.skin_overlap_new = worse(a.skin_overlap_new, b.skin_overlap_new);
  w.folded_triangles = worse(a.folded_triangles, b.folded_triangles);
  w.folded_new = worse(a.folded_new, b.folded_new);
  w.inverted_triangles = worse(a.inverted_triangles, b.inverted_triangles);
  w.new_inverted_triangles = worse(a.new_inverted_triangles, b.new_inverted_triangles);
  w.contact_vertices = worse(a.contact_vertices, b.contact_vertices);
  w.edge_distortion_mean = worse(a.edge_distortion_mean, b.edge_distortion_mean);
  w.edge_distortion_max = worse(a.edge_distortion_max, b.edge_distortion_max);
  w.max_displacement = worse(a.max_displacement, b.max_displacement);
  w.rest_distance = worse(a.rest_distance, b.rest_distance);
  w.iso_residual_max = worse(a.iso_residual_max, b.iso_residual_max);
  w.iso_residual_mean = worse(a.iso_residual_mean, b.iso_residual_mean);
  // Volume: the frame whose ratio is farthest from 1 supplies both volume and ratio.
  const bool a_ok = !std::isnan(a.volume_ratio), b_ok = !std::isnan(b.volume_ratio);
  const FrameMetrics& v = !a_ok   ? b
                          : !b_ok ? a
                                  : (std::abs(b.volume_ratio - 1) > std::abs(a.volume_ratio - 1) ? b : a);
  w.volume = v.volume;
  w.volume_ratio = v.volume_ratio;
  if (std::isnan(w.volume)) w.volume = std::isnan(a.volume) ? b.volume : a.volume;
  return w;
}

FrameMetricsEvaluator::~FrameMetricsEvaluator() = default;

FrameMetricsEvaluator::FrameMetricsEvaluator(track::Positions rest, track::Triangles triangles,
                                             SelfIntersectionOptions options, SkinReference skin)
    : rest_(std::move(rest)), triangles_(std::move(triangles)), options_(options) {
  detail::check_triangles(triangles_, rest_.rows(), "FrameMetricsEvaluator");
  edges_ = unique_edges(triangles_);
  rest_lengths_ = edge_lengths(rest_, edges_);
  closure_ = mesh_closure(triangles_, rest_.rows());
  closed_triangles_ = closure_.closed() ? triangles_ : closed_rows(triangles_, closure_);
  rest_volume_ = closed_triangles_.rows() > 0 ? enclosed_volume(rest_, closed_triangles_) : 0.0;
  rest_diagonal_ = bbox_diagonal(rest_);
  rest_overlap_ = self_overlap(rest_, triangles_);
  skin_triangles_ = triangles_;
  if (!skin.rigid_vertices.empty()) {
    std::vector<char> rigid(static_cast<std::size_t>(rest_.rows()), 0);
    for (int v : skin.rigid_vertices) {
      require(v >= 0 && v < rest_.rows(), "FrameMetricsEvaluator: rigid vertex " + std::to_string(v),
              "outside the mesh's " + std::to_string(rest_.rows()) + " vertices",
              "pass vertex indices of this mesh (find_rigid_pieces)");
      rigid[static_cast<std::size_t>(v)] = 1;
    }
    skin_triangles_ = rows_without(triangles_, rigid);
    has_rigid_ = skin_triangles_.rows() < triangles_.rows();
  }
  rest_skin_overlap_ = has_rigid_ ? self_overlap(rest_, skin_triangles_) : rest_overlap_;
  if (!skin.weights.empty())
    folds_ = std::make_unique<FoldCounter>(rest_, triangles_, skin.weights, skin.rest_skin);
}

const std::vector<std::array<int, 2>>& FrameMetricsEvaluator::rest_pairs() const {
  std::call_once(rest_pairs_once_, [this] {
    SelfIntersectionDetails details;
    SelfIntersectionOptions options = options_;
    options.max_pairs = std::numeric_limits<int>::max();
    count_self_intersections(rest_, triangles_, &details, options);
    rest_pairs_ = std::move(details.pairs);
  });
  return rest_pairs_;
}

FrameMetrics FrameMetricsEvaluator::evaluate(const track::Positions& posed, bool self_intersections,
                                             bool overlap, const std::vector<Affine>* skin) const {
  detail::check_same_vertex_count(rest_, posed, "FrameMetricsEvaluator::evaluate");
  FrameMetrics m;
  if (self_intersections) {
    const std::vector<std::array<int, 2>>& at_rest = rest_pairs();
    SelfIntersectionDetails details;
    SelfIntersectionOptions options = options_;
    options.max_pairs = std::numeric_limits<int>::max();
    m.self_intersections = count_self_intersections(posed, triangles_, &details, options);
    m.degenerate_faces = details.degenerate_count;
    // Both lists are sorted: the pairs of this frame not in the rest list.
    m.self_intersections_new = 0;
    for (const auto& pair : details.pairs)
      m.self_intersections_new += std::binary_search(at_rest.begin(), at_rest.end(), pair) ? 0 : 1;
  }
  if (overlap) {
    m.self_overlap = self_overlap(posed, triangles_).overlap;
    m.self_overlap_new = new_overlap_share(m.self_overlap, rest_overlap_);
    m.skin_overlap = has_rigid_ ? self_overlap(posed, skin_triangles_).overlap : m.self_overlap;
    m.skin_overlap_new = new_overlap_share(m.skin_overlap, rest_skin_overlap_);
  }
  if (folds_ && skin) {
    const FoldCounter::Count c = folds_->count(folds_->folded(posed, *skin));
    m.folded_triangles = c.folded;
    m.folded_new = c.folded_new;
  }
  if (closed_triangles_.rows() > 0) {
    m.volume = enclosed_volume(posed, closed_triangles_);
    if (rest_volume_ != 0) m.volume_ratio = m.volume / rest_volume_;
  }
  const EdgeDistortion d = distortion(posed, edges_, rest_lengths_);
  m.edge_distortion_mean = d.mean;
  m.edge_distortion_max = d.max;
  m.max_displacement = max_displacement(rest_, posed);
  if (rest_diagonal_ > 0) m.rest_distance = m.max_displacement / rest_diagonal_;
  return m;
}

}  // namespace isokit::skinning
