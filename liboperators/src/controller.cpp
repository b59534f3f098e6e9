// SPDX-License-Identifier: MIT
#include "isokit/operators/controller.h"

#include <cmath>

#include "isokit/core/error.h"
#include "isokit/core/math.h"

namespace isokit::operators {
Controller::Controller(std::vector<ControllerKnot> knots, std::string name)
    : knots_(std::move(knots)), name_(std::move(name)) {
  const std::string what = "controller '" + name_ + "'";
  require(knots_.size() >= 2, what + " knots", "a controller needs at least two knots",
          "give knots at alpha = 0 and alpha = pi");
  for (std::size_t i = 0; i < knots_.size(); ++i) {
    const auto& k = knots_[i];
    const std::string item = what + " knots[" + std::to_string(i) + "]";
    require(std::isfinite(k.alpha) && std::isfinite(k.d), item, "not finite", "use finite numbers");
    require(k.d >= 0 && k.d <= 1, item, "d = " + format_number(k.d) + " is outside [0, 1]",
            "controller values are operator parameters in [0, 1]");
    if (i > 0)
      require(k.alpha > knots_[i - 1].alpha, item, "angles must increase strictly",
              "sort the knots by angle");
  }
  require(std::abs(knots_.front().alpha) < 1e-9 && std::abs(knots_.back().alpha - kPi) < 1e-6,
          what + " knots", "the first knot must be at alpha = 0 and the last at pi (radians)",
          "add end knots");
}

Controller Controller::preset(const std::string& name) {
  if (name == "contact") return Controller({{0, 0}, {kPi / 2, 0}, {kPi, 1}}, name);
  if (name == "bulge") return Controller({{0, 0}, {kPi, 1}}, name);
  if (name == "blend2013") return Controller({{0, 0}, {kPi / 4, 1}, {kPi / 2, 0}, {kPi, 0}}, name);
  if (name == "bulge2013") return Controller({{0, 0}, {kPi / 2, 1}, {kPi, 1}}, name);
  if (name == "constant0") return Controller({{0, 0}, {kPi, 0}}, name);
  if (name == "constant1") return Controller({{0, 1}, {kPi, 1}}, name);
  std::string list;
  for (const auto& n : preset_names()) list += (list.empty() ? "" : ", ") + n;
  throw InputError("controller preset '" + name + "': unknown; use one of " + list);
}

std::vector<std::string> Controller::preset_names() {
  return {"contact", "bulge", "blend2013", "bulge2013", "constant0", "constant1"};
}

double Controller::eval(double alpha) const {
  if (!(alpha > knots_.front().alpha)) return knots_.front().d;
  if (alpha >= knots_.back().alpha) return knots_.back().d;
  std::size_t i = 1;
  while (knots_[i].alpha < alpha) ++i;
  const auto& a = knots_[i - 1];
  const auto& b = knots_[i];
  const double t = (alpha - a.alpha) / (b.alpha - a.alpha);
  const double s = t * t * (3 - 2 * t);  // smoothstep: C1 with zero slope at the knots
  return a.d + (b.d - a.d) * s;
}

ControllerTable Controller::table() const {
  ControllerTable t;
  for (int i = 0; i < ControllerTable::kSize; ++i)
    t.values[i] = static_cast<float>(eval(kPi * i / (ControllerTable::kSize - 1)));
  return t;
}

}  // namespace isokit::operators
