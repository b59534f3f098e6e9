// SPDX-License-Identifier: MIT
#include "isokit/core/stage.h"

#include <exception>
#include <utility>

namespace isokit {

namespace {

thread_local std::string failed_stage;

}  // namespace

Stage::Stage(std::string what) : what_(std::move(what)), uncaught_(std::uncaught_exceptions()) {}

Stage::~Stage() {
  if (std::uncaught_exceptions() <= uncaught_ || !failed_stage.empty()) return;
  try {
    failed_stage = what_;
  } catch (...) {  // out of memory even for the name: the message says less, nothing terminates
  }
}

std::string Stage::failed() {
  return failed_stage;
}

void Stage::clear_failed() {
  failed_stage.clear();
}

std::string out_of_memory_message() {
  const std::string stage = Stage::failed();
  return "out of memory" + (stage.empty() ? std::string() : " while " + stage) +
         "; the input is larger than this machine's memory allows (or corrupt): give a smaller input, or "
         "run it on a machine with more memory";
}

}  // namespace isokit
