// SPDX-License-Identifier: MIT
/// \file
/// What a command is doing, for its error messages: a command marks each stage of its work with a
/// `Stage` ("reading rigs/x.glb", "fitting the part fields"), and when an exception leaves a stage
/// the innermost one is remembered, so that an error caught at the top — a `std::bad_alloc` above
/// all, which carries no message of its own — can still say what was being done.
#pragma once

#include <string>

namespace isokit {

class Stage {
 public:
  /// Enters stage `what` (a phrase that follows "while": "reading rigs/x.glb").
  explicit Stage(std::string what);
  /// Leaves it; when an exception is leaving it, records it as `failed()` unless an inner stage
  /// already was.
  ~Stage();
  Stage(const Stage&) = delete;
  Stage& operator=(const Stage&) = delete;

  /// The innermost stage an exception left on this thread since the last `clear_failed`; empty if
  /// none.
  static std::string failed();
  static void clear_failed();

 private:
  std::string what_;
  int uncaught_;
};

/// "out of memory while <failed stage>" (or "out of memory" when no stage was left by the
/// exception): the one-line message of a `std::bad_alloc` caught at a command's top.
std::string out_of_memory_message();

}  // namespace isokit
