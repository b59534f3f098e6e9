// SPDX-License-Identifier: MIT
#include "isokit/core/error.h"

#include <cmath>
#include <cstdio>

namespace isokit {

void require(bool ok, const std::string& what, const std::string& why, const std::string& fix) {
  if (ok) return;
  throw InputError(what + ": " + why + "; " + fix);
}

std::string format_number(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

}  // namespace isokit
