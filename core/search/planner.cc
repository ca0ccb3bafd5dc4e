// Listing names of what planners guarantee.
#include "core/search/planner.h"

#include <string_view>

namespace pathd {

std::string_view GuaranteeName(const PlannerTraits& traits) {
  if (traits.real_time) return "real-time";
  if (traits.kinematic) return "kinematic";
  if (traits.geometric) return traits.optimal ? "euclidean-optimal" : "geometric";
  if (traits.any_angle) return "any-angle";
  if (traits.fewest_moves) return "fewest moves";
  if (traits.optimal) return "optimal";
  if (traits.bounded) return "bounded";
  return "heuristic";
}

}  // namespace pathd
