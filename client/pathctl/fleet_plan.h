// What `pathctl fleet plan` and `pathctl render --robots` share: the
// PlanFleet request from the command line (the --robots file, --solver and
// its options, the cost options) and a one-line summary of the answer.
#ifndef PATHD_CLIENT_PATHCTL_FLEET_PLAN_H_
#define PATHD_CLIENT_PATHCTL_FLEET_PLAN_H_

#include <string>

#include "absl/status/statusor.h"
#include "client/pathctl/options.h"
#include "pathd/v1/planner_service.pb.h"

namespace pathd::pathctl {

// The request for map `map`. INVALID_ARGUMENT (a usage error) naming the
// flag, or the file and line of a bad robot; the file's read error.
absl::StatusOr<v1::PlanFleetRequest> FleetPlanRequest(const Options& options,
                                                      const std::string& map);

// --solver's value: lacam (also empty), pibt, prioritized or cbs;
// INVALID_ARGUMENT naming the flag otherwise.
absl::StatusOr<v1::FleetSolver> SolverFromName(const std::string& name);

// "fleet plan (lacam): 12 robots, makespan 40, sum of costs 310 (lower
// bound 298)" or "no fleet plan: <reason>".
std::string FleetPlanSummary(const v1::PlanFleetResponse& response);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_FLEET_PLAN_H_
