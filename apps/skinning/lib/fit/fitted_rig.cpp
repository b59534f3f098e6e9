// SPDX-License-Identifier: MIT
#include "isokit/skinning/fitted_rig.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <mutex>
#include <numeric>
#include <set>
#include <utility>

#include "isokit/core/error.h"
#include "isokit/core/parallel.h"
#include "isokit/implicit/fit_quality.h"
#include "isokit/implicit/skeleton.h"
#include "isokit/operators/biharmonic.h"
#include "isokit/operators/controller.h"
#include "isokit/skinning/deform.h"
#include "isokit/track/mesh.h"

namespace isokit::skinning {

std::vector<int> clean_partition(const std::vector<int>& labels, const track::Triangles& triangles,
                                 int num_vertices) {
  const track::Adjacency adj = track::vertex_adjacency(triangles, num_vertices);
  std::vector<int> out = labels;
  for (int round = 0; round < 8; ++round) {
    // Components of equal labels.
    std::vector<int> comp(static_cast<std::size_t>(num_vertices), -1), size;
    std::vector<int> stack;
    for (int s = 0; s < num_vertices; ++s) {
      if (comp[s] >= 0) continue;
      const int id = static_cast<int>(size.size());
      size.push_back(0);
      comp[s] = id;
      stack.push_back(s);
      while (!stack.empty()) {
        const int v = stack.back();
        stack.pop_back();
        ++size[id];
        for (int k = adj.offsets[v]; k < adj.offsets[v + 1]; ++k) {
          const int u = adj.neighbors[k];
          if (comp[u] < 0 && out[u] == out[v]) {
            comp[u] = id;
            stack.push_back(u);
          }
        }
      }
    }
    // Largest component per label.
    std::map<int, int> best;  // label -> component
    for (int v = 0; v < num_vertices; ++v) {
      auto it = best.find(out[v]);
      if (it == best.end() || size[comp[v]] > size[it->second]) best[out[v]] = comp[v];
    }
    // Reassign the others by majority of outside neighbours.
    std::map<int, std::map<int, int>> votes;  // component -> label -> count
    for (int v = 0; v < num_vertices; ++v) {
      if (best[out[v]] == comp[v]) continue;
      for (int k = adj.offsets[v]; k < adj.offsets[v + 1]; ++k) {
        const int u = adj.neighbors[k];
        if (comp[u] != comp[v]) ++votes[comp[v]][out[u]];
      }
    }
    if (votes.empty()) break;
    std::map<int, int> target;
    for (const auto& [c, vs] : votes) {
      int lab = -1, cnt = -1;
      for (const auto& [l, n] : vs)
        if (n > cnt) {
          lab = l;
          cnt = n;
        }
      target[c] = lab;
    }
    bool changed = false;
    for (int v = 0; v < num_vertices; ++v) {
      auto it = target.find(comp[v]);
      if (it != target.end() && out[v] != it->second) {
        out[v] = it->second;
        changed = true;
      }
    }
    if (!changed) break;
  }
  return out;
}

namespace {

/// The partition seen per joint (recomputed at each pass, after failed fits are merged).
struct JointParts {
  const Rig& rig;
  const std::vector<Eigen::Vector3d>& joint_positions;  ///< rest, per joint
  const std::vector<int>& partition;                    ///< joint per vertex
  std::vector<std::vector<int>> triangles;              ///< per joint: its triangles
  std::vector<int> count;                               ///< per joint: its vertices
  std::vector<std::vector<int>> children;               ///< per joint: its child joints
  std::vector<Eigen::Vector3d> normals;                 ///< per vertex: unit area-weighted normal (rest)
  std::vector<double> edge;                             ///< per vertex: mean length of its edges (rest)

