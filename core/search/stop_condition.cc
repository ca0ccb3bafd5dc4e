// The stop condition's clock and cancel checks and the progress rate limit.
#include "core/search/stop_condition.h"

#include "absl/time/clock.h"

namespace pathd {

void ProgressSink::Poll(int64_t expansions, double best_f) {
  const absl::Time now = absl::Now();
  if (next_ == absl::InfinitePast()) {
    next_ = now + interval_;
    return;
  }
  if (now < next_) return;
  // From now rather than next_ += interval: a long stretch between polls
  // must not be followed by a burst of catch-up reports.
  next_ = now + interval_;
  Report(expansions, best_f, now);
}

PlanOutcome StopCondition::CheckNow() const {
  // The deadline first: gRPC cancels a call whose deadline passed too, and the
  // outcome should say it timed out rather than that someone cancelled it.
  if (deadline_ != absl::InfiniteFuture() && absl::Now() >= deadline_) {
    return PlanOutcome::kTimeout;
  }
  if (cancelled_ != nullptr && cancelled_->load(std::memory_order_relaxed)) {
    return PlanOutcome::kCancelled;
  }
  return PlanOutcome::kFound;
}

}  // namespace pathd
