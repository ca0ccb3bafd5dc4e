// Table, Nearest, Trip and Isochrone: DecodePlanQuery for the cost options
// and each position checked on the gRPC thread; the planning grid (the
// InflationCache's shaped copy), core/fleet and the response on a worker.
#include "server/rpc/fleet_queries.h"

#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/fleet/isochrone.h"
#include "core/fleet/nearest.h"
#include "core/fleet/table.h"
#include "core/fleet/trip.h"
#include "core/planning/plan_query.h"
#include "core/search/endpoints.h"
#include "core/search/registry.h"
#include "core/status_macros.h"
#include "server/convert.h"
#include "server/request_log.h"
#include "server/rpc/fleet_common.h"
#include "server/rpc/unary_call.h"

namespace pathd::server {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// ---- Table ----

TableMethod MethodFromProto(v1::TableMethod m) {
  switch (m) {
    case v1::TABLE_METHOD_BACKWARD:
      return TableMethod::kBackward;
    case v1::TABLE_METHOD_FORWARD:
      return TableMethod::kForward;
    default:
      return TableMethod::kAuto;
  }
}

// The table on the planning grid, backward fields from the SPM cache.
absl::StatusOr<CostTable> RunTable(InflationCache& inflation, IncrementalCache& cache,
                                   const std::string& map, const FleetQuery& q,
                                   const std::vector<Cell>& sources,
                                   const std::vector<Cell>& destinations, TableMethod method,
                                   const StopCondition& stop, uint64_t* map_version,
                                   const char* source_field = "sources",
                                   const char* destination_field = "destinations") {
  PATHD_ASSIGN_OR_RETURN(std::shared_ptr<const Grid> grid,
                         PlanningGridFor(inflation, q, sources, source_field));
  if (q.query().robot_radius_cells > 0.0 && destinations.data() != sources.data()) {
    PATHD_RETURN_IF_ERROR(
        PlanningGridFor(inflation, q, destinations, destination_field).status());
  }
  *map_version = q.decoded.snapshot->version;
  const PlanQuery& query = q.query();
  FieldProvider fields = [&](Cell goal, const StopCondition& s) -> absl::StatusOr<FieldLookup> {
    const IncrementalCache::Key key{.map = map,
                                    .goal = goal,
                                    .cost = query.request.cost,
                                    .robot_radius_cells = query.robot_radius_cells,
                                    .inflation_radius_cells = query.inflation_radius_cells,
                                    .cost_scaling_per_cell = query.cost_scaling_per_cell,
                                    .min_clearance_cells = query.min_clearance_cells};
    PATHD_ASSIGN_OR_RETURN(IncrementalCache::SpmAnswer answer,
                           cache.GetSpm(key, q.decoded.snapshot, s));
    // A queued repair may have brought the field past the snapshot.
    *map_version = std::max(*map_version, answer.map_version);
    return FieldLookup{answer.outcome, std::move(answer.field), answer.cache_hit,
                       answer.expansions};
  };
  return ComputeTable(grid, query.request.cost, sources, destinations, method, fields, stop);
}

struct TableCall : UnaryCall<v1::TableRequest, v1::TableResponse> {
  static constexpr char kRpc[] = "Table";
  std::optional<FleetQuery> q;
  std::vector<Cell> sources;
  std::vector<Cell> destinations;
};

absl::Status PrepareTable(const PlanDeps& deps, TableCall& call) {
  const v1::TableRequest& r = *call.request;
  if (r.sources_size() == 0) return absl::InvalidArgumentError("sources: give at least one");
  if (r.destinations_size() == 0) {
    return absl::InvalidArgumentError("destinations: give at least one");
  }
  const int64_t entries = int64_t{r.sources_size()} * r.destinations_size();
  if (entries > deps.limits.max_table_entries) {
    return absl::ResourceExhaustedError(absl::StrFormat(
        "%d sources x %d destinations is %d entries; the limit is %d (--max_table_entries)",
        r.sources_size(), r.destinations_size(), entries, deps.limits.max_table_entries));
  }
  PATHD_ASSIGN_OR_RETURN(call.q, DecodeFleetQuery(deps, r.map(), r.options()));
  PATHD_ASSIGN_OR_RETURN(call.sources, DecodeCells(r.sources(), "sources", *call.q));
  PATHD_ASSIGN_OR_RETURN(call.destinations,
                         DecodeCells(r.destinations(), "destinations", *call.q));
  return absl::OkStatus();
}

absl::Status AnswerTable(TableCall& call, InflationCache& inflation, IncrementalCache& cache,
                         int64_t max_message_bytes) {
  const absl::Time started = absl::Now();
  const FleetQuery& q = *call.q;
  const StopCondition stop(call.deadline, &call.cancelled, q.query().max_expansions);
  uint64_t version = 0;
  PATHD_ASSIGN_OR_RETURN(
      const CostTable table,
      RunTable(inflation, cache, call.request->map(), q, call.sources, call.destinations,
               MethodFromProto(call.request->method()), stop, &version));
  if (table.outcome != PlanOutcome::kFound) {
    return StoppedStatus(table.outcome, "table", q.query().max_expansions,
                         q.decoded.expansion_limit_source);
  }
  v1::TableResponse& out = *call.response;
  const double res = q.stored().resolution();
  out.set_map_version(version);
  out.set_method(table.method == TableMethod::kBackward ? v1::TABLE_METHOD_BACKWARD
                                                        : v1::TABLE_METHOD_FORWARD);
  out.set_fields_cached(table.fields_cached);
  out.set_expansions(table.expansions);
  out.set_robot_radius_cells(q.query().robot_radius_cells);
  out.set_robot_radius_m(q.query().robot_radius_cells * res);
  for (const Cell c : call.sources) *out.add_sources() = ToProto(c);
  for (const Cell c : call.destinations) *out.add_destinations() = ToProto(c);
  out.mutable_entries()->Reserve(static_cast<int>(table.entries.size()));
  for (const TableCell& e : table.entries) {
    v1::TableEntry* entry = out.add_entries();
    if (!e.reachable) continue;
    entry->set_reachable(true);
    entry->set_cost(e.cost);
    entry->set_cost_m(e.cost * res);
    entry->set_length(e.length);
    entry->set_length_m(e.length * res);
  }
  out.set_planning_time_us(absl::ToInt64Microseconds(absl::Now() - started));
  if (absl::Status s = CheckResponseSize(out, "table response", max_message_bytes); !s.ok()) {
    out.Clear();
    return s;
  }
  return absl::OkStatus();
}

// ---- Nearest ----

struct NearestCall : UnaryCall<v1::NearestRequest, v1::NearestResponse> {
  static constexpr char kRpc[] = "Nearest";
  std::optional<FleetQuery> q;
  Cell target;
  double yaw = 0.0;
  double max_distance_cells = kMaxGoalToleranceCells;
  std::optional<Footprint> polygon;
};

absl::Status PrepareNearest(const PlanDeps& deps, NearestCall& call) {
  const v1::NearestRequest& r = *call.request;
  PATHD_ASSIGN_OR_RETURN(call.q, DecodeFleetQuery(deps, r.map(), r.options()));
  const Grid& grid = call.q->stored();
  PATHD_ASSIGN_OR_RETURN(const PositionPose pose, PoseFromPosition(r.point(), grid, "point"));
  call.target = Cell{static_cast<int32_t>(std::floor(pose.pose.x)),
                     static_cast<int32_t>(std::floor(pose.pose.y))};
  call.yaw = pose.pose.yaw;
  PATHD_ASSIGN_OR_RETURN(const std::optional<Footprint> footprint,
                         FootprintFromOptions(r.options(), grid));
  if (footprint.has_value() && !footprint->is_circle()) call.polygon = footprint;
  double limit = 0.0;
  const char* field = "";
  if (r.max_distance_case() == v1::NearestRequest::kMaxDistanceM) {
    field = "max_distance_m";
    limit = r.max_distance_m();
  } else if (r.max_distance_case() == v1::NearestRequest::kMaxDistanceCells) {
    field = "max_distance_cells";
    limit = r.max_distance_cells();
  }
  if (!std::isfinite(limit) || limit < 0.0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s %g must be finite and >= 0", field, limit));
  }
  const double cells = r.max_distance_case() == v1::NearestRequest::kMaxDistanceM
                           ? limit / grid.resolution()
                           : limit;
  if (cells > kMaxGoalToleranceCells) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s %g is %g cells; the limit is %g cells", field, limit, cells, kMaxGoalToleranceCells));
  }
  if (cells > 0.0) call.max_distance_cells = cells;
  return absl::OkStatus();
}