  /// Nearest ancestor of `j` with vertices (-1: none): a part to close the start against.
  int ancestor_with_vertices(int j) const {
    int p = rig.joints[j].parent;
    while (p >= 0 && count[p] == 0) p = rig.joints[p].parent;
    return p;
  }
};

/// Step 1 (docs/skinning.md "Pipeline", 1): the triangles, vertex counts and children of every
/// joint. A triangle belongs to the joint of at least two of its vertices (else to its first
/// vertex's joint).
JointParts joint_parts(const Rig& r, const std::vector<Eigen::Vector3d>& jp,
                       const std::vector<int>& partition) {
  const int nv = static_cast<int>(r.rest.rows());
  const int nj = static_cast<int>(r.joints.size());
  JointParts parts{r, jp, partition, {}, {}, {}, {}, {}};
  parts.triangles.resize(static_cast<std::size_t>(nj));
  for (Eigen::Index f = 0; f < r.triangles.rows(); ++f) {
    const int a = partition[r.triangles(f, 0)], b = partition[r.triangles(f, 1)],
              c = partition[r.triangles(f, 2)];
    const int j = (b == c) ? b : a;
    parts.triangles[static_cast<std::size_t>(j)].push_back(static_cast<int>(f));
  }
  parts.count.assign(static_cast<std::size_t>(nj), 0);
  for (int v = 0; v < nv; ++v) ++parts.count[partition[v]];
  parts.normals.assign(static_cast<std::size_t>(nv), Eigen::Vector3d::Zero());
  parts.edge.assign(static_cast<std::size_t>(nv), 0.0);
  std::vector<int> edges(static_cast<std::size_t>(nv), 0);
  for (Eigen::Index f = 0; f < r.triangles.rows(); ++f) {
    Eigen::Vector3d q[3];
    for (int k = 0; k < 3; ++k) q[k] = r.rest.row(r.triangles(f, k)).transpose().cast<double>();
    const Eigen::Vector3d n = (q[1] - q[0]).cross(q[2] - q[0]);
    for (int k = 0; k < 3; ++k) {
      const std::size_t v = static_cast<std::size_t>(r.triangles(f, k));
      parts.normals[v] += n;
      parts.edge[v] += (q[(k + 1) % 3] - q[k]).norm() + (q[(k + 2) % 3] - q[k]).norm();
      edges[v] += 2;
    }
  }
  for (int v = 0; v < nv; ++v) {
    const double l = parts.normals[v].norm();
    if (l > 0) parts.normals[v] /= l;
    if (edges[v] > 0) parts.edge[v] /= edges[v];
  }
  parts.children.resize(static_cast<std::size_t>(nj));
  for (int j = 0; j < nj; ++j)
    if (r.joints[j].parent >= 0) parts.children[r.joints[j].parent].push_back(j);
  return parts;
}

/// Step 3, second pass (docs/skinning.md "Pipeline", 3): the vertices of every joint whose fit
/// failed go to a neighbour whose part touches its part (the parent, else the child with most
/// vertices) that is fitted, or failed but larger, which is marked in `refit`. \return false
/// when no vertex moved (nothing to refit).
bool merge_failed_fits(const Rig& r, std::vector<BonePart>& bones, std::vector<int>& partition,
                       std::vector<char>& refit) {
  const int nv = static_cast<int>(r.rest.rows());
  const int nj = static_cast<int>(r.joints.size());
  // Joints whose parts share a triangle: a separate piece (a sword, a rigid part) shares no
  // neighbour's primitive; the capsule fallback covers it.
  std::set<std::pair<int, int>> touching;
  for (Eigen::Index f = 0; f < r.triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = partition[r.triangles(f, k)], b = partition[r.triangles(f, (k + 1) % 3)];
      if (a != b) touching.insert({std::min(a, b), std::max(a, b)});
    }
  // Smallest failed parts first. A failed neighbour larger than the part can take it too and is
  // refitted instead of merged (a patch of a neighbour's skin holes a limb: both fits fail, and
  // the limb with its patch back fits); a joint that takes vertices is not merged in this pass.
  std::vector<int> failed;
  for (int j = 0; j < nj; ++j)
    if (!bones[j].fitted && bones[j].vertices > 0) failed.push_back(j);
  std::stable_sort(failed.begin(), failed.end(),
                   [&](int a, int b) { return bones[a].vertices < bones[b].vertices; });
  std::vector<int> target(static_cast<std::size_t>(nj), -1);
  auto can_take = [&](int t, int j) {
    if (target[t] >= 0 || touching.count({std::min(t, j), std::max(t, j)}) == 0) return false;
    return bones[t].fitted || bones[t].vertices > bones[j].vertices;
  };
  for (int j : failed) {
    if (refit[j]) continue;  // takes a smaller part's vertices: refitted, not merged
    int t = r.joints[j].parent;
    if (t < 0 || !can_take(t, j)) {
      t = -1;
      for (int c = 0; c < nj; ++c)
        if (r.joints[c].parent == j && can_take(c, j) && (t < 0 || bones[c].vertices > bones[t].vertices))
          t = c;
    }
    if (t < 0) continue;
    target[j] = t;
    refit[t] = 1;
  }
  bool any = false;
  for (int v = 0; v < nv; ++v)
    if (target[partition[v]] >= 0) {
      partition[v] = target[partition[v]];
      any = true;
    }
  if (!any) return false;
  for (int j = 0; j < nj; ++j)
    if (target[j] >= 0) {
      bones[j].vertices = 0;
      bones[j].merged_into = target[j];
      bones[j].rule = FitRule::shared;
      bones[j].error += " (its vertices were merged into '" + r.joints[target[j]].name + "')";
    }
  return true;
}

/// The mesh of joint `j`'s part: its triangles over its own, locally numbered rest vertices.
implicit::MeshPart part_mesh(const JointParts& parts, int j, const std::string& name) {
  const Rig& r = parts.rig;
  implicit::MeshPart part;
  part.name = name;
  std::vector<int> local(static_cast<std::size_t>(r.rest.rows()), -1);
  for (int f : parts.triangles[j]) {
    std::array<int, 3> t{};
    for (int k = 0; k < 3; ++k) {
      const int v = r.triangles(f, k);
      if (local[v] < 0) {
        local[v] = static_cast<int>(part.vertices.size());
        part.vertices.push_back({r.rest(v, 0), r.rest(v, 1), r.rest(v, 2)});
      }
      t[static_cast<std::size_t>(k)] = local[v];
    }
    part.triangles.push_back(t);
  }
  return part;
}

/// The part's triangles and `rings` rings of its neighbours' triangles around them (each ring:
/// the triangles sharing a vertex with the set), over locally numbered rest vertices. The part's
/// own vertices keep their place first (what the distance field follows across its border). A
/// vertex of ring k is moved `k × sink` of its mean edge length inwards along its normal, so
/// that across the border the neighbour's field, not this one, holds the neighbour's vertices.
void add_overlap_rings(const JointParts& parts, int j, int rings, double sink, implicit::MeshPart& part) {
  const Rig& r = parts.rig;
  const std::size_t nv = static_cast<std::size_t>(r.rest.rows());
  std::vector<char> in_set(static_cast<std::size_t>(r.triangles.rows()), 0), vertex_in(nv, 0);
  for (int f : parts.triangles[static_cast<std::size_t>(j)]) {
    in_set[static_cast<std::size_t>(f)] = 1;
    for (int k = 0; k < 3; ++k) vertex_in[static_cast<std::size_t>(r.triangles(f, k))] = 1;
  }
  std::vector<int> local(nv, -1);
  {
    // The numbering part_mesh gave (first use in the joint's triangles).
    int next = 0;
    for (int f : parts.triangles[static_cast<std::size_t>(j)])
      for (int k = 0; k < 3; ++k) {
        int& l = local[static_cast<std::size_t>(r.triangles(f, k))];
        if (l < 0) l = next++;
      }
  }
  for (int ring = 0; ring < rings; ++ring) {
    std::vector<int> added;
    for (Eigen::Index f = 0; f < r.triangles.rows(); ++f) {
      if (in_set[static_cast<std::size_t>(f)]) continue;
      for (int k = 0; k < 3; ++k)
        if (vertex_in[static_cast<std::size_t>(r.triangles(f, k))]) {
          added.push_back(static_cast<int>(f));
          break;
        }
    }
    if (added.empty()) break;
    for (int f : added) {
      in_set[static_cast<std::size_t>(f)] = 1;
      std::array<int, 3> t{};
      for (int k = 0; k < 3; ++k) {
        const int v = r.triangles(f, k);
        vertex_in[static_cast<std::size_t>(v)] = 1;
        int& l = local[static_cast<std::size_t>(v)];
        if (l < 0) {
          l = static_cast<int>(part.vertices.size());
          const Eigen::Vector3d q = r.rest.row(v).transpose().cast<double>() -
                                    parts.normals[static_cast<std::size_t>(v)] *
                                        ((ring + 1) * sink * parts.edge[static_cast<std::size_t>(v)]);
          part.vertices.push_back({q.x(), q.y(), q.z()});
        }
        t[static_cast<std::size_t>(k)] = l;
      }
      part.triangles.push_back(t);
    }
  }
}

/// Step 2, branching parts (2013 §4.1 closes every joint of a part; docs/skinning.md "Decision:
/// closing a branching part's holes"): a part such as hips or chest has a hole at each child
/// limb; each gets an opening like a bone end, along the child's direction. The children are
/// the nearest descendants with vertices (through merged joints).
void add_child_openings(const JointParts& parts, int j, double extent, implicit::MeshPart& part) {
  const Rig& r = parts.rig;
  const std::vector<Eigen::Vector3d>& jp = parts.joint_positions;
  const std::vector<std::vector<int>>& children = parts.children;
  const int nv = static_cast<int>(r.rest.rows());
  std::vector<int> openings, stack(children[j].rbegin(), children[j].rend());
  while (!stack.empty()) {
    const int c = stack.back();
    stack.pop_back();
    if (parts.count[c] > 0)
      openings.push_back(c);
    else
      stack.insert(stack.end(), children[c].rbegin(), children[c].rend());
  }
  for (int c : openings) {
    Eigen::Vector3d cdir;
    if (children[c].size() == 1 && (jp[children[c][0]] - jp[c]).norm() > 1e-3 * extent) {
      cdir = jp[children[c][0]] - jp[c];
    } else {
      Eigen::Vector3d cc = Eigen::Vector3d::Zero();
      int m = 0;
      for (int v = 0; v < nv; ++v)
        if (parts.partition[v] == c) cc += Eigen::Vector3d(r.rest(v, 0), r.rest(v, 1), r.rest(v, 2)), ++m;
      cdir = cc / std::max(m, 1) - jp[c];
    }
    if (!(cdir.norm() > 1e-6 * extent)) continue;
    cdir.normalize();
    part.openings.push_back({{jp[c].x(), jp[c].y(), jp[c].z()}, {cdir.x(), cdir.y(), cdir.z()}});
  }
}

/// Step 2, a leaf or branching joint (or a refit): the segment runs from the joint along the
/// direction to its vertices' centroid (their principal axis, oriented away from the parent, for
/// a root or when the centroid lies on the joint), grown so that the culling planes cut no
/// vertex at an end without a joint. Sets `seg0`, `seg1` and the closure flags of `o`.
void segment_along_vertices(const JointParts& parts, int j, const implicit::MeshPart& part,
                            const Eigen::Vector3d& centroid, double extent, bool has_parent_part,
                            implicit::PartFitOptions& o, Eigen::Vector3d& seg0, Eigen::Vector3d& seg1) {
  const Rig& r = parts.rig;
  const std::vector<Eigen::Vector3d>& jp = parts.joint_positions;
  const Eigen::Vector3d start = jp[j];
  Eigen::Vector3d dir = centroid - start;
  if (dir.norm() < 0.1 * extent || !has_parent_part) {
    // Principal axis of the vertices, oriented away from the parent.
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const Vec3d& p : part.vertices) {
      const Eigen::Vector3d d = Eigen::Vector3d(p.x, p.y, p.z) - centroid;
      cov += d * d.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
    dir = es.eigenvectors().col(2);
    if (r.joints[j].parent >= 0 && dir.dot(start - jp[r.joints[j].parent]) < 0) dir = -dir;
  }
  dir.normalize();
  double lo = 0, hi = 0;
  for (const Vec3d& p : part.vertices) {
    const double u = (Eigen::Vector3d(p.x, p.y, p.z) - start).dot(dir);
    lo = std::min(lo, u);
    hi = std::max(hi, u);
  }
  // Grow the segment so that the culling planes (at cull_h of its length) cut no vertex at
  // an end without a joint.
  const double margin = 2.0 * o.cull_h / (1.0 - 2.0 * o.cull_h) * (hi - lo) + 1e-6 * extent;
  // Vertices well behind the joint (a root, or hips around their joint): no joint end.
  if (!has_parent_part || lo < -0.25 * (hi - lo)) o.close_start = false;
  if (!o.close_start) seg0 = start + dir * (lo - margin);
  seg1 = start + dir * (hi + margin);
  o.close_end = false;
}

/// Step 2 (2013 §4.1; docs/skinning.md "Pipeline", 2): the bone segment of joint `j`'s part,
/// which places the fit's culling planes and closure points. A joint with one child (not being
/// refitted) runs to the child; any other along its vertices (`segment_along_vertices`), with an
/// opening per child limb. Sets the part's segment and openings and the closure flags of `o`.
/// \return the segment `{start, end}`.
std::pair<Eigen::Vector3d, Eigen::Vector3d> place_bone_segment(const JointParts& parts, int j, bool refit,
                                                               implicit::MeshPart& part,
                                                               implicit::PartFitOptions& o) {
  const std::vector<Eigen::Vector3d>& jp = parts.joint_positions;
  const std::vector<std::vector<int>>& children = parts.children;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const Vec3d& p : part.vertices) centroid += Eigen::Vector3d(p.x, p.y, p.z);
  centroid /= double(part.vertices.size());
  const Eigen::Vector3d start = jp[j];
  const bool has_parent_part = parts.ancestor_with_vertices(j) >= 0;
  o.close_start = has_parent_part;
  double extent = 0;
  for (const Vec3d& p : part.vertices)
    extent = std::max(extent, (Eigen::Vector3d(p.x, p.y, p.z) - start).norm());
  Eigen::Vector3d seg0 = start, seg1;
  if (!refit && children[j].size() == 1 && (jp[children[j][0]] - start).norm() > 1e-3 * extent) {
    seg1 = jp[children[j][0]];
    o.close_end = parts.count[children[j][0]] > 0;
  } else {
    segment_along_vertices(parts, j, part, centroid, extent, has_parent_part, o, seg0, seg1);
    add_child_openings(parts, j, extent, part);
  }
  part.bone_start = {seg0.x(), seg0.y(), seg0.z()};
  part.bone_end = {seg1.x(), seg1.y(), seg1.z()};
  return {seg0, seg1};
}

/// Step 3 (docs/skinning.md "Pipeline", 3): the HRBF fit (libimplicit `fit_part`), retried.
/// Heat weights have no visibility term, so a partition may hold patches of a neighbouring
/// surface facing the bone (armpit, crotch); an HRBF through them has spurious far-field inside
/// regions. Triangles facing the bone are dropped, more strictly on each retry, and the last try
/// also drops the closure points. A fit whose error is above `max_error × r` (0: never;
/// SkinSetup::max_fit_error) counts as failed. Sets `b.fit` and `b.fitted`, or `b.error` (the
/// first try's).
void fit_with_retries(implicit::MeshPart& part, const implicit::PartFitOptions& o, double max_error,
                      const Eigen::Vector3d& seg0, const Eigen::Vector3d& seg1, BonePart& b) {
  const Eigen::Vector3d axis = seg1 - seg0;
  auto facing = [&](const std::array<int, 3>& t) {
    Eigen::Vector3d q[3];
    for (int k = 0; k < 3; ++k) {
      const Vec3d& v = part.vertices[static_cast<std::size_t>(t[static_cast<std::size_t>(k)])];
      q[k] = Eigen::Vector3d(v.x, v.y, v.z);
    }
    const Eigen::Vector3d c = (q[0] + q[1] + q[2]) / 3.0, n = (q[1] - q[0]).cross(q[2] - q[0]);
    const double u = std::clamp((c - seg0).dot(axis) / std::max(axis.squaredNorm(), 1e-300), 0.0, 1.0);
    const Eigen::Vector3d radial = c - (seg0 + u * axis);
    const double denom = n.norm() * radial.norm();
    return denom > 0 ? n.dot(radial) / denom : 1.0;
  };
  const std::vector<std::array<int, 3>> all = part.triangles;
  const double thresholds[] = {-0.2, 0.3, 0.3};
  for (int attempt = 0; attempt < 3 && !b.fitted; ++attempt) {
    part.triangles.clear();
    for (const auto& t : all)
      if (facing(t) > thresholds[attempt]) part.triangles.push_back(t);
    implicit::PartFitOptions oa = o;
    if (attempt == 2) {  // no closure at all
      oa.closure = implicit::PartFitOptions::Closure::joints;
      oa.close_start = oa.close_end = false;
      part.openings.clear();
    }
    try {
      b.fit = implicit::fit_part(part, oa);
      if (max_error > 0 && !(b.fit.error <= max_error * b.fit.r)) {  // a poor fit counts as failed
        if (attempt == 0)
          b.error = "poor fit: error " + format_number(b.fit.error) + " above " + format_number(max_error) +
                    " r = " + format_number(max_error * b.fit.r) + " (setup key fit.max_error)";
        continue;
      }
      b.fitted = true;
      b.error.clear();
      b.rule = attempt == 0 ? FitRule::hrbf : attempt == 1 ? FitRule::hrbf_strict : FitRule::hrbf_open;
    } catch (const InputError& e) {
      if (attempt == 0) b.error = e.what();
    }
  }
}

/// Steps 2 and 3 for joint `j`: its part's mesh, bone segment and fit into `b`.
/// \return false when the joint has no vertices or no triangles (`b.error` says which).
bool fit_joint(const JointParts& parts, const SkinSetup& setup, int j, bool refit, BonePart& b) {
  const Rig& r = parts.rig;
  b.fitted = false;
  b.error.clear();
  b.joint = j;
  b.vertices = parts.count[j];
  b.rule = parts.count[j] == 0 ? FitRule::no_vertices : FitRule::none;
  const std::string name = r.name + ": joint '" + r.joints[j].name + "'";
  if (parts.count[j] == 0) {
    b.error = "no vertices";
    return false;
  }
  implicit::MeshPart part = part_mesh(parts, j, name);
  if (part.triangles.empty()) {
    b.error = "no triangles";
    return false;
  }
  implicit::PartFitOptions o = setup.fit;
  const auto [seg0, seg1] = place_bone_segment(parts, j, refit, part, o);
  b.start = seg0;
  b.end = seg1;
  if (o.field == implicit::PartFitOptions::FieldKind::distance) {
    // The part's own closed surface (all its triangles: a patch of a neighbour's skin is skin the
    // field must follow too, and rings of the neighbours' across its border); where it cannot
    // give a field, the HRBF tries below. (Keeping a part's HRBF where it agrees with the part's
    // vertices better was measured and not kept: the HRBF reaches into the neighbours and the
    // composed field agrees less, docs/decisions/part-fields-from-the-mesh.md.)
    try {
      implicit::MeshPart overlapping = part;
      add_overlap_rings(parts, j, o.distance.overlap_rings, o.distance.overlap_sink, overlapping);
      b.fit = implicit::fit_part(overlapping, o);
      b.fitted = true;
      b.rule = FitRule::distance;
      return true;
    } catch (const InputError& e) {
      b.error = e.what();
      o.field = implicit::PartFitOptions::FieldKind::hrbf;
    }
  }
  fit_with_retries(part, o, setup.max_fit_error, seg0, seg1, b);
  return true;
}

/// Step 3 (docs/skinning.md, "No vertex without a field"): a capsule fitted to joint `j`'s part
/// (libimplicit `fit_capsule`), kept when `max_p95_over_r` is 0 or when its vertex → surface p95
/// is at most `max_p95_over_r` times its radius. \return whether `b` took it.
bool fit_fallback(const JointParts& parts, const SkinSetup& setup, int j, double max_p95_over_r,
                  BonePart& b) {
  const Rig& r = parts.rig;
  implicit::MeshPart part = part_mesh(parts, j, r.name + ": joint '" + r.joints[j].name + "'");
  if (part.vertices.empty())
    for (int v = 0; v < static_cast<int>(r.rest.rows()); ++v)
      if (parts.partition[v] == j) part.vertices.push_back({r.rest(v, 0), r.rest(v, 1), r.rest(v, 2)});
  implicit::PartFitOptions o = setup.fit;
  const auto [seg0, seg1] = place_bone_segment(parts, j, false, part, o);
  implicit::FittedPart fit;
  try {
    fit = implicit::fit_capsule(part, o);
  } catch (const InputError& e) {
    if (max_p95_over_r == 0) b.error += "; capsule fallback: " + std::string(e.what());
    return false;
  }
  if (max_p95_over_r > 0 &&
      !(implicit::fit_distances(*fit.field(), fit.local_to_world, part.vertices, part.triangles)
            .to_surface_p95 <= max_p95_over_r * fit.r))
    return false;
  b.fit = fit;
  b.start = seg0;
  b.end = seg1;
  b.fitted = true;
  b.rule = FitRule::capsule;
  return true;
}

/// A merge target whose refit failed (pass 1) keeps its first primitive, and the joints merged
/// into it get their vertices back (the fallback then covers them).
void undo_failed_merges(const std::vector<BonePart>& first, const std::vector<int>& first_partition,
                        std::vector<BonePart>& bones, std::vector<int>& partition) {
  const std::size_t nj = bones.size();
  std::vector<char> undo(nj, 0);
  for (std::size_t t = 0; t < nj; ++t) undo[t] = !bones[t].fitted && first[t].fitted;
  for (std::size_t j = 0; j < nj; ++j) {
    const int t = bones[j].merged_into;
    if (t >= 0 && undo[static_cast<std::size_t>(t)]) bones[j] = first[j];
    if (undo[j]) bones[j] = first[j];
  }
  for (std::size_t v = 0; v < partition.size(); ++v)
    if (undo[static_cast<std::size_t>(partition[v])]) partition[v] = first_partition[v];
}

}  // namespace

