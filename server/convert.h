// Translation between the pathd.v1 wire types and core's value types. The
// server is the only place that does this, so core never sees protobuf and
// every field check (with the field's name in the message) lives here.
#ifndef PATHD_SERVER_CONVERT_H_
#define PATHD_SERVER_CONVERT_H_

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "core/kinematics/footprint.h"
#include "core/kinematics/pose.h"
#include "core/map/grid.h"
#include "core/planning/plan_query.h"
#include "core/search/endpoints.h"
#include "core/search/planner.h"
#include "pathd/v1/common.pb.h"
#include "pathd/v1/map_service.pb.h"
#include "pathd/v1/planner_service.pb.h"
#include "server/map_store.h"

namespace pathd::server {

inline v1::Cell ToProto(Cell c) {
  v1::Cell out;
  out.set_x(c.x);
  out.set_y(c.y);
  return out;
}
inline Cell FromProto(const v1::Cell& c) { return Cell{c.x(), c.y()}; }

// The cell a request position denotes. A cell is passed through unchecked
// (ValidateEndpoints reports it off the map); a world point is converted with
// Grid::WorldToCell. INVALID_ARGUMENT naming `what` ("start"/"goal") when the
// position is unset, or the world point is not finite or off the map (with
// its EndpointFault when `what` is "start" or "goal").
absl::StatusOr<Cell> CellFromPosition(const v1::Position& position,
                                      const Grid& grid, std::string_view what);

// ---- robots with shape and kinematics (convert_kinematic.cc) ----

struct WireQuery;

// The frame of every world coordinate pathd answers in (Nav2's global
// frame).
inline constexpr char kFrameId[] = "map";

// A request position as a pose in cell coordinates, and whether it carried a
// heading (a world or cell pose) rather than only a place.
struct PositionPose {
  Pose pose;
  bool has_yaw = false;
};

// The exact pose a position denotes: a cell's centre, a world point (its
// cell coordinates, heading 0), a world pose (heading turned into the grid
// frame, less Grid::frame_yaw) or a cell pose. INVALID_ARGUMENT naming
// `what` when unset, not finite, or off the map (with its EndpointFault).
absl::StatusOr<PositionPose> PoseFromPosition(const v1::Position& position, const Grid& grid,
                                              std::string_view what);

// options.footprint in cells (metres divided by the resolution), nullopt
// when unset. INVALID_ARGUMENT "options.footprint: ..." naming the problem
// (not exactly one shape, a bad polygon, larger than the map).
absl::StatusOr<std::optional<Footprint>> FootprintFromOptions(const v1::PlanOptions& options,
                                                              const Grid& grid);

// The kinematic part of a decoded query. For a kinematic planner (PlannerTraits::
// kinematic): query->request.kinematic from the exact start and goal poses
// (a missing start heading faces the goal; a missing goal heading lets the
// path end at any heading unless goal_yaw_tolerance says otherwise), the
// footprint (else the robot radius as a circle, else a point), the motion
// model, turning radius (default 0.4 m, at least a cell), penalties, the goal
// tolerances (goal_tolerance becomes the position tolerance and stops being
// a blocked-goal substitute), lattice and smoothing; the robot radius is
// folded into the footprint. For other planners: a footprint without a robot
// radius sets robot_radius_cells to its inscribed radius. Errors name the
// option.
absl::Status DecodeKinematics(const WireQuery& wire, const Grid& grid, PlanQuery* query);

// The path as poses (cell and world frame, headings) into response->poses,
// world_poses and, when any pose reverses, reverse: a kinematic planner's
// own poses, else the path's cell centres or polyline vertices each facing
// the next.
void FillPoses(const PlanResult& result, const Grid& grid, v1::PlanResponse* response);

// Cost model parameters from request options. INVALID_ARGUMENT for an unknown
// connectivity, or a cost_weight that is negative or not finite. An unset
// cost_weight means 1.0.
absl::StatusOr<CostParams> CostParamsFromOptions(const v1::PlanOptions& options);

// The expansion budget for a request: options.max_expansions capped by the
// server's limit (0 = none on either side). INVALID_ARGUMENT when negative.
absl::StatusOr<int64_t> EffectiveMaxExpansions(const v1::PlanOptions& options,
                                               int64_t server_limit);

// Everything in PlanOptions except the expansion budget and robot radius:
// cost parameters, heuristic weight (unset: 1.5), look-ahead, cost-to-go,
// potential-field parameters (0 keeps each default), ant-colony and
// reaction-diffusion parameters (unset keeps each default). INVALID_ARGUMENT
// naming the field for a bad value.
absl::Status PlanOptionsToRequest(const v1::PlanOptions& options, PlanRequest* request);

// options.ant_colony / options.reaction_diffusion into `params` (which hold
// the defaults): set fields replace them, then the whole is validated;
// INVALID_ARGUMENT names the field as options.ant_colony.NAME.
absl::Status AntColonyFromOptions(const v1::AntColonyOptions& options,
                                  AntColonyParams* params);
absl::Status ReactionDiffusionFromOptions(const v1::ReactionDiffusionOptions& options,
                                          ReactionDiffusionParams* params);

// The robot radius in cells (0 when unset): robot_radius_cells as given, or
// robot_radius_m / resolution, capped at the map's diagonal. INVALID_ARGUMENT
// naming the field when negative or not finite.
absl::StatusOr<double> RobotRadiusCells(const v1::PlanOptions& options,
                                        const Grid& grid);

// The minimum clearance in cells (0 when unset): min_clearance_cells as
// given, or min_clearance_m / resolution, capped at the map's diagonal.
// INVALID_ARGUMENT naming the field when negative or not finite.
absl::StatusOr<double> MinClearanceCells(const v1::PlanOptions& options,
                                         const Grid& grid);

// Nav2's inflation costs: query->inflation_radius_cells from
// inflation_radius_cells as given or inflation_radius_m / resolution, capped
// at the map's diagonal (0 when unset or 0: no inflation costs), and
// query->cost_scaling_per_cell = cost_scaling_factor (per metre; unset:
// Nav2's 10) * resolution. Reads query->robot_radius_cells, so it comes
// after the robot radius and the footprint are decoded. INVALID_ARGUMENT
// naming the field when the radius is negative or not finite, smaller than
// the robot radius, or the factor is not finite and > 0.
absl::Status DecodeInflationCost(const v1::PlanOptions& options, const Grid& grid,
                                 PlanQuery* query);

// Largest goal tolerance a request may ask for: the search for a substitute
// goal runs on the gRPC thread and visits up to (2 * 1024 + 1)^2 cells.
inline constexpr double kMaxGoalToleranceCells = 1024.0;

// The goal tolerance in cells (0 when unset): goal_tolerance_cells as given,
// or goal_tolerance_m / resolution. INVALID_ARGUMENT naming the field when
// negative, not finite, or over kMaxGoalToleranceCells.
absl::StatusOr<double> GoalToleranceCells(const v1::PlanOptions& options,
                                          const Grid& grid);

// Least default reach of options.snap_start, cells.
inline constexpr double kDefaultSnapStartCells = 2.0;

// options.snap_start into query->snap_start, snap_start_max_cells (unset or
// 0: twice the robot radius, at least kDefaultSnapStartCells; at most
// kMaxGoalToleranceCells) and requested_start (query->request.start, so it
// comes after the start and the robot radius are decoded). INVALID_ARGUMENT
// naming snap_start_max_m/_cells when negative, not finite or too large.
absl::Status DecodeSnapStart(const v1::PlanOptions& options, const Grid& grid,
                             PlanQuery* query);

// Registry name of a wire planner value (UNSPECIFIED means A*).
// INVALID_ARGUMENT "unknown planner 17" for a value the enum does not define.
absl::StatusOr<std::string_view> PlannerName(int planner);

// Names where an expansion cap came from, for the messages that report it:
// "--max_expansions" when the server's limit binds, else
// "options.max_expansions".
const char* ExpansionLimitSource(const v1::PlanOptions& options,
                                 int64_t server_limit);

// The parts of a request message a plan query is decoded from, and which
// parts of its PlanOptions the RPC reads. WireQueryOf makes one per request
// type; a null pointer is a part the message does not have.
struct WireQuery {
  const std::string* map = nullptr;
  // v1::Planner; UNSPECIFIED means A*.
  int planner = 0;
  const v1::Position* start = nullptr;
  const v1::Position* goal = nullptr;
  const google::protobuf::RepeatedPtrField<v1::Position>* via = nullptr;
  const v1::PlanOptions* options = nullptr;
  bool allow_partial = false;
  // Every search option (PlanOptionsToRequest, simplify, return_expansions)
  // rather than the cost parameters only (CostParamsFromOptions).
  bool search_options = false;
  bool goal_tolerance = false;
  bool expansion_budget = false;
};
// Plan, PlanStream, PlanBatch items: everything.
WireQuery WireQueryOf(const v1::PlanRequest& request);
// CostToGo: the goal, cost parameters, radius and expansion budget.
WireQuery WireQueryOf(const v1::CostToGoRequest& request);
// IsPathValid: cost parameters and radius (the poses are checked, not
// planned between: is_path_valid.cc decodes them).
WireQuery WireQueryOf(const v1::IsPathValidRequest& request);
// Navigate's open message: endpoints, search options, radius, budget; the
// planner is open.planner, or when unspecified hybrid_astar for options that
// give the robot kinematics (min_turning_radius, motion_model), else
// dstar_lite.
WireQuery WireQueryOf(const v1::NavigateOpen& open);

// The server's limits that decoding applies.
struct QueryLimits {
  // --max_expansions; 0 = none.
  int64_t max_expansions = 0;
  // --max_cost_to_go_cells for a whole field in a Plan response (8 bytes per
  // cell); nullopt: not checked.
  std::optional<int64_t> max_cost_to_go_cells = std::nullopt;
};

// A request decoded against the map it names.
struct DecodedQuery {
  std::shared_ptr<const MapSnapshot> snapshot;
  PlanQuery query;
  // Which setting query.max_expansions came from (ExpansionLimitSource).
  const char* expansion_limit_source = "";
  // options.return_expansions (search_options only).
  bool return_expansions = false;
  // options.path_encoding, checked (BuildPlanResponse's).
  v1::PathEncoding path_encoding = v1::PATH_ENCODING_UNSPECIFIED;
};

// The one decoding of a planning request (Plan, PlanStream, PlanBatch,
// CostToGo, IsPathValid, Navigate). In this order, each error
// INVALID_ARGUMENT naming the field unless said otherwise: the planner
// ("unknown planner 17"), the map (NOT_FOUND from the store), start and goal
// (CellFromPosition), the options (PlanOptionsToRequest or
// CostParamsFromOptions), the robot radius, a whole cost-to-go field over
// limits.max_cost_to_go_cells, the expansion budget, the goal tolerance, the
// number of via points and each via point. Decoding checks fields, not the
// map: endpoint rules are the façade's (CheckPlanQuery).
absl::StatusOr<DecodedQuery> DecodePlanQuery(const WireQuery& wire,
                                             const MapStore& store,
                                             const QueryLimits& limits);

// The one place a PlanResponse is filled (Plan, PlanStream, PlanBatch items,
// Navigate): outcome and reason, start and the goal planned to, the path's
// cells and world centres, cost, length, expansions, time, episodes,
// trajectory, the cost-to-go field (copied once from a shared float field,
// or from result.cost_to_go), legs (a failed leg's reason names the leg),
// expanded cells from query.request.expansion_recorder, and where the plan
// came from (map version, planner, radius, cache hit, repaired cells,
// requested goal). `expansion_limit_source` (empty: none) is appended to an
// expansion-limit reason. `path_encoding` (DecodedQuery::path_encoding)
// says whether the path goes out as path and world_path, as packed_path and
// path_frame (proto/path_codec.h), or both.
void BuildPlanResponse(const PlanQuery& query, const PlanAnswer& answer,
                       std::string_view expansion_limit_source,
                       v1::PathEncoding path_encoding, v1::PlanResponse* response);

// The result part of BuildPlanResponse for callers without a query (the
// request fuzzer): path cells and their world centres, cost, length,
// expansions, time, outcome, and a reason when nothing was found.
// `max_expansions` is the budget that applied, for the reason text.
void FillPlanResponse(const PlanResult& result, const PlanRequest& request,
                      const Grid& grid, int64_t max_expansions,
                      v1::PathEncoding path_encoding, v1::PlanResponse* response);

v1::PlanOutcome ToProto(PlanOutcome outcome);

// The typed reason of a plan request's error status: the attached
// EndpointFault (START/GOAL_OUTSIDE_MAP, START/GOAL_OCCUPIED), else by code:
// INVALID_ARGUMENT and FAILED_PRECONDITION -> INVALID_REQUEST, NOT_FOUND ->
// MAP_NOT_FOUND (the map lookup is the only NOT_FOUND a plan request
// meets), DEADLINE_EXCEEDED -> TIMEOUT, CANCELLED -> CANCELLED; UNSPECIFIED
// for OK and every other code.
v1::PlanOutcome OutcomeOfStatus(const absl::Status& status);

// True for the outcomes that say why a request was rejected
// (START_OUTSIDE_MAP .. MAP_NOT_FOUND).
bool IsRejectionOutcome(v1::PlanOutcome outcome);

// ---- maps (convert_map.cc) ----

// Metadata of one map version.
void FillMapInfo(const MapSnapshot& snapshot, v1::MapInfo* info);

// Update changes in wire order. INVALID_ARGUMENT "change N: ..." for a change
// with neither cell nor rect; bounds and costs are checked by MapStore.
absl::StatusOr<std::vector<MapChange>> MapChangesFromProto(
    const google::protobuf::RepeatedPtrField<v1::CellChange>& changes);

// Resolution for raw and Moving AI maps: 0 means 1.0; otherwise it must be
// finite and > 0 (INVALID_ARGUMENT naming "resolution").
absl::StatusOr<double> ResolutionFromProto(double resolution);
// World pose; every component must be finite (INVALID_ARGUMENT naming it).
absl::StatusOr<GridOrigin> OriginFromProto(const v1::Origin& origin);

// A grid from raw cells, checking width * height == len(cells) before copying
// and refusing maps over the store's --max_map_cells with RESOURCE_EXHAUSTED.
absl::StatusOr<Grid> GridFromRawCells(const v1::RawCells& raw, const MapStore& store);

}  // namespace pathd::server

#endif  // PATHD_SERVER_CONVERT_H_
