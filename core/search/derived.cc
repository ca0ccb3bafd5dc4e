// DerivedStop's reads of the stop condition, out of line: derived.h is
// included by plan_types.h and stop_condition.h, so it cannot include them.
#include "core/search/derived.h"

#include "absl/status/status.h"
#include "core/search/plan_types.h"
#include "core/search/stop_condition.h"

namespace pathd {

bool DerivedStop::Stopped() const { return Outcome() != PlanOutcome::kFound; }

PlanOutcome DerivedStop::Outcome() const {
  return condition_ == nullptr ? PlanOutcome::kFound : condition_->CheckNow();
}

absl::Time DerivedStop::deadline() const {
  return condition_ == nullptr ? absl::InfiniteFuture() : condition_->deadline();
}

absl::StatusOr<PlanResult> StoppedWhileDeriving(const DerivedStop& stop) {
  PlanResult result;
  result.outcome = stop.Outcome();
  if (result.outcome == PlanOutcome::kFound) {
    return absl::InternalError(
        "a derived structure's build returned nothing though the query was "
        "neither past its deadline nor cancelled");
  }
  result.stopped_while = stop.stopped_while();
  return result;
}

}  // namespace pathd