FittedRig::FittedRig(const Rig& rig, const SkinSetup& setup, const Progress& progress)
    : rig_(std::make_shared<const Rig>(rig)) {
  const Rig& r = *rig_;
  require(!r.weights.empty(), r.name + ": weights", "the rig has no skin weights",
          "compute heat weights first (isokit-skin does when a file has none)");
  const int nv = static_cast<int>(r.rest.rows());
  const int nj = static_cast<int>(r.joints.size());
  partition_ = clean_partition(dominant_joint(r.weights, nv), r.triangles, nv);
  const std::vector<Eigen::Vector3d> jp = rest_joint_positions(r);

  bones_.resize(static_cast<std::size_t>(nj));
  std::vector<char> refit(static_cast<std::size_t>(nj), 0);
  const auto t0 = std::chrono::steady_clock::now();
  // Pass 0 fits every joint; pass 1 merges the vertices of joints whose fit failed into a
  // fitted neighbour (the parent, else the child with most vertices) and refits those
  // neighbours with a segment covering all their vertices.
  // A target whose refit fails keeps its first primitive and gives the merged vertices back;
  // joints with vertices still without a primitive get a fitted capsule.
  std::vector<BonePart> first;
  std::vector<int> first_partition;
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) {
      // With SkinSetup::capsule_match, a failed part that a capsule matches (vertex -> surface p95
      // <= capsule_match r) keeps its own joint's motion; the others share a touching neighbour's
      // primitive.
      const JointParts parts = joint_parts(r, jp, partition_);
      for (int j = 0; j < nj; ++j)
        if (setup.capsule_match > 0 && !bones_[j].fitted && parts.count[j] > 0)
          fit_fallback(parts, setup, j, setup.capsule_match, bones_[j]);
      if (!merge_failed_fits(r, bones_, partition_, refit)) break;
    }
    const JointParts parts = joint_parts(r, jp, partition_);
    // The joints' fits are independent: one task each (the result does not depend on the order).
    int done = 0;
    std::mutex report;
    parallel_for(static_cast<std::size_t>(nj), 1, [&](std::size_t begin, std::size_t end) {
      for (std::size_t jj = begin; jj < end; ++jj) {
        const int j = static_cast<int>(jj);
        if (pass == 1 && !refit[jj]) continue;
        if (fit_joint(parts, setup, j, refit[jj] != 0, bones_[jj]) && progress) {
          const std::lock_guard<std::mutex> lock(report);
          progress("fit", ++done, nj);
        }
      }
    });
    if (pass == 0) first = bones_, first_partition = partition_;
  }
  undo_failed_merges(first, first_partition, bones_, partition_);
  const JointParts parts = joint_parts(r, jp, partition_);
  for (int j = 0; j < nj; ++j)
    if (!bones_[j].fitted && parts.count[j] > 0) fit_fallback(parts, setup, j, 0, bones_[j]);
  fit_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  require(
      fitted_count() > 0, r.name,
      "no joint could be fitted with a primitive", "check the mesh and weights (first error: " + [&] {
        for (const BonePart& b : bones_)
          if (!b.error.empty()) return b.error;
        return std::string("none");
      }() + ")");
}

