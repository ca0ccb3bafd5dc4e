// What the fleet RPCs (Table, Nearest, Trip, Isochrone in fleet_queries.cc,
// PlanFleet in fleet_plan.cc) share: the cost options decoded as a plan
// query, positions checked and named, the planning grid from the inflation
// cache, the status of a stopped computation, and admission to the worker
// pool with one request log line.
#ifndef PATHD_SERVER_RPC_FLEET_COMMON_H_
#define PATHD_SERVER_RPC_FLEET_COMMON_H_

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_format.h"
#include "core/fleet/mapf.h"
#include "core/map/grid.h"
#include "core/search/plan_types.h"
#include "server/convert.h"
#include "server/request_log.h"
#include "server/rpc/plan_call.h"
#include "server/rpc/unary_call.h"

namespace pathd::server {

// What every fleet query decodes: the map snapshot and the cost options as
// a plan query (cost, robot radius or footprint, inflation and clearance
// costs, expansion budget).
struct FleetQuery {
  DecodedQuery decoded;
  const Grid& stored() const { return *decoded.snapshot->grid; }
  const PlanQuery& query() const { return decoded.query; }
};

// Distance along timed cells: a straight move 1, a diagonal sqrt(2), a
// wait 0 (cells).
double StepsLength(const std::vector<Cell>& cells);

// A robot's timed path in a response: its cells and their world centres on
// `stored`, its cost (the step of its last arrival at its goal) and length
// in cells and metres.
void FillFleetPath(const std::vector<Cell>& cells, const Grid& stored, v1::FleetPath* path);

// The solver of a request (UNSPECIFIED: LaCAM), and back. CheckFleetSolver
// names `field` when the value is none of the enum's (the wire carries any
// number).
absl::Status CheckFleetSolver(v1::FleetSolver solver, std::string_view field);
FleetSolver FleetSolverFromProto(v1::FleetSolver solver);
v1::FleetSolver FleetSolverToProto(FleetSolver solver);

// The map snapshot and the cost options of `map` and `options` (with an
// expansion budget), refusing cost shaping a fleet query cannot use.
absl::StatusOr<FleetQuery> DecodeFleetQuery(const PlanDeps& deps, const std::string& map,
                                            const v1::PlanOptions& options,
                                            int planner = 0);

// Each position as a cell that is on the map and traversable on the stored
// map, errors naming `field`[i].
absl::StatusOr<std::vector<Cell>> DecodeCells(
    const google::protobuf::RepeatedPtrField<v1::Position>& positions,
    const std::string& field, const FleetQuery& q);

// The grid a query plans on: the snapshot's, or its shaped copy from the
// cache; then no cell may be inscribed by the radius (errors name
// `field`[i], or `field` alone for a single unindexed position).
absl::StatusOr<std::shared_ptr<const Grid>> PlanningGridFor(
    InflationCache& inflation, const FleetQuery& q, const std::vector<Cell>& cells,
    const std::string& field, bool indexed = true);

// The status a stopped computation answers with.
absl::Status StoppedStatus(PlanOutcome outcome, const char* what, int64_t budget,
                           const char* budget_source);

template <typename Call>
void FinishFleetCall(Call& call, const absl::Status& status, std::string_view outcome) {
  LogRequest(Call::kRpc, call.request->map(), absl::StrFormat("outcome=%s", outcome), status,
             call.received);
  call.reactor->Finish(ToGrpcStatus(status));
}

// Submits a prepared call whose work is `work`.
template <typename Call, typename Work>
grpc::ServerUnaryReactor* Admit(const PlanDeps& deps, std::shared_ptr<Call> call,
                                const absl::Status& prepared, Work work,
                                const char* failed) {
  auto job = std::make_unique<CallJob<Call>>(
      call,
      [work = std::move(work)](Call& c, SearchScratch&) -> Verdict {
        absl::Status s = work(c);
        return {s, s.ok() ? "OK" : "ERROR"};
      },
      &FinishFleetCall<Call>, JobFailureText{"out of memory", failed});
  return AdmitUnaryCall(deps.pool, std::move(call), prepared, std::move(job),
                        &FinishFleetCall<Call>);
}

}  // namespace pathd::server

#endif  // PATHD_SERVER_RPC_FLEET_COMMON_H_
