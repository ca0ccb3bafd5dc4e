// The one table between wire planner values (pathd.v1.Planner) and the names
// the planner registry, pathctl and the docs use, derived from the enum's
// descriptor: PLANNER_WEIGHTED_ASTAR <-> "weighted_astar". Linked by the
// server and pathctl, so a planner added to the proto is named everywhere.
#ifndef PATHD_PROTO_PLANNER_NAMES_H_
#define PATHD_PROTO_PLANNER_NAMES_H_

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "pathd/v1/planner_service.pb.h"

namespace pathd {

struct WirePlanner {
  v1::Planner wire;
  std::string name;
};

// Every planner value but PLANNER_UNSPECIFIED, in enum order. Built once from
// the descriptor; thread-safe.
const std::vector<WirePlanner>& WirePlanners();

// The name of `planner`; nullopt for PLANNER_UNSPECIFIED and unknown values.
std::optional<std::string_view> WirePlannerName(int planner);

// The wire value named `name`; nullopt when no planner has that name.
std::optional<v1::Planner> WirePlannerFromName(std::string_view name);

}  // namespace pathd

#endif  // PATHD_PROTO_PLANNER_NAMES_H_