absl::Status AnswerNearest(NearestCall& call, InflationCache& inflation) {
  const FleetQuery& q = *call.q;
  const bool unknown_is_free = q.query().request.cost.unknown_is_free;
  std::optional<NearestCell> found;
  v1::NearestResponse& out = *call.response;
  if (call.polygon.has_value()) {
    PATHD_ASSIGN_OR_RETURN(const FootprintChecker checker,
                           FootprintChecker::Create(*call.polygon));
    found = NearestAllowedCell(q.stored(), call.target, call.max_distance_cells,
                               FootprintFits(q.stored(), checker, call.yaw, unknown_is_free));
    out.set_footprint_checked(true);
  } else {
    std::shared_ptr<const Grid> grid = q.decoded.snapshot->grid;
    if (q.query().robot_radius_cells > 0.0) {
      PATHD_ASSIGN_OR_RETURN(grid, inflation.Get(*q.decoded.snapshot,
                                                 GridShape{.robot_radius_cells =
                                                               q.query().robot_radius_cells}));
      out.set_robot_radius_cells(q.query().robot_radius_cells);
    }
    const Grid& g = *grid;
    found = NearestAllowedCell(g, call.target, call.max_distance_cells, [&g, unknown_is_free](Cell c) {
      return Traversable(g.cost(c), unknown_is_free);
    });
  }
  const Grid& grid = q.stored();
  out.set_map_version(q.decoded.snapshot->version);
  out.set_frame_id(kFrameId);
  *out.mutable_requested() = ToProto(call.target);
  if (!found.has_value()) return absl::OkStatus();
  out.set_found(true);
  *out.mutable_cell() = ToProto(found->cell);
  const WorldPoint w = grid.CellCenter(found->cell);
  out.mutable_world()->set_x(w.x);
  out.mutable_world()->set_y(w.y);
  out.set_distance_cells(found->distance);
  out.set_distance_m(found->distance * grid.resolution());
  return absl::OkStatus();
}