AxisGuard::AxisGuard(const FittedRig& fitted, double offset) : fitted_(&fitted), offset_(offset) {
  const Rig& r = fitted.rig();
  const std::size_t nv = static_cast<std::size_t>(r.rest.rows());
  own_.assign(nv, -1);
  radial_.assign(nv, Eigen::Vector2d::Zero());
  for (std::size_t v = 0; v < nv; ++v) {
    const int j = fitted.partition()[v];
    if (j < 0 || !fitted.bones()[static_cast<std::size_t>(j)].fitted) continue;
    const implicit::FittedPart& part = fitted.bones()[static_cast<std::size_t>(j)].fit;
    const Vec3d p{r.rest(static_cast<Eigen::Index>(v), 0), r.rest(static_cast<Eigen::Index>(v), 1),
                  r.rest(static_cast<Eigen::Index>(v), 2)};
    const Vec3d l = part.local_to_world.apply_inverse(p);  // bone frame: +z along the bone
    const Eigen::Vector2d a(l.x, l.y);
    if (!(a.norm() >= 0.5 * part.r)) continue;
    own_[v] = j;
    radial_[v] = a;
  }
}

int AxisGuard::apply(const std::vector<Affine>& skin, track::Positions& positions) const {
  const auto& bones = fitted_->bones();
  std::vector<Affine> to_local(bones.size(), Affine::Identity());
  for (const BonePart& b : bones)
    if (b.fitted)
      to_local[static_cast<std::size_t>(b.joint)] =
          (rigid_part(skin[b.joint]) * to_affine(b.fit.local_to_world)).inverse();
  int moved = 0;
  for (Eigen::Index v = 0; v < positions.rows(); ++v) {
    const int j = own_[static_cast<std::size_t>(v)];
    if (j < 0) continue;
    const Eigen::Vector2d& a = radial_[static_cast<std::size_t>(v)];
    const Affine& L = to_local[static_cast<std::size_t>(j)];
    const Eigen::Vector3d l = L * positions.row(v).transpose().cast<double>();
    const Eigen::Vector2d b(l.x(), l.y());
    if (!(a.dot(b) < 0)) continue;  // on its side (or not finite: the tracker deals with it)
    const Eigen::Vector2d c = b - (a.dot(b) / a.squaredNorm()) * a + offset_ * a;
    positions.row(v) = (L.inverse() * Eigen::Vector3d(c.x(), c.y(), l.z())).transpose().cast<float>();
    ++moved;
  }
  return moved;
}

