// SPDX-License-Identifier: MIT
#include "io/isolated.h"

#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <new>

#include "isokit/core/error.h"

#if defined(__unix__) || defined(__APPLE__)
#include <poll.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#define ISOKIT_HAS_FORK 1
#else
#define ISOKIT_HAS_FORK 0
#endif

#if defined(__SANITIZE_ADDRESS__)
#define ISOKIT_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define ISOKIT_ASAN 1
#endif
#endif
#ifndef ISOKIT_ASAN
#define ISOKIT_ASAN 0
#endif

namespace isokit::skinning::io {

bool isolation_available() {
  return ISOKIT_HAS_FORK != 0;
}

#if ISOKIT_HAS_FORK

namespace {

// The child's first byte says how the work ended; the rest is its result or its message.
constexpr char kOk = 'O';
constexpr char kInputError = 'E';
constexpr char kOutOfMemory = 'M';
constexpr char kOtherError = 'X';

void write_all(int fd, const std::string& bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;  // the parent went away: nothing left to tell
    done += static_cast<std::size_t>(n);
  }
}

[[noreturn]] void child_main(const std::function<std::string()>& work, const IsolationLimits& limits,
                             int out_fd, int err_fd) {
  ::dup2(err_fd, STDERR_FILENO);
  // A crash of the work ends the child: the parent's crash handlers (a test framework's, a crash
  // reporter's) are not the child's business.
  for (const int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) std::signal(sig, SIG_DFL);
  if (limits.memory_mib > 0 && !ISOKIT_ASAN) {
    const rlim_t bytes = static_cast<rlim_t>(limits.memory_mib) << 20;
    const rlimit lim{bytes, bytes};
    ::setrlimit(RLIMIT_AS, &lim);
  }
  std::string message;
  try {
    message = kOk + work();
  } catch (const InputError& e) {
    message = kInputError + std::string(e.what());
  } catch (const std::bad_alloc&) {
    message = std::string(1, kOutOfMemory);
  } catch (const std::exception& e) {
    message = kOtherError + std::string(e.what());
  } catch (...) {
    message = kOtherError + std::string("unknown exception");
  }
  write_all(out_fd, message);
  ::close(out_fd);
  std::fflush(stderr);
  ::_exit(0);  // no atexit handlers, no static destructors of the parent's objects
}

/// Everything the child writes before it ends; false when `seconds` ran out first.
bool read_until_eof(int fd, double seconds, std::string& out) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  char buf[1 << 16];
  for (;;) {
    const double left = std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0) return false;
    pollfd p{fd, POLLIN, 0};
    const int r = ::poll(&p, 1, static_cast<int>(std::ceil(std::min(left, 3600.0) * 1000)));
    if (r < 0 && errno == EINTR) continue;
    if (r == 0) continue;  // re-check the deadline
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return true;
    out.append(buf, static_cast<std::size_t>(n));
  }
}

/// The last non-empty line the child wrote to stderr (e.g. assimp's assertion), or "".
std::string last_stderr_line(std::FILE* err) {
  std::fflush(err);
  std::string text;
  std::rewind(err);
  char buf[4096];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, err)) > 0) {
    text.append(buf, n);
    if (text.size() > (1u << 20)) text.erase(0, text.size() - (1u << 16));
  }
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' ')) text.pop_back();
  const std::size_t nl = text.find_last_of('\n');
  std::string line = nl == std::string::npos ? text : text.substr(nl + 1);
  if (line.size() > 300) line = line.substr(0, 300) + "...";
  return line;
}

std::string how_it_ended(int status, bool timed_out, const IsolationLimits& limits) {
  if (timed_out) return "took longer than " + format_number(limits.seconds) + " s and was stopped";
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    std::string s = "crashed (signal " + std::to_string(sig) + ", " + strsignal(sig) + ")";
    if (sig == SIGABRT) s = "aborted (an assertion inside the library)";
    if (sig == SIGKILL && limits.memory_mib > 0)
      s += " (memory limit " + std::to_string(limits.memory_mib) + " MiB?)";
    return s;
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) != 0)
    return "exited with status " + std::to_string(WEXITSTATUS(status));
  return "ended without a result";
}

}  // namespace

std::string run_isolated(const std::function<std::string()>& work, const IsolationLimits& limits,
                         const std::string& what, const std::string& fix) {
  require(limits.seconds > 0 && std::isfinite(limits.seconds), what + ": time limit",
          "must be > 0 s (got " + format_number(limits.seconds) + ")", "pass a positive number of seconds");
  int fds[2];
  require(::pipe(fds) == 0, what, std::string("cannot create a pipe: ") + std::strerror(errno),
          "check the process's file-descriptor limit");
  std::FILE* err = std::tmpfile();
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(fds[0]);
    child_main(work, limits, fds[1], err ? ::fileno(err) : STDERR_FILENO);
  }
  ::close(fds[1]);
  if (pid < 0) {
    ::close(fds[0]);
    if (err) std::fclose(err);
    throw InputError(what + ": cannot start a child process (" + std::strerror(errno) +
                     "); set LoadOptions::isolate_importer = false to read in this process");
  }
  std::string bytes;
  const bool finished = read_until_eof(fds[0], limits.seconds, bytes);
  ::close(fds[0]);
  if (!finished) ::kill(pid, SIGKILL);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  const std::string line = err ? last_stderr_line(err) : std::string();
  if (err) std::fclose(err);
  const bool clean = finished && WIFEXITED(status) && WEXITSTATUS(status) == 0 && !bytes.empty();
  if (!clean) {
    std::string msg = what + " " + how_it_ended(status, !finished, limits);
    if (!line.empty()) msg += " [" + line + "]";
    throw InputError(msg + "; " + fix);
  }
  const std::string body = bytes.substr(1);
  switch (bytes[0]) {
    case kOk:
      return body;
    case kInputError:
      throw InputError(body);
    case kOutOfMemory:
      throw InputError(what + " ran out of memory (limit " + std::to_string(limits.memory_mib) + " MiB); " +
                       fix);
    default:
      throw InputError(what + " failed: " + body + "; " + fix);
  }
}

#else

std::string run_isolated(const std::function<std::string()>& work, const IsolationLimits&, const std::string&,
                         const std::string&) {
  return work();
}

#endif

}  // namespace isokit::skinning::io