// ---- Trip ----

struct TripCall : UnaryCall<v1::TripRequest, v1::TripResponse> {
  static constexpr char kRpc[] = "Trip";
  std::optional<FleetQuery> q;
  std::vector<Cell> stops;
  const Planner* planner = nullptr;
};

absl::Status PrepareTrip(const PlanDeps& deps, TripCall& call) {
  const v1::TripRequest& r = *call.request;
  if (r.waypoints_size() < 2) {
    return absl::InvalidArgumentError(
        absl::StrFormat("waypoints: a trip needs at least 2, not %d", r.waypoints_size()));
  }
  if (r.waypoints_size() > deps.limits.max_trip_stops) {
    return absl::ResourceExhaustedError(
        absl::StrFormat("%d waypoints; the limit is %d (--max_trip_stops)", r.waypoints_size(),
                        deps.limits.max_trip_stops));
  }
  if (r.planner() == v1::PLANNER_SPM || r.planner() == v1::PLANNER_DSTAR_LITE) {
    return absl::InvalidArgumentError(
        "planner: the legs are planned through via points, which the cached planners "
        "(spm, dstar_lite) cannot do; use astar or dijkstra");
  }
  // The planner first: a kinematic one would make the decoder ask for the
  // start and goal poses a trip does not have.
  PATHD_ASSIGN_OR_RETURN(const std::string_view name, PlannerName(r.planner()));
  call.planner = PlannerRegistry::Default().Get(name);
  if (call.planner == nullptr) {
    return absl::UnimplementedError(
        absl::StrFormat("planner '%s' is not available on this server", name));
  }
  if (call.planner->traits().kinematic) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "planner: %s plans between poses, not through via points; use a grid planner",
        name));
  }
  PATHD_ASSIGN_OR_RETURN(call.q, DecodeFleetQuery(deps, r.map(), r.options(), r.planner()));
  PATHD_ASSIGN_OR_RETURN(call.stops, DecodeCells(r.waypoints(), "waypoints", *call.q));
  return absl::OkStatus();
}

