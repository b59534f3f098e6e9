// SPDX-License-Identifier: MIT
/// \file
/// The logic behind `isokit-opdesigner` (testable without the CLI): slice plots (2014 Fig. 5a/6
/// style), the 2D composition of two capsule fields at a joint (Fig. 5b style), inspection.
#pragma once

#include <array>
#include <optional>
#include <string>

#include "isokit/operators/controller.h"
#include "isokit/operators/io.h"
#include "isokit/plot/figure.h"

namespace isokit::opdesigner {

/// Heat map of the operator at `d` (interpolated between slices) over (f1, f2) ∈ [0, 1]², iso-lines
/// every 0.1 (0.5 thick), the profile at `d` overlaid (boundary curves dashed white, contact
/// curves green). Saved by extension (.png/.svg/.pdf).
void plot_slice(const operators::StoredOperator& op, double d, const std::string& out_path);

struct ComposeOptions {
  double angle_deg{120};    ///< joint bend angle: 0 = straight bones, 180 = folded back
  std::optional<double> d;  ///< fixed operator parameter; unset = the spec's controller d(α)
  double radius{0.35};      ///< capsule radius (the 0.5 iso-distance)
  int samples{361};         ///< samples per axis of the field grid
  int pixels{560};
};

struct ComposeStats {
  double contact_length{0};  ///< length of the contact part of the 0.5 iso-line (both fields > 0.5)
  double max_d{0};           ///< largest d used
};

/// The composed field of `compose` without the figure (shared by `compose` and the design studio's
/// live preview): two capsules along the bones composed by `op`, d from `controller` (or the fixed
/// `options.d`). \throw isokit::InputError for an angle, d or sample count out of range.
struct ComposedField {
  plot::ScalarGrid grid;                ///< g over [-1.6, 1.6]², options.samples per axis
  std::vector<plot::Segment2> contact;  ///< contact part of the 0.5 iso-line (both fields > 0.5)
  std::array<plot::Point2, 3> bones{};  ///< bone 1 start, joint (origin), bone 2 end
  ComposeStats stats;
};
ComposedField compose_field(const operators::GridOperator& op, const operators::ControllerTable& controller,
                            const ComposeOptions& options);

/// Two 2D capsule fields f(r) = (1 - (r/R)²)³ (0.5 at r = radius) along bones meeting at the
/// origin, bone 1 from (-1.2, 0) to (0, 0), bone 2 from (0, 0) along angle `angle_deg`, composed
/// by the operator; figure with iso-lines and the contact part of the 0.5 line in green.
/// `out_path` empty: no figure, statistics only.
ComposeStats compose(const operators::StoredOperator& op, const ComposeOptions& options,
                     const std::string& out_path);

}  // namespace isokit::opdesigner
