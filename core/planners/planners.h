// Factories of the built-in planners. The registry (registry.cc) is the only
// caller; everything else creates planners by name.
#ifndef PATHD_CORE_PLANNERS_PLANNERS_H_
#define PATHD_CORE_PLANNERS_PLANNERS_H_

#include <memory>

#include "core/planner.h"

namespace pathd {

std::unique_ptr<Planner> MakeAStarPlanner();
std::unique_ptr<Planner> MakeDijkstraPlanner();
std::unique_ptr<Planner> MakeBfsPlanner();
std::unique_ptr<Planner> MakeJpsPlanner();

}  // namespace pathd

#endif  // PATHD_CORE_PLANNERS_PLANNERS_H_