TripEnd EndFromProto(v1::TripEnd end) {
  switch (end) {
    case v1::TRIP_END_FIXED_LAST:
      return TripEnd::kFixedLast;
    case v1::TRIP_END_ANY:
      return TripEnd::kAny;
    default:
      return TripEnd::kRoundTrip;
  }
}

absl::Status AnswerTrip(TripCall& call, InflationCache& inflation, IncrementalCache& cache,
                        int64_t max_message_bytes, SearchScratch& scratch) {
  const FleetQuery& q = *call.q;
  v1::TripResponse& out = *call.response;
  const double res = q.stored().resolution();
  const StopCondition stop(call.deadline, &call.cancelled, q.query().max_expansions);
  absl::Time t0 = absl::Now();
  uint64_t version = 0;
  PATHD_ASSIGN_OR_RETURN(const CostTable table,
                         RunTable(inflation, cache, call.request->map(), q, call.stops,
                                  call.stops, TableMethod::kAuto, stop, &version,
                                  "waypoints", "waypoints"));
  if (table.outcome != PlanOutcome::kFound) {
    return StoppedStatus(table.outcome, "trip's table", q.query().max_expansions,
                         q.decoded.expansion_limit_source);
  }
  out.set_table_time_us(absl::ToInt64Microseconds(absl::Now() - t0));
  out.set_map_version(q.decoded.snapshot->version);
  const size_t n = call.stops.size();
  CostMatrix costs(n, std::vector<double>(n, 0.0));
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = 0; j < n; ++j) {
      if (i != j) costs[i][j] = table.at(i, j).reachable ? table.at(i, j).cost : kInf;
    }
  }
  t0 = absl::Now();
  const TripEnd end = EndFromProto(call.request->end());
  absl::StatusOr<TripOrder> order = SolveTrip(costs, end);
  out.set_order_time_us(absl::ToInt64Microseconds(absl::Now() - t0));
  if (!order.ok()) {
    if (!absl::IsFailedPrecondition(order.status())) return order.status();
    // "stop i" is waypoints[i] to the client.
    std::string reason(order.status().message());
    out.set_reason(absl::StrFormat("%s (stops are waypoints[i])", reason));
    return absl::OkStatus();
  }
  for (const int32_t s : order->order) out.add_order(s);
  out.set_cost(order->cost);
  out.set_cost_m(order->cost * res);
  out.set_lower_bound(order->lower_bound);
  out.set_lower_bound_m(order->lower_bound * res);
  out.set_gap(order->lower_bound > 0.0 ? (order->cost - order->lower_bound) / order->lower_bound
                                       : 0.0);
  out.set_exact(order->exact);
  out.set_method(order->method);
  out.set_bound_method(order->bound_method);
  // The legs: start at the first stop, through the others in order, to the
  // last (back to the first for a round trip), as one via-point plan.
  t0 = absl::Now();
  PlanQuery legs = q.query();
  legs.request.start = call.stops[order->order.front()];
  legs.requested_start = legs.request.start;
  std::vector<Cell> rest;
  for (size_t k = 1; k < order->order.size(); ++k) rest.push_back(call.stops[order->order[k]]);
  if (end == TripEnd::kRoundTrip) rest.push_back(call.stops[order->order.front()]);
  legs.request.goal = rest.back();
  legs.requested_goal = legs.request.goal;
  rest.pop_back();
  legs.via = std::move(rest);
  PATHD_RETURN_IF_ERROR(CheckPlanQuery(q.stored(), /*stateful=*/false, &legs));
  const std::shared_ptr<const MapSnapshot>& snapshot = q.decoded.snapshot;
  PlanEngine engine;
  engine.planner = call.planner;
  engine.inflate = [&inflation, &snapshot](const std::shared_ptr<const Grid>&,
                                           const GridShape& shape) {
    return inflation.Get(*snapshot, shape);
  };
  PATHD_ASSIGN_OR_RETURN(
      const PlanAnswer answer,
      RunPlanQuery(legs, PlanSnapshot{snapshot->grid, snapshot->version}, engine, stop, scratch));
  if (answer.result.outcome == PlanOutcome::kCancelled ||
      answer.result.outcome == PlanOutcome::kTimeout) {
    return StoppedStatus(answer.result.outcome, "trip's legs", 0, "");
  }
  BuildPlanResponse(legs, answer, q.decoded.expansion_limit_source, q.decoded.path_encoding,
                    out.mutable_plan());
  out.set_legs_time_us(absl::ToInt64Microseconds(absl::Now() - t0));
  out.set_found(answer.result.found());
  if (!answer.result.found()) out.set_reason(out.plan().reason());
  if (absl::Status s = CheckResponseSize(out, "trip response", max_message_bytes); !s.ok()) {
    out.Clear();
    return s;
  }
  return absl::OkStatus();
}

