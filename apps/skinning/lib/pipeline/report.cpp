// SPDX-License-Identifier: MIT
#include "isokit/skinning/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>

#include "isokit/core/atomic_file.h"
#include "isokit/core/error.h"

namespace isokit::skinning {

namespace {

using nlohmann::json;

json num(double v) {
  return std::isfinite(v) ? json(v) : json(nullptr);
}
json count(int v) {
  return v >= 0 ? json(v) : json(nullptr);
}

json metrics_to_json(const FrameMetrics& m) {
  return json{{"self_intersections", count(m.self_intersections)},
              {"self_intersections_new", count(m.self_intersections_new)},
              {"self_overlap", num(m.self_overlap)},
              {"self_overlap_new", num(m.self_overlap_new)},
              {"skin_overlap", num(m.skin_overlap)},
              {"skin_overlap_new", num(m.skin_overlap_new)},
              {"folded_triangles", count(m.folded_triangles)},
              {"folded_new", count(m.folded_new)},
              {"degenerate_faces", count(m.degenerate_faces)},
              {"inverted_triangles", count(m.inverted_triangles)},
              {"new_inverted_triangles", count(m.new_inverted_triangles)},
              {"iso_residual_max", num(m.iso_residual_max)},
              {"iso_residual_mean", num(m.iso_residual_mean)},
              {"contact_vertices", count(m.contact_vertices)},
              {"edge_distortion_mean", num(m.edge_distortion_mean)},
              {"edge_distortion_max", num(m.edge_distortion_max)},
              {"volume_ratio", num(m.volume_ratio)},
              {"max_displacement", num(m.max_displacement)}};
}

/// True for the methods that call a tracker or a projector.
bool has_tracker(Method m) {
  return m == Method::kImplicit2013 || m == Method::kTracking2014;
}

/// The mesh's connected components and whether each is closed (volumes cover the closed ones).
json components_json(const MeshClosure& c) {
  json list = json::array();
  for (const MeshComponent& k : c.components)
    list.push_back(json{{"triangles", k.triangles},
                        {"closed", k.closed()},
                        {"border_edges", k.border_edges},
                        {"non_manifold_edges", k.non_manifold_edges},
                        {"misoriented_edges", k.misoriented_edges}});
  return list;
}

/// Tracker calls and calls at the cap of a bake: totals over the frames and the largest per frame.
struct CallCounts {
  long long calls{0}, capped{0};
  int max_calls{0}, max_capped{0};
};

CallCounts call_counts(const BakeResult& r) {
  CallCounts c;
  for (const FrameStats& s : r.stats) {
    c.calls += s.tracker_calls;
    c.capped += s.capped_calls;
    c.max_calls = std::max(c.max_calls, s.tracker_calls);
    c.max_capped = std::max(c.max_capped, s.capped_calls);
  }
  return c;
}

/// The call counts of a method (totals) and of its worst frame (null without a tracker).
void add_call_counts(const BakeResult& r, json& method, json& worst) {
  const bool tracked = has_tracker(r.method);
  const CallCounts c = call_counts(r);
  method["tracker_calls"] = tracked ? json(c.calls) : json(nullptr);
  method["capped_calls"] = tracked ? json(c.capped) : json(nullptr);
  method["capped_share"] = tracked && c.calls > 0 ? json(double(c.capped) / double(c.calls)) : json(nullptr);
  worst["tracker_calls"] = tracked ? json(c.max_calls) : json(nullptr);
  worst["capped_calls"] = tracked ? json(c.max_capped) : json(nullptr);
}

/// "capped/calls" over the animation for the methods with a tracker, else "-".
std::string calls_at_cap(const BakeResult& r) {
  if (!has_tracker(r.method)) return "-";
  const CallCounts c = call_counts(r);
  return std::to_string(c.capped) + "/" + std::to_string(c.calls);
}

double dqs_ms(const std::vector<BakeResult>& results) {
  for (const BakeResult& r : results)
    if (r.method == Method::kDqs) return r.mean_ms;
  return std::nan("");
}

}  // namespace

std::string metrics_json(const Rig& rig, const std::vector<BakeResult>& results, const ReportContext& c) {
  json j;
  j["rig"] = rig.name;
  j["vertices"] = rig.rest.rows();
  j["triangles"] = rig.triangles.rows();
  j["joints"] = rig.joints.size();
  j["animation"] = c.animation;
  j["fps"] = c.fps;
  j["threads"] = c.threads;
  j["fit_seconds"] = c.fit_seconds;
  if (c.agreement) {
    const RestAgreement& a = *c.agreement;
    json ra;
    ra["vertices"] = a.composed.points;
    ra["angle_p50_deg"] = num(a.composed.angle_p50);
    ra["angle_p95_deg"] = num(a.composed.angle_p95);
    ra["angle_max_deg"] = num(a.composed.angle_max);
    ra["over_60_deg"] = a.composed.over_limit;
    ra["distance_p50"] = num(a.composed.distance_p50);
    ra["distance_p95"] = num(a.composed.distance_p95);
    ra["distance_max"] = num(a.composed.distance_max);
    ra["hidden_vertices"] = a.hidden_vertices;
    ra["visible_over_60_deg"] = a.visible.over_limit;
    ra["visible_angle_p95_deg"] = num(a.visible.angle_p95);
    ra["triangles"] = a.triangles;
    ra["inverted_triangles"] = a.inverted_triangles;
    ra["open_panels"] = a.open_panels;
    ra["panel_vertices"] = a.panel_vertices;
    ra["unrelated_inside"] = a.unrelated_inside;
    j["rest_agreement"] = ra;
  }
  const MeshClosure closure = mesh_closure(rig.triangles, rig.rest.rows());
  j["closed"] = closure.closed();
  j["components"] = components_json(closure);
  const double dqs = dqs_ms(results);
  json methods = json::object();
  for (const BakeResult& r : results) {
    json m;
    m["mean_ms"] = r.mean_ms;
    m["ratio_to_dqs"] = num(r.mean_ms / dqs);
    m["vertex_iterations_per_second"] = r.vertex_iterations_per_second;
    m["setup_seconds"] = r.setup_seconds;
    m["rest_recovery"] = r.rest_recovery >= 0 ? json(r.rest_recovery) : json(nullptr);
    json worst = metrics_to_json(r.worst);
    add_call_counts(r, m, worst);
    m["worst"] = worst;
    json frames = json::array();
    for (std::size_t f = 0; f < r.stats.size(); ++f) {
      const FrameStats& s = r.stats[f];
      json fr = metrics_to_json(s.metrics);
      fr["frame"] = f;
      fr["ms"] = s.ms;
      fr["substeps"] = s.substeps;
      fr["iterations"] = s.iterations;
      fr["lost_vertices"] = s.lost_vertices;
      fr["tracker_calls"] = has_tracker(r.method) ? json(s.tracker_calls) : json(nullptr);
      fr["capped_calls"] = has_tracker(r.method) ? json(s.capped_calls) : json(nullptr);
      fr["call_iterations"] = has_tracker(r.method) ? json(s.call_iterations) : json(nullptr);
      frames.push_back(fr);
    }
    m["frames"] = frames;
    methods[to_string(r.method)] = m;
  }
  j["methods"] = methods;
  return j.dump(2) + "\n";
}

std::string comparison_table(const std::vector<BakeResult>& results) {
  const double dqs = dqs_ms(results);
  auto fmt = [](const char* f, double v) {
    if (!std::isfinite(v)) return std::string("-");
    char b[64];
    std::snprintf(b, sizeof b, f, v);
    return std::string(b);
  };
  std::ostringstream o;
  auto counts = [](int all, int fresh) {
    return (all >= 0 ? std::to_string(all) : "-") + " (" + (fresh >= 0 ? std::to_string(fresh) : "-") + ")";
  };
  o << "| method | new overlap (% of volume) | skin overlap (%) | self-intersections | folded (new) "
       "| inverted triangles (new) | iso residual max | edge distortion mean / max | volume ratio | rest "
       "recovery "
       "| calls at cap | ms/frame | × dqs |\n";
  o << "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const BakeResult& r : results) {
    const FrameMetrics& w = r.worst;
    o << "| " << to_string(r.method) << " | " << fmt("%.4f", 100 * w.self_overlap_new) << " | "
      << fmt("%.4f", 100 * w.skin_overlap_new) << " | "
      << (w.self_intersections >= 0 ? std::to_string(w.self_intersections) : "-") << " | "
      << counts(w.folded_triangles, w.folded_new) << " | "
      << counts(w.inverted_triangles, w.new_inverted_triangles) << " | " << fmt("%.1e", w.iso_residual_max)
      << " | " << fmt("%.3f", w.edge_distortion_mean) << " / " << fmt("%.3f", w.edge_distortion_max) << " | "
      << fmt("%.4f", w.volume_ratio) << " | " << (r.rest_recovery >= 0 ? fmt("%.1e", r.rest_recovery) : "-")
      << " | " << calls_at_cap(r) << " | " << fmt("%.2f", r.mean_ms) << " | " << fmt("%.1f", r.mean_ms / dqs)
      << " |\n";
  }
  return o.str();
}

void write_text_file(const std::string& path, const std::string& text) {
  namespace fs = std::filesystem;
  const fs::path p(path);
  if (p.has_parent_path()) {
    std::error_code ec;
    fs::create_directories(p.parent_path(), ec);
  }
  write_text_file_atomically(path, text);
}

}  // namespace isokit::skinning
