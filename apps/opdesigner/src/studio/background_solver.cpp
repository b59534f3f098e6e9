// SPDX-License-Identifier: MIT
#include "studio/background_solver.h"

#include <exception>
#include <utility>

namespace isokit::studio::detail {

BackgroundSolver::BackgroundSolver(operators::OperatorSpec base, operators::BiharmonicOptions options)
    : base_(std::move(base)), options_(std::move(options)), thread_([this] { run(); }) {}

BackgroundSolver::~BackgroundSolver() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void BackgroundSolver::post(long generation, const operators::OperatorSpec& spec, std::vector<int> slices) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    job_ = Job{generation, std::make_shared<const operators::OperatorSpec>(spec), std::move(slices)};
    has_job_ = true;
  }
  wake_.notify_all();
}

void BackgroundSolver::rebase(const operators::OperatorSpec& spec) {
  std::lock_guard<std::mutex> lock(mutex_);
  next_base_ = std::make_shared<const operators::OperatorSpec>(spec);
}

void BackgroundSolver::set_paused(bool paused) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    paused_ = paused;
  }
  wake_.notify_all();
}

std::vector<BackgroundSolver::Result> BackgroundSolver::take() {
  std::lock_guard<std::mutex> lock(mutex_);
  return std::exchange(outbox_, {});
}

void BackgroundSolver::wait(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait_for(lock, timeout, [&] { return stop_ || !outbox_.empty() || (!has_job_ && !busy_); });
}

bool BackgroundSolver::idle() {
  std::lock_guard<std::mutex> lock(mutex_);
  return !has_job_ && !busy_ && outbox_.empty();
}

std::string BackgroundSolver::error() {
  std::lock_guard<std::mutex> lock(mutex_);
  return error_;
}

void BackgroundSolver::run() {
  for (;;) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stop_ || has_job_; });
      if (stop_) return;
      job = std::move(job_);
      has_job_ = false;
      busy_ = true;
    }
    solve_job(job);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      busy_ = false;
    }
    done_.notify_all();
  }
}

// Solves the job's slices until a newer job or stop arrives. False on a failure (recorded).
bool BackgroundSolver::solve_job(const Job& job) {
  const int nd = job.spec->slices;
  for (const int k : job.slices) {
    std::shared_ptr<const operators::OperatorSpec> rebase;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stop_ || !paused_; });  // a drag in progress: stand aside
      if (stop_ || has_job_) return true;
      rebase = std::exchange(next_base_, nullptr);
    }
    Result r{job.generation, k, {}};
    try {
      if (rebase) generator_ = std::make_unique<operators::BiharmonicOperatorGenerator>(*rebase, options_);
      if (!generator_) generator_ = std::make_unique<operators::BiharmonicOperatorGenerator>(base_, options_);
      r.values = generator_->solve_edited(nd == 1 ? 0.0 : double(k) / (nd - 1), *job.spec);
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(mutex_);
      error_ = "background solve of slice " + std::to_string(k) + ": " + e.what();
      return false;
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      outbox_.push_back(std::move(r));
    }
    done_.notify_all();
  }
  return true;
}

}  // namespace isokit::studio::detail
