// SPDX-License-Identifier: MIT
/// \file
/// Controllers `d(α)`: the operator parameter `d ∈ [0, 1]` as a function of the angle
/// `α ∈ [0, π]` between the operands' gradients (2014 §4.1, Fig. 4; 2013 §4.2, Fig. 7).
/// A controller is a piecewise curve through knots `(α_i, d_i)`, joined by smoothstep
/// segments (C¹: zero slope at every knot), sampled into a fixed-size table. The table is plain
/// data (`ControllerTable`) so CUDA kernels can evaluate it with the same inline code.
#pragma once

#include <string>
#include <vector>

#include "isokit/core/hostdev.h"
#include "isokit/core/math.h"

namespace isokit::operators {

/// The sampled controller: `values[i] = d(π i / (kSize - 1))`, evaluated by linear interpolation.
struct ControllerTable {
  static constexpr int kSize = 256;
  float values[kSize]{};

  /// `d(α)`; `α` is clamped to [0, π].
  ISOKIT_HOSTDEV float operator()(float alpha) const {
    const float t = alpha * (float(kSize - 1) / kPiF);
    if (!(t > 0.f)) return values[0];  // also catches NaN
    if (t >= float(kSize - 1)) return values[kSize - 1];
    const int i = int(t);
    const float w = t - float(i);
    return values[i] + w * (values[i + 1] - values[i]);
  }
};

/// A knot of a controller curve: angle in radians, value in [0, 1].
struct ControllerKnot {
  double alpha{0};
  double d{0};
};

/// A controller curve. Knots are sorted by angle, the first at 0 and the last at π; values in
/// [0, 1]. \throw isokit::InputError on invalid knots (the message names the knot).
class Controller {
 public:
  explicit Controller(std::vector<ControllerKnot> knots, std::string name = "custom");

  /// Presets (angles in radians):
  /// - "contact": `d_c` of 2014 Fig. 4(a): 0 on [0, π/2] (clean union while the joint bends
  ///   like an elbow before contact), smoothstep up to 1 at π (full contact of disjoint parts).
  /// - "bulge": `d_b` of 2014 Fig. 4(b): rises from 0 at α = 0 ("the bulge starts at low bending
  ///   angles") to 1 at π. The paper gives only the plot; why this reading:
  ///   docs/decisions/the-bulge-controller.md.
  /// - "blend2013": 2013 Fig. 7(a) for the gradient-based blend, as the blend amount `d`
  ///   (θ = θ_u (1 - d) + θ_b d): union (0) at α = 0, full blend (1) at π/4, union again from
  ///   π/2 to π.
  /// - "bulge2013": 2013 Fig. 7(b): 0 at α = 0 rising to 1 at π/2, constant to π.
  /// - "constant0", "constant1": d ≡ 0 / d ≡ 1.
  /// \throw isokit::InputError for an unknown name (the message lists the presets).
  static Controller preset(const std::string& name);
  static std::vector<std::string> preset_names();

  /// Exact curve value (smoothstep between knots).
  double eval(double alpha) const;
  ControllerTable table() const;
  const std::vector<ControllerKnot>& knots() const { return knots_; }
  const std::string& name() const { return name_; }

 private:
  std::vector<ControllerKnot> knots_;
  std::string name_;
};

}  // namespace isokit::operators
