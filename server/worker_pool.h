// The fixed pool of planning threads behind one bounded queue per priority.
// At most threads() jobs run at once, each with a SearchScratch of the pool's
// own (reused from job to job); interactive jobs always start before batch
// ones, and a full queue fails fast (with a retry hint) instead of piling up
// latency. Jobs run on the pool's threads, except short ones a gRPC thread
// may run itself when a worker is free and nothing waits (SubmitShort): the
// hand-off to a worker and back would cost more than such a job.
#ifndef PATHD_SERVER_WORKER_POOL_H_
#define PATHD_SERVER_WORKER_POOL_H_

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <thread>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "core/search/search_scratch.h"

namespace pathd::server {

// A unit of work. Once accepted by Submit, exactly one of Run or Drop is
// called, exactly once; when Run throws, Fail follows it.
class Job {
 public:
  virtual ~Job() = default;
  // Runs on a pool thread with that thread's scratch (valid for the call only).
  virtual void Run(SearchScratch& scratch) = 0;
  // The pool shut down before the job ran; runs on the thread calling
  // Shutdown. Must not block for long (answer UNAVAILABLE and return).
  virtual void Drop() = 0;
  // Run threw: `status` is RESOURCE_EXHAUSTED for std::bad_alloc, INTERNAL
  // for anything else. Runs on the same pool thread. Must answer the call the
  // job serves with `status` (unless Run already did) and release whatever
  // the job holds, or the client waits forever and shutdown with it. The
  // default calls Drop(), which answers and releases too, but with
  // UNAVAILABLE; jobs that own a call should override it.
  virtual void Fail(const absl::Status& status);
};

// A Job from callables; `drop` and `fail` may be empty (an empty `fail`
// calls `drop`).
std::unique_ptr<Job> MakeJob(std::function<void(SearchScratch&)> run,
                             std::function<void()> drop = nullptr,
                             std::function<void(const absl::Status&)> fail = nullptr);

// Thread-safe.
class WorkerPool {
 public:
  struct Options {
    // Worker threads; 0 means std::thread::hardware_concurrency() (at least 1).
    int threads = 0;
    // Interactive jobs that may wait for a worker; at least 1.
    size_t queue_depth = 256;
    // Batch jobs that may wait for a worker; at least 1.
    size_t batch_queue_depth = 1024;
    // SubmitShort runs a job on the calling thread while the recent mean run
    // time of the jobs submitted that way is at most this; zero: never
    // (--inline_max_job_time).
    absl::Duration inline_max_job_time = absl::Milliseconds(1);
  };
  // Which queue a job waits in. A free worker always takes the oldest
  // interactive job first and a batch job only when none waits, so a batch
  // backlog never delays a robot's Plan; batch work can starve while
  // interactive work keeps every worker busy (by design).
  enum class Priority {
    // Plan, CostToGo, IsPathValid, Navigate messages, cache repairs.
    kInteractive,
    // PlanBatch requests.
    kBatch,
  };
  enum class ShutdownMode {
    // Run every queued job, then stop.
    kDrain,
    // Drop() every queued job; running jobs still finish.
    kDrop,
  };

  // Starts the threads.
  explicit WorkerPool(const Options& options);
  // Shutdown(kDrop) if not already shut down.
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  // Queues `job` behind the jobs of its priority. Never blocks: when that
  // priority's queue is full, RESOURCE_EXHAUSTED naming the queue and its flag
  // with a retry hint (RetryAfter() in server/grpc_status.h; see
  // EstimateRetryAfter); UNAVAILABLE after Shutdown. On error the job is
  // destroyed without Run or Drop; the caller answers with the status.
  absl::Status Submit(std::unique_ptr<Job> job,
                      Priority priority = Priority::kInteractive);

  // An interactive job that is usually short (a Plan, an IsPathValid). Runs
  // it on the calling thread before returning, as a worker would (the
  // scratch, the failure handling, the busy count), when all of these hold:
  // fewer than threads() jobs are running, none waits, the pool is not
  // shutting down, and the mean run time of the recent jobs given to this
  // function (wherever they ran) is at most Options::inline_max_job_time,
  // and `time_left` (until the call's deadline) is more than that: a call
  // about to time out goes to the queue, where it is dropped if it did.
  // Otherwise queues it as Submit does. The caller must not hold locks its
  // job takes.
  absl::Status SubmitShort(std::unique_ptr<Job> job,
                           absl::Duration time_left = absl::InfiniteDuration());

  // Stops accepting jobs, handles queued ones per `mode`, and joins the
  // threads (so every running job has returned). Idempotent; must not be
  // called from a pool thread.
  void Shutdown(ShutdownMode mode);

