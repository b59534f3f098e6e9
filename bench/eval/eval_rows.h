// SPDX-License-Identifier: MIT
/// \file
/// Rows of the real-rig evaluation: one per (rig, animation, method), read from the `--metrics`
/// JSON of a bake (report.h), so that metrics added to that JSON (`closed`,
/// `self_intersections_new`, per-frame `tracker_calls` / `capped_calls`) are used when present and
/// left `null` ("—" in the table) when absent.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace isokit::eval {

using Row = nlohmann::json;

/// The rows of one bake: `metrics` is the parsed metrics JSON of every method; `mesh_closed` is
/// the evaluation's own closedness test, used when the JSON has no `closed`.
std::vector<Row> rows_from_metrics(const nlohmann::json& metrics, const std::string& rig,
                                   const std::string& animation, bool mesh_closed);

/// A row saying that a rig, an animation or a method failed (`error`: the one-line message).
Row error_row(const std::string& rig, const std::string& animation, const std::string& method,
              const std::string& error);

/// The Markdown table of `rows` (one line each; "—" for a value not measured).
std::string markdown_table(const std::vector<Row>& rows);

}  // namespace isokit::eval
