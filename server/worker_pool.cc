// WorkerPool: fixed threads, a bounded FIFO queue per priority, one scratch
// per thread shared by the workers and SubmitShort's callers, and the retry
// hint for refused jobs.
#include "server/worker_pool.h"

#include <algorithm>
#include <chrono>
#include <exception>
#include <new>
#include <utility>

#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "server/grpc_status.h"
#include "spdlog/spdlog.h"

namespace pathd::server {
namespace {

thread_local bool on_worker_thread = false;

class FunctionJob : public Job {
 public:
  FunctionJob(std::function<void(SearchScratch&)> run, std::function<void()> drop,
              std::function<void(const absl::Status&)> fail)
      : run_(std::move(run)), drop_(std::move(drop)), fail_(std::move(fail)) {}
  void Run(SearchScratch& scratch) override { run_(scratch); }
  void Drop() override {
    if (drop_) drop_();
  }
  void Fail(const absl::Status& status) override {
    if (fail_) {
      fail_(status);
    } else {
      Drop();
    }
  }

 private:
  std::function<void(SearchScratch&)> run_;
  std::function<void()> drop_;
  std::function<void(const absl::Status&)> fail_;
};

// The status a job that threw answers with.
absl::Status FailureStatus(std::exception_ptr thrown) {
  try {
    std::rethrow_exception(thrown);
  } catch (const std::bad_alloc&) {
    return absl::ResourceExhaustedError(
        "the server ran out of memory while handling this request; retry later");
  } catch (const std::exception& e) {
    return absl::InternalError(
        absl::StrFormat("the request failed inside the server: %s", e.what()));
  } catch (...) {
    return absl::InternalError(
        "the request failed inside the server (a non-standard exception)");
  }
}

int ThreadCount(int requested) {
  if (requested > 0) return requested;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

// The mean of recent run times, the newest weighted 1/8; `mean` zero: none yet.
void UpdateMean(absl::Duration ran_for, absl::Duration& mean) {
  mean = mean == absl::ZeroDuration() ? ran_for : mean + (ran_for - mean) / 8;
}

}  // namespace

void Job::Fail(const absl::Status& /*status*/) { Drop(); }

std::unique_ptr<Job> MakeJob(std::function<void(SearchScratch&)> run,
                             std::function<void()> drop,
                             std::function<void(const absl::Status&)> fail) {
  return std::make_unique<FunctionJob>(std::move(run), std::move(drop),
                                       std::move(fail));
}

WorkerPool::WorkerPool(const Options& options)
    : queue_depth_(std::max<size_t>(1, options.queue_depth)),
      batch_queue_depth_(std::max<size_t>(1, options.batch_queue_depth)),
      inline_max_job_time_(options.inline_max_job_time) {
  const int n = ThreadCount(options.threads);
  {
    absl::MutexLock lock(&mu_);
    for (int i = 0; i < n; ++i) free_scratch_.push_back(std::make_unique<SearchScratch>());
  }
  threads_.reserve(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) threads_.emplace_back([this] { WorkerLoop(); });
}

WorkerPool::~WorkerPool() { Shutdown(ShutdownMode::kDrop); }

absl::Status WorkerPool::Submit(std::unique_ptr<Job> job, Priority priority) {
  absl::MutexLock lock(&mu_);
  return EnqueueLocked(std::move(job), priority, /*short_job=*/false);
}

absl::Status WorkerPool::EnqueueLocked(std::unique_ptr<Job> job, Priority priority,
                                       bool short_job) {
  if (stopping_) return absl::UnavailableError("server is shutting down");
  const bool interactive = priority == Priority::kInteractive;
  std::deque<Queued>& queue = interactive ? queue_ : batch_queue_;
  if (queue.size() >= queue_depth(priority)) {
    const absl::Duration after = EstimateRetryAfterLocked(priority);
    return WithRetryAfter(
        absl::ResourceExhaustedError(absl::StrFormat(
            "%s work queue full (%d jobs waiting, the limit set by %s); retry "
            "in about %d ms (trailing metadata %s)",
            interactive ? "interactive" : "batch", queue.size(),
            interactive ? "--queue_depth" : "--batch_queue_depth",
            absl::ToInt64Milliseconds(after), kRetryAfterMsKey)),
        after);
  }
  queue.push_back(Queued{std::move(job), short_job});
  return absl::OkStatus();
}

absl::Status WorkerPool::SubmitShort(std::unique_ptr<Job> job, absl::Duration time_left) {
  std::unique_ptr<SearchScratch> scratch;
  {
    absl::MutexLock lock(&mu_);
    const bool run_here = !stopping_ && inline_max_job_time_ > absl::ZeroDuration() &&
                          mean_short_job_time_ <= inline_max_job_time_ &&
                          time_left > inline_max_job_time_ &&
                          queue_.empty() && batch_queue_.empty() &&
                          !free_scratch_.empty();
    if (!run_here) {
      return EnqueueLocked(std::move(job), Priority::kInteractive, /*short_job=*/true);
    }
    scratch = std::move(free_scratch_.back());
    free_scratch_.pop_back();
  }
  inline_runs_.fetch_add(1, std::memory_order_relaxed);
  const bool was_on_worker = on_worker_thread;
  on_worker_thread = true;
  const absl::Duration ran_for = RunJob(*job, *scratch);
  on_worker_thread = was_on_worker;
  job.reset();
  JobEnded(std::move(scratch), ran_for, /*short_job=*/true);
  return absl::OkStatus();
}

absl::Duration WorkerPool::EstimateRetryAfter(Priority priority) const {
  absl::MutexLock lock(&mu_);
  return EstimateRetryAfterLocked(priority);
}

absl::Duration WorkerPool::EstimateRetryAfterLocked(Priority priority) const {
  size_t ahead = queue_.size();
  if (priority == Priority::kBatch) ahead += batch_queue_.size();
  const absl::Duration per_job =
      mean_job_time_ > absl::ZeroDuration() ? mean_job_time_ : kDefaultJobTime;
  const absl::Duration wait =
      per_job * static_cast<double>(ahead) / static_cast<double>(threads_.size());
  // Whole milliseconds, rounded up: the hint travels as an integer.
  return std::clamp(absl::Ceil(wait, absl::Milliseconds(1)), kMinRetryAfter,
                    kMaxRetryAfter);
}

void WorkerPool::Shutdown(ShutdownMode mode) {
  absl::MutexLock join_lock(&join_mu_);
  if (joined_) return;
  std::deque<Queued> dropped;
  {
    absl::MutexLock lock(&mu_);
    stopping_ = true;
    if (mode == ShutdownMode::kDrop) {
      dropped.swap(queue_);
      for (Queued& queued : batch_queue_) dropped.push_back(std::move(queued));
      batch_queue_.clear();
    }
  }
  // Outside mu_: a Drop() answers an RPC, which must not hold the pool lock.
  for (Queued& queued : dropped) queued.job->Drop();
  for (std::thread& t : threads_) t.join();
  joined_ = true;
}

size_t WorkerPool::queued() const {
  absl::MutexLock lock(&mu_);
  return queue_.size() + batch_queue_.size();
}

size_t WorkerPool::queued(Priority priority) const {
  absl::MutexLock lock(&mu_);
  return priority == Priority::kInteractive ? queue_.size() : batch_queue_.size();
}

bool WorkerPool::OnWorkerThread() { return on_worker_thread; }

void WorkerPool::WorkerLoop() {
  on_worker_thread = true;
  for (;;) {
    Queued queued;
    std::unique_ptr<SearchScratch> scratch;
    {
      absl::MutexLock lock(&mu_, absl::Condition(this, &WorkerPool::CanStartOrDone));
      std::deque<Queued>& queue = queue_.empty() ? batch_queue_ : queue_;
      if (queue.empty()) return;  // stopping, nothing left to drain
      queued = std::move(queue.front());
      queue.pop_front();
      scratch = std::move(free_scratch_.back());
      free_scratch_.pop_back();
    }
    const absl::Duration ran_for = RunJob(*queued.job, *scratch);
    // The job's destructor may release what it holds (a call, a session):
    // before the scratch is given back, as on the inline path.
    queued.job.reset();
    JobEnded(std::move(scratch), ran_for, queued.short_job);
  }
}

absl::Duration WorkerPool::RunJob(Job& job, SearchScratch& scratch) {
  busy_.fetch_add(1, std::memory_order_relaxed);
  const auto started = std::chrono::steady_clock::now();
  std::exception_ptr thrown;
  try {
    if (fail_next_jobs_.load(std::memory_order_relaxed) > 0 &&
        fail_next_jobs_.fetch_sub(1, std::memory_order_relaxed) > 0) {
      throw std::bad_alloc();
    }
    job.Run(scratch);
  } catch (...) {
    thrown = std::current_exception();
  }
  if (thrown != nullptr) {
    // Jobs answer their own errors; one that escaped still has to answer
    // its call and release what it holds (Job::Fail), or the client waits
    // forever and the server's shutdown waits for that call.
    const absl::Status status = FailureStatus(thrown);
    job_failures_.fetch_add(1, std::memory_order_relaxed);
    spdlog::error("worker job threw; answering its call with {}", status.ToString());
    try {
      job.Fail(status);
    } catch (...) {
      spdlog::error("worker job threw again while failing; its call may be unanswered");
    }
  }
  const auto ran_for_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                              std::chrono::steady_clock::now() - started)
                              .count();
  busy_ns_.fetch_add(ran_for_ns, std::memory_order_relaxed);
  busy_.fetch_sub(1, std::memory_order_relaxed);
  return absl::Nanoseconds(ran_for_ns);
}

void WorkerPool::JobEnded(std::unique_ptr<SearchScratch> scratch, absl::Duration ran_for,
                          bool short_job) {
  absl::MutexLock lock(&mu_);
  free_scratch_.push_back(std::move(scratch));
  UpdateMean(ran_for, mean_job_time_);
  if (short_job) UpdateMean(ran_for, mean_short_job_time_);
}

}  // namespace pathd::server
