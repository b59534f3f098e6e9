// SPDX-License-Identifier: MIT
/// \file
/// The exception isokit throws for bad user input. Messages name the item that is wrong, the
/// value seen, and what to do instead.
#pragma once

#include <stdexcept>
#include <string>

namespace isokit {

/// Thrown for invalid input (parameters, files, meshes). Library code never aborts the process.
class InputError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Throws `InputError("<what>: <why> (got <value>); <fix>")` unless `ok`.
void require(bool ok, const std::string& what, const std::string& why, const std::string& fix);

/// `std::to_string` for floats with full precision, also for NaN and infinities.
std::string format_number(double v);

}  // namespace isokit