  int threads() const { return static_cast<int>(threads_.size()); }
  size_t queue_depth(Priority priority = Priority::kInteractive) const {
    return priority == Priority::kInteractive ? queue_depth_ : batch_queue_depth_;
  }
  // Jobs of both priorities waiting for a worker right now (for logs and
  // metrics).
  size_t queued() const;
  // Workers running a job right now (for metrics: busy / threads is the
  // instantaneous utilisation).
  int busy() const { return busy_.load(std::memory_order_relaxed); }
  // Time all workers spent running jobs, summed over jobs that returned (a
  // running job counts when it ends). Its rate over threads() is the
  // utilisation between two scrapes.
  absl::Duration busy_time() const {
    return absl::Nanoseconds(busy_ns_.load(std::memory_order_relaxed));
  }
  // Jobs of `priority` waiting for a worker right now.
  size_t queued(Priority priority) const;
  // Jobs SubmitShort ran on the calling thread, since start (for metrics).
  int64_t inline_runs() const { return inline_runs_.load(std::memory_order_relaxed); }

  // How long a job of `priority` refused now should wait before it is sent
  // again: the time the workers need to start every job queued ahead of it
  // (the queued interactive jobs, plus the batch ones for kBatch) at the
  // recent mean run time of a job (kDefaultJobTime before any job ran),
  // clamped to [kMinRetryAfter, kMaxRetryAfter]. A client that waits this
  // long finds room unless more work arrived meanwhile, and clients refused
  // together do not all come back at once when the backlog is long.
  absl::Duration EstimateRetryAfter(Priority priority) const;
  static constexpr absl::Duration kDefaultJobTime = absl::Milliseconds(50);
  static constexpr absl::Duration kMinRetryAfter = absl::Milliseconds(10);
  static constexpr absl::Duration kMaxRetryAfter = absl::Seconds(30);

  // Jobs whose Run threw (each answered through Job::Fail), since start.
  int64_t job_failures() const {
    return job_failures_.load(std::memory_order_relaxed);
  }

  // Test hook: the next `count` jobs throw std::bad_alloc on their worker
  // right before Run, as an allocation failure inside the job would.
  void FailNextJobsForTesting(int count) {
    fail_next_jobs_.store(count, std::memory_order_relaxed);
  }

  // True while a thread runs a job of any WorkerPool: a worker, or a caller
  // of SubmitShort running one (lets tests and asserts check that work is
  // where it should be).
  static bool OnWorkerThread();

 private:
  struct Queued {
    std::unique_ptr<Job> job;
    // Given to SubmitShort: its run time feeds mean_short_job_time_.
    bool short_job = false;
  };
  void WorkerLoop();
  // Submit's queueing and refusals.
  absl::Status EnqueueLocked(std::unique_ptr<Job> job, Priority priority, bool short_job)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  // A job may start (one waits and a scratch is free), or the pool stopped
  // and nothing is left to drain: the workers' wake-up condition.
  bool CanStartOrDone() const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    const bool waiting = !queue_.empty() || !batch_queue_.empty();
    return waiting ? !free_scratch_.empty() : stopping_;
  }
  // Runs `job` with `scratch` on this thread: the busy count and time, the
  // test hook, failures answered through Job::Fail. Returns the run time.
  absl::Duration RunJob(Job& job, SearchScratch& scratch);
  // Gives back a scratch taken from free_scratch_ and counts `ran_for`.
  void JobEnded(std::unique_ptr<SearchScratch> scratch, absl::Duration ran_for,
                bool short_job) ABSL_LOCKS_EXCLUDED(mu_);
  absl::Duration EstimateRetryAfterLocked(Priority priority) const
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);

  const size_t queue_depth_;
  const size_t batch_queue_depth_;
  const absl::Duration inline_max_job_time_;
  mutable absl::Mutex mu_;
  std::deque<Queued> queue_ ABSL_GUARDED_BY(mu_);
  std::deque<Queued> batch_queue_ ABSL_GUARDED_BY(mu_);
  // One scratch per thread: a job takes one when it starts and gives it back
  // when it ends, so at most threads() jobs run at once wherever they run.
  // Search memory grows to the largest map a scratch has served and is then
  // reused without clearing (SearchScratch ids).
  std::vector<std::unique_ptr<SearchScratch>> free_scratch_ ABSL_GUARDED_BY(mu_);
  // Exponentially weighted means of recent run times (weight 1/8 for the
  // newest), zero until a job has run: of every job, for EstimateRetryAfter;
  // of SubmitShort's jobs, for its choice.
  absl::Duration mean_job_time_ ABSL_GUARDED_BY(mu_);
  absl::Duration mean_short_job_time_ ABSL_GUARDED_BY(mu_);
  // Workers leave once this is set and both queues are empty; kDrop empties
  // the queues itself, so both modes share one exit rule.
  bool stopping_ ABSL_GUARDED_BY(mu_) = false;
  // Sized in the constructor and never resized; only joined (once, under
  // join_mu_), so threads() needs no lock.
  std::vector<std::thread> threads_;
  absl::Mutex join_mu_;
  bool joined_ ABSL_GUARDED_BY(join_mu_) = false;
  // Metrics only: relaxed atomics, so no job waits on them.
  std::atomic<int> busy_{0};
  std::atomic<int64_t> busy_ns_{0};
  std::atomic<int64_t> job_failures_{0};
  std::atomic<int64_t> inline_runs_{0};
  std::atomic<int> fail_next_jobs_{0};
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_WORKER_POOL_H_
