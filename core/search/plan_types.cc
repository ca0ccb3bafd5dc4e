// Names of plan outcomes.
#include "core/search/plan_types.h"

#include <string_view>

namespace pathd {

std::string_view PlanOutcomeName(PlanOutcome outcome) {
  switch (outcome) {
    case PlanOutcome::kFound:
      return "FOUND";
    case PlanOutcome::kNoPath:
      return "NO_PATH";
    case PlanOutcome::kExpansionLimit:
      return "EXPANSION_LIMIT";
    case PlanOutcome::kTimeout:
      return "TIMEOUT";
    case PlanOutcome::kCancelled:
      return "CANCELLED";
    case PlanOutcome::kLocalMinimum:
      return "LOCAL_MINIMUM";
  }
  return "UNKNOWN";
}

}  // namespace pathd
