// SPDX-License-Identifier: MIT
/// \file
/// Runs a piece of work in a child process (POSIX fork), so that a third-party library that
/// aborts, crashes, hangs or allocates without bound on a malformed file (assimp 5.2: the known
/// limits of docs/fuzzing.md) ends the child, not the caller. The work returns its result as
/// bytes; an `InputError` it throws is passed back and rethrown with its message; a child that
/// dies is reported as an `InputError` naming what it did, how it ended and the last line it
/// wrote to stderr.
#pragma once

#include <cstddef>
#include <functional>
#include <string>

namespace isokit::skinning::io {

struct IsolationLimits {
  /// Wall-clock limit of the child, in seconds (> 0); it is killed after that.
  double seconds{600};
  /// Address-space limit of the child in MiB (RLIMIT_AS); 0 = none. Not applied in builds with
  /// AddressSanitizer (its shadow memory needs the whole address space).
  std::size_t memory_mib{0};
};

/// True where work can run in a child process (POSIX); elsewhere `run_isolated` runs it in the
/// calling process.
bool isolation_available();

/// Runs `work` in a child process and returns its bytes. `what` names the work in errors
/// ("assimp reading FILE"); `fix` is appended to crash messages.
/// \throw isokit::InputError: the work's own InputError (same message), or the child's end
/// (signal, exit status, time or memory limit) with the last stderr line.
std::string run_isolated(const std::function<std::string()>& work, const IsolationLimits& limits,
                         const std::string& what, const std::string& fix);

}  // namespace isokit::skinning::io
