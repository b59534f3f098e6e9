// SPDX-License-Identifier: MIT
#include "eval_rows.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <utility>
#include <vector>

namespace isokit::eval {

namespace {

using nlohmann::json;

/// Largest value of `key` over the frames; null when a frame lacks it (or has null).
json worst_over(const json& frames, const char* key) {
  json out = nullptr;
  for (const json& f : frames) {
    if (!f.contains(key) || !f[key].is_number()) return nullptr;
    if (out.is_null() || f[key].get<double>() > out.get<double>()) out = f[key];
  }
  return out;
}

/// Smallest and largest value of `key` over the frames that have it (nulls skipped).
std::pair<json, json> range_over(const json& frames, const char* key) {
  json lo = nullptr, hi = nullptr;
  for (const json& f : frames) {
    if (!f.contains(key) || !f[key].is_number()) continue;
    const double v = f[key].get<double>();
    if (lo.is_null() || v < lo.get<double>()) lo = v;
    if (hi.is_null() || v > hi.get<double>()) hi = v;
  }
  return {lo, hi};
}

/// Sum of `key` (or `alt`) over the frames; null when a frame lacks both.
json sum_over(const json& frames, const char* key, const char* alt) {
  double sum = 0;
  for (const json& f : frames) {
    const char* k = f.contains(key) ? key : alt;
    if (!f.contains(k) || !f[k].is_number()) return nullptr;
    sum += f[k].get<double>();
  }
  return frames.empty() ? json(nullptr) : json(sum);
}

/// `closed` of the metrics JSON: a bool, or a list of components (all closed); else `fallback`.
bool closed_of(const json& metrics, bool fallback) {
  if (!metrics.contains("closed")) return fallback;
  const json& c = metrics["closed"];
  if (c.is_boolean()) return c.get<bool>();
  if (!c.is_array()) return fallback;
  return std::all_of(c.begin(), c.end(), [](const json& e) {
    if (e.is_boolean()) return e.get<bool>();
    return e.is_object() && e.value("closed", false);
  });
}

// The median and the 95th percentile (nearest rank) of the iterations per tracker call over every
// frame's `call_iterations`; null when no frame has them.
std::pair<json, json> call_iteration_quantiles(const json& frames) {
  std::vector<double> it;
  for (const json& f : frames)
    if (f.contains("call_iterations") && f["call_iterations"].is_array())
      for (const json& v : f["call_iterations"])
        if (v.is_number()) it.push_back(v.get<double>());
  if (it.empty()) return {json(nullptr), json(nullptr)};
  std::sort(it.begin(), it.end());
  const std::size_t n = it.size();
  const double median = n % 2 ? it[n / 2] : 0.5 * (it[n / 2 - 1] + it[n / 2]);
  const std::size_t rank = static_cast<std::size_t>(std::ceil(0.95 * double(n)));
  return {json(median), json(it[std::max<std::size_t>(rank, 1) - 1])};
}

Row method_row(const json& m, bool closed) {
  const json& frames = m["frames"];
  const json& worst = m["worst"];
  Row r;
  r["frames"] = frames.size();
  r["self_overlap_new"] = worst_over(frames, "self_overlap_new");
  r["skin_overlap_new"] = worst_over(frames, "skin_overlap_new");
  r["folded_new"] = worst_over(frames, "folded_new");
  r["self_intersections_new"] = worst_over(frames, "self_intersections_new");
  r["self_intersections"] = worst.value("self_intersections", json(nullptr));
  r["new_inverted_triangles"] = worst.value("new_inverted_triangles", json(nullptr));
  r["edge_distortion_max"] = worst.value("edge_distortion_max", json(nullptr));
  r["edge_distortion_mean"] = worst.value("edge_distortion_mean", json(nullptr));
  const auto volume = range_over(frames, "volume_ratio");
  r["volume_ratio_min"] = closed ? volume.first : json(nullptr);
  r["volume_ratio_max"] = closed ? volume.second : json(nullptr);
  r["iso_residual_max"] = worst.value("iso_residual_max", json(nullptr));
  r["rest_recovery"] = m.value("rest_recovery", json(nullptr));
  r["mean_ms"] = m.value("mean_ms", json(nullptr));
  r["worst_ms"] = worst_over(frames, "ms");
  r["tracker_calls"] = sum_over(frames, "tracker_calls", "tracker_calls");
  r["capped_calls"] = sum_over(frames, "capped_calls", "calls_at_cap");
  const bool calls =
      r["tracker_calls"].is_number() && r["capped_calls"].is_number() && r["tracker_calls"].get<double>() > 0;
  r["capped_share"] =
      calls ? json(r["capped_calls"].get<double>() / r["tracker_calls"].get<double>()) : json(nullptr);
  const auto [median, p95] = call_iteration_quantiles(frames);
  r["iterations_median"] = median;
  r["iterations_p95"] = p95;
  return r;
}

std::string cell(const json& v, const char* format) {
  if (!v.is_number()) return "—";
  char b[64];
  std::snprintf(b, sizeof b, format, v.get<double>());
  return b;
}

/// A share as a percentage (null stays null).
json percent(const json& v) {
  return v.is_number() ? json(100 * v.get<double>()) : json(nullptr);
}

std::string count_cell(const json& v) {
  return v.is_number() ? std::to_string(std::llround(v.get<double>())) : "—";
}

}  // namespace

std::vector<Row> rows_from_metrics(const json& metrics, const std::string& rig, const std::string& animation,
                                   bool mesh_closed) {
  const bool closed = closed_of(metrics, mesh_closed);
  std::vector<Row> rows;
  for (const auto& [name, m] : metrics.at("methods").items()) {
    Row r = method_row(m, closed);
    r["rig"] = rig;
    r["animation"] = animation;
    r["method"] = name;
    r["closed"] = closed;
    r["closed_from"] = metrics.contains("closed") ? "metrics" : "eval";
    r["error"] = nullptr;
    rows.push_back(std::move(r));
  }
  return rows;
}

Row error_row(const std::string& rig, const std::string& animation, const std::string& method,
              const std::string& error) {
  std::string line = error;
  for (char& c : line)
    if (c == '|' || c == '\n') c = c == '|' ? '/' : ' ';
  return Row{{"rig", rig}, {"animation", animation}, {"method", method}, {"error", line}};
}

std::string markdown_table(const std::vector<Row>& rows) {
  std::ostringstream o;
  o << "| rig | animation | method | frames | overlap new (%) | skin overlap new (%) | self-int. new (all) "
       "| folded new | new inverted | edge dist. max / mean | volume min / max | iso residual | rest "
       "recovery "
       "| ms mean / worst | calls at cap | iterations per call median / p95 |\n"
       "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const Row& r : rows) {
    o << "| " << r.value("rig", "") << " | " << r.value("animation", "") << " | " << r.value("method", "")
      << " | ";
    if (r.contains("error") && r["error"].is_string()) {
      o << "**failed:** " << r["error"].get<std::string>() << " | | | | | | | | | | | | |\n";
      continue;
    }
    o << r["frames"].get<int>() << " | " << cell(percent(r["self_overlap_new"]), "%.4f") << " | "
      << cell(percent(r["skin_overlap_new"]), "%.4f") << " | " << count_cell(r["self_intersections_new"])
      << " (" << count_cell(r["self_intersections"]) << ") | " << count_cell(r["folded_new"]) << " | "
      << count_cell(r["new_inverted_triangles"]) << " | " << cell(r["edge_distortion_max"], "%.2f") << " / "
      << cell(r["edge_distortion_mean"], "%.3f") << " | "
      << (r["closed"].get<bool>()
              ? cell(r["volume_ratio_min"], "%.3f") + " / " + cell(r["volume_ratio_max"], "%.3f")
              : std::string("(open)"))
      << " | " << cell(r["iso_residual_max"], "%.1e") << " | " << cell(r["rest_recovery"], "%.1e") << " | "
      << cell(r["mean_ms"], "%.1f") << " / " << cell(r["worst_ms"], "%.1f") << " | "
      << cell(percent(r["capped_share"]), "%.0f %%") << " | " << cell(r["iterations_median"], "%.0f") << " / "
      << cell(r["iterations_p95"], "%.0f") << " |\n";
  }
  return o.str();
}

}  // namespace isokit::eval