// ---- Isochrone ----

struct IsochroneCall : UnaryCall<v1::IsochroneRequest, v1::IsochroneResponse> {
  static constexpr char kRpc[] = "Isochrone";
  std::optional<FleetQuery> q;
  Cell start;
  double budget_cells = 0.0;
};

absl::Status PrepareIsochrone(const PlanDeps& deps, IsochroneCall& call) {
  const v1::IsochroneRequest& r = *call.request;
  PATHD_ASSIGN_OR_RETURN(call.q, DecodeFleetQuery(deps, r.map(), r.options()));
  const Grid& grid = call.q->stored();
  double budget = 0.0;
  const char* field = "";
  switch (r.budget_case()) {
    case v1::IsochroneRequest::kBudgetM:
      field = "budget_m";
      budget = r.budget_m();
      break;
    case v1::IsochroneRequest::kBudgetCells:
      field = "budget_cells";
      budget = r.budget_cells();
      break;
    case v1::IsochroneRequest::BUDGET_NOT_SET:
      return absl::InvalidArgumentError("budget_m or budget_cells is required");
  }
  if (!std::isfinite(budget) || budget < 0.0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s %g must be finite and >= 0", field, budget));
  }
  call.budget_cells =
      r.budget_case() == v1::IsochroneRequest::kBudgetM ? budget / grid.resolution() : budget;
  PATHD_ASSIGN_OR_RETURN(call.start, CellFromPosition(r.start(), grid, "start"));
  return ValidateEndpoint(grid, call.start, "start", call.q->query().request.cost);
}

void FillRing(const std::vector<GridCorner>& ring, const Grid& grid, v1::CellRing* cells,
              v1::WorldRing* world) {
  for (const GridCorner& v : ring) {
    v1::CellPoint* c = cells->add_points();
    c->set_x(v.x);
    c->set_y(v.y);
    const WorldPoint w =
        grid.CellPointToWorld(CellPoint{static_cast<double>(v.x), static_cast<double>(v.y)});
    v1::WorldPoint* p = world->add_points();
    p->set_x(w.x);
    p->set_y(w.y);
  }
}

