// SPDX-License-Identifier: MIT
/// \file
/// The studio's background thread: solves a list of slices of a spec with its own generator
/// (`solve_edited` is not thread-safe) and hands the results over through a mutex-guarded
/// outbox. A new job replaces the current one after the slice in progress.
#pragma once

#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "isokit/operators/biharmonic.h"

namespace isokit::studio::detail {

class BackgroundSolver {
 public:
  /// A solved slice, for the spec of job `generation`.
  struct Result {
    long generation{0};
    int slice{0};
    std::vector<float> values;
  };

  /// Starts the thread; its generator is built there from `base` (the spec the model opened).
  BackgroundSolver(operators::OperatorSpec base, operators::BiharmonicOptions options);
  /// Stops after the slice in progress and joins.
  ~BackgroundSolver();
  BackgroundSolver(const BackgroundSolver&) = delete;
  BackgroundSolver& operator=(const BackgroundSolver&) = delete;

  /// Replaces the job: solve `slices` (in this order) of `spec`, tagging results `generation`.
  void post(long generation, const operators::OperatorSpec& spec, std::vector<int> slices);
  /// Rebuilds the generator around `spec` before the next slice (its edit band follows the
  /// edited profile; see StudioModel).
  void rebase(const operators::OperatorSpec& spec);
  /// Pauses the thread at the next slice boundary (the slice in progress finishes) until
  /// `set_paused(false)`: a drag's synchronous solve then has the cores to itself. Posting,
  /// rebasing and stopping still work while paused; `idle()` stays false while a job waits.
  void set_paused(bool paused);
  /// The results finished since the last call.
  std::vector<Result> take();
  /// Blocks until a result is ready, the job is done, or `timeout` passes.
  void wait(std::chrono::milliseconds timeout);
  /// True when the last posted job is finished (or failed) and no result is waiting.
  bool idle();
  /// The last failure ("" if none): the slice and the message.
  std::string error();

 private:
  struct Job {
    long generation{0};
    std::shared_ptr<const operators::OperatorSpec> spec;
    std::vector<int> slices;
  };
  void run();
  bool solve_job(const Job& job);

  operators::OperatorSpec base_;
  std::shared_ptr<const operators::OperatorSpec> next_base_;  // set by rebase(), guarded
  operators::BiharmonicOptions options_;
  std::unique_ptr<operators::BiharmonicOperatorGenerator> generator_;  // worker thread only
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  bool stop_{false}, has_job_{false}, busy_{false}, paused_{false};
  Job job_;
  std::vector<Result> outbox_;
  std::string error_;
  std::thread thread_;
};

}  // namespace isokit::studio::detail
