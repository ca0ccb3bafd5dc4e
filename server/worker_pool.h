// The fixed pool of planning threads behind a bounded queue. Planning never
// runs on gRPC's threads; each worker owns the SearchScratch its jobs reuse,
// and a full queue fails fast instead of piling up latency.
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
#include "core/search_scratch.h"

namespace pathd::server {

// A unit of work. Once accepted by Submit, exactly one of Run or Drop is
// called, exactly once.
class Job {
 public:
  virtual ~Job() = default;
  // Runs on a pool thread with that thread's scratch (valid for the call only).
  virtual void Run(SearchScratch& scratch) = 0;
  // The pool shut down before the job ran; runs on the thread calling
  // Shutdown. Must not block for long (answer UNAVAILABLE and return).
  virtual void Drop() = 0;
};

// A Job from two callables; `drop` may be empty.
std::unique_ptr<Job> MakeJob(std::function<void(SearchScratch&)> run,
                             std::function<void()> drop = nullptr);

// Thread-safe.
class WorkerPool {
 public:
  struct Options {
    // Worker threads; 0 means std::thread::hardware_concurrency() (at least 1).
    int threads = 0;
    // Jobs that may wait for a worker; at least 1.
    size_t queue_depth = 256;
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

  // Queues `job`. Never blocks: RESOURCE_EXHAUSTED "work queue full (depth
  // N)" when the queue is full, UNAVAILABLE after Shutdown. On error the job
  // is destroyed without Run or Drop; the caller answers with the status.
  absl::Status Submit(std::unique_ptr<Job> job);

  // Stops accepting jobs, handles queued ones per `mode`, and joins the
  // threads (so every running job has returned). Idempotent; must not be
  // called from a pool thread.
  void Shutdown(ShutdownMode mode);

  int threads() const { return static_cast<int>(threads_.size()); }
  size_t queue_depth() const { return queue_depth_; }
  // Jobs waiting for a worker right now (for logs and metrics).
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

  // True on a thread of any WorkerPool (lets tests and asserts check that
  // work is where it should be).
  static bool OnWorkerThread();

 private:
  void WorkerLoop();
  bool HasWorkOrStopping() const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    return stopping_ || !queue_.empty();
  }

  const size_t queue_depth_;
  mutable absl::Mutex mu_;
  std::deque<std::unique_ptr<Job>> queue_ ABSL_GUARDED_BY(mu_);
  // Workers leave once this is set and the queue is empty; kDrop empties the
  // queue itself, so both modes share one exit rule.
  bool stopping_ ABSL_GUARDED_BY(mu_) = false;
  // Sized in the constructor and never resized; only joined (once, under
  // join_mu_), so threads() needs no lock.
  std::vector<std::thread> threads_;
  absl::Mutex join_mu_;
  bool joined_ ABSL_GUARDED_BY(join_mu_) = false;
  // Metrics only: relaxed atomics, so no job waits on them.
  std::atomic<int> busy_{0};
  std::atomic<int64_t> busy_ns_{0};
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_WORKER_POOL_H_