absl::Status AnswerIsochrone(IsochroneCall& call, InflationCache& inflation,
                             int64_t max_message_bytes) {
  const FleetQuery& q = *call.q;
  PATHD_ASSIGN_OR_RETURN(std::shared_ptr<const Grid> grid,
                         PlanningGridFor(inflation, q, {call.start}, "start",
                                         /*indexed=*/false));
  const StopCondition stop(call.deadline, &call.cancelled, q.query().max_expansions);
  const Isochrone iso =
      ComputeIsochrone(*grid, q.query().request.cost, call.start, call.budget_cells, stop);
  if (iso.outcome != PlanOutcome::kFound) {
    return StoppedStatus(iso.outcome, "isochrone", q.query().max_expansions,
                         q.decoded.expansion_limit_source);
  }
  v1::IsochroneResponse& out = *call.response;
  const Grid& stored = q.stored();
  const double res = stored.resolution();
  out.set_map_version(q.decoded.snapshot->version);
  *out.mutable_start() = ToProto(call.start);
  out.set_reachable_cells(iso.reachable_cells);
  out.set_area_m2(static_cast<double>(iso.reachable_cells) * res * res);
  out.set_budget_cells(call.budget_cells);
  out.set_budget_m(call.budget_cells * res);
  out.set_expansions(iso.expansions);
  out.set_frame_id(kFrameId);
  out.set_robot_radius_cells(q.query().robot_radius_cells);
  for (const CellPolygon& p : iso.polygons) {
    v1::IsochronePolygon* polygon = out.add_polygons();
    FillRing(p.exterior, stored, polygon->mutable_exterior(), polygon->mutable_world_exterior());
    for (const auto& hole : p.holes) {
      FillRing(hole, stored, polygon->add_holes(), polygon->add_world_holes());
    }
  }
  if (absl::Status s = CheckResponseSize(out, "isochrone response", max_message_bytes);
      !s.ok()) {
    out.Clear();
    return s;
  }
  return absl::OkStatus();
}

}  // namespace

grpc::ServerUnaryReactor* ServeTable(const PlanDeps& deps, grpc::CallbackServerContext* context,
                                     const v1::TableRequest* request,
                                     v1::TableResponse* response) {
  auto call = StartUnaryCall<TableCall>(context, request, response);
  const absl::Status prepared = PrepareTable(deps, *call);
  return Admit(
      deps, std::move(call), prepared,
      [inflation = &deps.inflation, cache = &deps.cache,
       bytes = deps.limits.max_message_bytes](TableCall& c) {
        return AnswerTable(c, *inflation, *cache, bytes);
      },
      "table failed");
}

grpc::ServerUnaryReactor* ServeNearest(const PlanDeps& deps,
                                       grpc::CallbackServerContext* context,
                                       const v1::NearestRequest* request,
                                       v1::NearestResponse* response) {
  auto call = StartUnaryCall<NearestCall>(context, request, response);
  const absl::Status prepared = PrepareNearest(deps, *call);
  return Admit(
      deps, std::move(call), prepared,
      [inflation = &deps.inflation](NearestCall& c) { return AnswerNearest(c, *inflation); },
      "nearest failed");
}

grpc::ServerUnaryReactor* ServeTrip(const PlanDeps& deps, grpc::CallbackServerContext* context,
                                    const v1::TripRequest* request,
                                    v1::TripResponse* response) {
  auto call = StartUnaryCall<TripCall>(context, request, response);
  const absl::Status prepared = PrepareTrip(deps, *call);
  auto job = std::make_unique<CallJob<TripCall>>(
      call,
      [inflation = &deps.inflation, cache = &deps.cache,
       bytes = deps.limits.max_message_bytes](TripCall& c, SearchScratch& scratch) -> Verdict {
        absl::Status s = AnswerTrip(c, *inflation, *cache, bytes, scratch);
        return {s, s.ok() ? (c.response->found() ? "FOUND" : "NO_TRIP") : "ERROR"};
      },
      &FinishFleetCall<TripCall>, JobFailureText{"out of memory", "trip failed"});
  return AdmitUnaryCall(deps.pool, std::move(call), prepared, std::move(job),
                        &FinishFleetCall<TripCall>);
}

grpc::ServerUnaryReactor* ServeIsochrone(const PlanDeps& deps,
                                         grpc::CallbackServerContext* context,
                                         const v1::IsochroneRequest* request,
                                         v1::IsochroneResponse* response) {
  auto call = StartUnaryCall<IsochroneCall>(context, request, response);
  const absl::Status prepared = PrepareIsochrone(deps, *call);
  return Admit(
      deps, std::move(call), prepared,
      [inflation = &deps.inflation, bytes = deps.limits.max_message_bytes](IsochroneCall& c) {
        return AnswerIsochrone(c, *inflation, bytes);
      },
      "isochrone failed");
}

}  // namespace pathd::server