std::vector<PrimitiveCoverage> primitive_coverage(const FittedRig& fitted) {
  const Rig& r = fitted.rig();
  const std::vector<BonePart>& bones = fitted.bones();
  const int nj = static_cast<int>(r.joints.size());
  std::vector<int> up(static_cast<std::size_t>(nj));
  for (int j = 0; j < nj; ++j) up[j] = fitted.primitive_parent(j);
  const std::vector<int>& owner = fitted.partition();
  std::vector<PrimitiveCoverage> out;
  for (const BonePart& b : bones) {
    if (!b.fitted) continue;
    PrimitiveCoverage c;
    c.joint = b.joint;
    const implicit::FieldPtr field = b.fit.field();
    for (Eigen::Index v = 0; v < r.rest.rows(); ++v) {
      const int o = owner[static_cast<std::size_t>(v)];
      if (o == b.joint) {
        ++c.own;
        continue;
      }
      const Vec3d q = b.fit.local_to_world.apply_inverse(Vec3d{r.rest(v, 0), r.rest(v, 1), r.rest(v, 2)});
      if (!(field->eval(Vec3f{float(q.x), float(q.y), float(q.z)}).value > 0.5f)) continue;
      (up[b.joint] == o || up[o] == b.joint ? c.related : c.unrelated)++;
    }
    out.push_back(c);
  }
  return out;
}

const char* to_string(FitRule rule) {
  switch (rule) {
    case FitRule::no_vertices:
      return "no vertices";
    case FitRule::hrbf:
      return "hrbf";
    case FitRule::hrbf_strict:
      return "hrbf strict";
    case FitRule::hrbf_open:
      return "hrbf open";
    case FitRule::distance:
      return "distance";
    case FitRule::shared:
      return "shared";
    case FitRule::capsule:
      return "capsule";
    case FitRule::none:
      return "none";
  }
  return "?";
}

int FittedRig::primitive_parent(int joint) const {
  int p = rig_->joints[static_cast<std::size_t>(joint)].parent;
  while (p >= 0 && !bones_[static_cast<std::size_t>(p)].fitted)
    p = rig_->joints[static_cast<std::size_t>(p)].parent;
  return p;
}

int FittedRig::fitted_count() const {
  int n = 0;
  for (const BonePart& b : bones_) n += b.fitted ? 1 : 0;
  return n;
}

}  // namespace isokit::skinning
