// How a search learns to stop: deadline, cancellation and expansion budget as
// one condition polled by every search loop, with an optional progress sink.
#ifndef PATHD_CORE_SEARCH_STOP_CONDITION_H_
#define PATHD_CORE_SEARCH_STOP_CONDITION_H_

#include <atomic>
#include <cstdint>
#include <limits>

#include "absl/time/time.h"
#include "core/search/plan_types.h"

namespace pathd {

// Receives a running search's progress, at most once per interval, from the
// stop condition's polls (so every planner reports without plumbing of its
// own). The first report comes one interval after the first poll, so a search
// that ends sooner reports nothing. Thread-compatible: one search polls it.
class ProgressSink {
 public:
  explicit ProgressSink(absl::Duration interval) : interval_(interval) {}
  virtual ~ProgressSink() = default;

  // Called at every poll; calls Report when the interval has passed since the
  // last report (or the first poll).
  void Poll(int64_t expansions, double best_f);

 protected:
  // `expansions` so far (descent steps for the potential field), `best_f` the
  // smallest key on the open list (NaN when the planner has none), `now` the
  // clock reading that passed the rate limit.
  virtual void Report(int64_t expansions, double best_f, absl::Time now) = 0;

 private:
  const absl::Duration interval_;
  // InfinitePast until the first poll arms it.
  absl::Time next_ = absl::InfinitePast();
};

// Deadline, cancellation and expansion budget as one condition, polled by
// every search loop every kPollInterval expansions (and at the budget).
// Thread-compatible; the cancel flag may be set from any thread.
class StopCondition {
 public:
  static constexpr int64_t kPollInterval = 1024;
  // best_f of a search without an ordered open list.
  static constexpr double kNoKey = std::numeric_limits<double>::quiet_NaN();

  StopCondition() = default;
  // `progress`, when not null, is polled with the search's progress and must
  // outlive the search.
  StopCondition(absl::Time deadline, const std::atomic<bool>* cancelled,
                int64_t max_expansions, ProgressSink* progress = nullptr)
      : deadline_(deadline),
        cancelled_(cancelled),
        max_expansions_(max_expansions),
        progress_(progress) {}

  static StopCondition None() { return StopCondition(); }

  // Returns the outcome to stop with, or kFound meaning "keep going". Cheap
  // enough to call every expansion; only reads the clock every kPollInterval.
  // `best_f` is the smallest open-list key, for progress reports.
  PlanOutcome Check(int64_t expansions, double best_f = kNoKey) const {
    if (max_expansions_ > 0 && expansions >= max_expansions_) {
      return PlanOutcome::kExpansionLimit;
    }
    if ((expansions & (kPollInterval - 1)) != 0) return PlanOutcome::kFound;
    return Poll(expansions, best_f);
  }
  // Checks cancellation and the deadline now.
  PlanOutcome CheckNow() const;
  // CheckNow plus a progress report: for loops that poll on their own
  // schedule (row by row) rather than through Check.
  PlanOutcome Poll(int64_t expansions, double best_f = kNoKey) const {
    if (progress_ != nullptr) progress_->Poll(expansions, best_f);
    return CheckNow();
  }

  // The same deadline and cancel flag with another expansion budget (0:
  // none), for callers that split one budget over several searches.
  StopCondition WithMaxExpansions(int64_t max_expansions) const {
    return StopCondition(deadline_, cancelled_, max_expansions);
  }

  absl::Time deadline() const { return deadline_; }
  int64_t max_expansions() const { return max_expansions_; }

 private:
  absl::Time deadline_ = absl::InfiniteFuture();
  const std::atomic<bool>* cancelled_ = nullptr;
  int64_t max_expansions_ = 0;
  ProgressSink* progress_ = nullptr;
};

}  // namespace pathd

#endif  // PATHD_CORE_SEARCH_STOP_CONDITION_H_
