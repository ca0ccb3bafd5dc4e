// The one memory budget of a pathd process: Navigate sessions and WatchMap
// streams reserve their bytes here before they are admitted, next to the
// caches' current bytes, so read-only clients cannot exhaust memory; each
// caller may hold only a share; freed memory is handed back to the system.
#ifndef PATHD_SERVER_MEMORY_BUDGET_H_
#define PATHD_SERVER_MEMORY_BUDGET_H_

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <thread>
#include <utility>

#include <grpcpp/server_context.h>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"

namespace pathd::server {

// Fixes glibc's trim threshold at 4 MiB and its mmap threshold at 32 MiB
// (the most it allows), unless GLIBC_TUNABLES sets either. By default glibc
// raises the trim threshold to twice the largest block freed so far: after a
// closed session's 16 MiB of D* Lite arrays, every thread arena may keep 32
// MiB of free top chunk resident, which malloc_trim does not reach, and
// limits_test saw RSS stay 75 MiB above its baseline after everything
// closed. A fixed 4 MiB returns an arena's free top at once; the 32 MiB mmap
// threshold keeps blocks up to that size on the heap, where they are reused
// without fresh page faults (a 1 MiB threshold made limits_test's workload
// twice as slow). Call once, before any thread starts.
void PinAllocatorThresholds();

// Thread-safe. Reservations are estimates made at admission (a session's D*
// Lite arrays, a watcher's worst-case backlog) and kept up to date as the
// holder learns its real size; the caches are bounded by their own flags and
// only read here, at each admission.
class MemoryBudget {
 public:
  enum class Part { kSessions = 0, kWatchers = 1 };
  static constexpr int kParts = 2;

  struct Options {
    // Everything together: caches, sessions and watchers
    // (--memory_budget_bytes); 0 = unbounded.
    int64_t total_bytes = int64_t{4} << 30;
    // Navigate sessions (--session_memory_bytes); 0 = only the total.
    int64_t session_bytes = int64_t{1} << 30;
    // WatchMap streams open at once (--max_watchers).
    int64_t max_watchers = 1024;
    // The share of each limit one caller may hold (--caller_memory_share),
    // in (0, 1].
    double caller_share = 0.5;
    // Callers are told apart by their bearer token when true (the server
    // checks tokens), else by their peer's IP address.
    bool callers_by_token = false;
    // The caches' bytes right now; empty = none.
    std::function<int64_t()> cache_bytes;
  };

  // What one session or watcher holds; returns it when destroyed (and hands
  // large frees back to the system). Move-only; thread-compatible.
  class Reservation {
   public:
    Reservation() = default;
    Reservation(Reservation&& other) noexcept;
    Reservation& operator=(Reservation&& other) noexcept;
    Reservation(const Reservation&) = delete;
    Reservation& operator=(const Reservation&) = delete;
    ~Reservation();

    // Sets the reserved bytes to `bytes`, within the limits: the same errors
    // as Reserve when growing past one (the reservation is then unchanged).
    absl::Status Resize(int64_t bytes);
    // Sets the reserved bytes to what is actually held, limits or not (the
    // memory is in use either way; the next admission sees it).
    void Update(int64_t bytes);
    int64_t bytes() const { return bytes_; }
    // Releases now (as the destructor would).
    void Release();

   private:
    friend class MemoryBudget;
    Reservation(MemoryBudget* budget, Part part, std::string caller, int64_t bytes)
        : budget_(budget), part_(part), caller_(std::move(caller)), bytes_(bytes) {}

    MemoryBudget* budget_ = nullptr;
    Part part_ = Part::kSessions;
    std::string caller_;
    int64_t bytes_ = 0;
  };

  // Starts the thread that returns freed memory to the system.
  explicit MemoryBudget(Options options);
  // Every reservation must have been released.
  ~MemoryBudget();
  MemoryBudget(const MemoryBudget&) = delete;
  MemoryBudget& operator=(const MemoryBudget&) = delete;

  // Reserves `bytes` of `part` for `caller` (CallerOf). RESOURCE_EXHAUSTED
  // naming the flag whose limit it would pass: --max_watchers (a watcher
  // beyond the count), --session_memory_bytes, --memory_budget_bytes (with
  // the caches' bytes), --caller_memory_share (the caller's share of any of
  // those). `what` names the reserving thing in the message.
  absl::StatusOr<Reservation> Reserve(Part part, const std::string& caller,
                                      int64_t bytes, std::string_view what);

  // The caller a call counts for: "token:<hash of the bearer token>" with
  // callers_by_token, else "peer:<IP address>" (port dropped).
  std::string CallerOf(const grpc::ServerContextBase& context) const;

  // For metrics and tests.
  int64_t reserved(Part part) const;
  int64_t holders(Part part) const;
  int64_t cache_bytes() const;
  int64_t refusals() const { return refusals_.load(std::memory_order_relaxed); }
  int64_t trims() const { return trims_.load(std::memory_order_relaxed); }
  const Options& options() const { return options_; }

  // Freed bytes after which the allocator is asked to return free memory to
  // the system (glibc keeps freed heap pages, so RSS would stay at its peak).
  static constexpr int64_t kTrimAfterFreedBytes = int64_t{16} << 20;
  // After such a release the memory is returned at once; besides, the
  // allocator's free bytes are looked at this often and returned when they
  // grew by kTrimAfterFreedBytes since the last trim (what gRPC frees late,
  // outside any reservation).
  static constexpr absl::Duration kTrimPoll = absl::Seconds(1);

 private:
  struct Usage {
    int64_t bytes = 0;
    int64_t holders = 0;
  };

  // Whether `caller` may add `extra_bytes` (and `extra_holders`) to `part`,
  // with the caches at `caches` bytes.
  absl::Status CheckLocked(Part part, const std::string& caller, int64_t extra_bytes,
                           int64_t extra_holders, int64_t caches,
                           std::string_view what) const
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  void Change(Part part, const std::string& caller, int64_t delta_bytes,
              int64_t delta_holders);

  const Options options_;
  mutable absl::Mutex mu_;
  std::array<Usage, kParts> parts_ ABSL_GUARDED_BY(mu_);
  // Per caller, only while it holds something.
  std::map<std::string, std::array<Usage, kParts>> callers_ ABSL_GUARDED_BY(mu_);
  int64_t freed_since_trim_ ABSL_GUARDED_BY(mu_) = 0;
  std::atomic<int64_t> refusals_{0};
  std::atomic<int64_t> trims_{0};

  // The trimming thread and what it waits for.
  void TrimLoop();
  absl::Mutex trim_mu_;
  // Signalled when trim_pending_ or stopping_ is set.
  absl::CondVar trim_cv_;
  bool trim_pending_ ABSL_GUARDED_BY(trim_mu_) = false;
  bool stopping_ ABSL_GUARDED_BY(trim_mu_) = false;
  std::thread trimmer_;
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_MEMORY_BUDGET_H_
