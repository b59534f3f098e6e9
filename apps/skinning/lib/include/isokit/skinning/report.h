// SPDX-License-Identifier: MIT
/// \file
/// Reports of bakes: the `--metrics` JSON (QUALITY.md metrics per frame, worst values, timings)
/// and the plain-text comparison table `isokit-skin demo` prints.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "isokit/skinning/fit_quality.h"
#include "isokit/skinning/pipeline.h"

namespace isokit::skinning {

struct ReportContext {
  std::string animation;  ///< e.g. "--bend LeftForeArm:x:150 (31 frames)"
  double fps{30};
  int threads{0};         ///< 0: unknown
  double fit_seconds{0};  ///< preprocessing: fit of all primitives
  /// The composed field against the rest mesh (fit_quality.h); written as `rest_agreement`.
  std::optional<RestAgreement> agreement;
};

/// The metrics JSON: `{rig, vertices, triangles, joints, animation, fps, threads, fit_seconds,
/// rest_agreement, closed, components, methods: {name: {mean_ms, ratio_to_dqs, vertex_iterations_per_second,
/// setup_seconds, rest_recovery, tracker_calls, capped_calls, capped_share, worst, frames: [...]}}}`. Values
/// not computed are `null` (docs/skinning-metrics.md, "The metrics JSON").
std::string metrics_json(const Rig& rig, const std::vector<BakeResult>& results,
                         const ReportContext& context);

/// One line per method: self-intersections, inverted triangles, iso residual, edge distortion,
/// volume ratio, rest recovery (worst values over the animation), calls at cap (tracker calls
/// stopped at the iteration cap / all calls), ms/frame, ratio to DQS.
std::string comparison_table(const std::vector<BakeResult>& results);

/// Writes `text` to `path` atomically (isokit::write_text_file_atomically), creating its folder
/// first when missing.
/// \throw InputError naming the path when it cannot be written.
void write_text_file(const std::string& path, const std::string& text);

}  // namespace isokit::skinning
