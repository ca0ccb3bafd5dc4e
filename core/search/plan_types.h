// The value types of one planning query: the request with its options, the
// outcome and the result, and the recorder of expanded cells.
#ifndef PATHD_CORE_SEARCH_PLAN_TYPES_H_
#define PATHD_CORE_SEARCH_PLAN_TYPES_H_

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "absl/time/time.h"
#include "core/kinematics/pose.h"
#include "core/kinematics/vehicle.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/derived.h"

namespace pathd {

// Attractive potential shape of the potential-field planner.
enum class AttractiveShape {
  // U = 1/2 k d^2 within switch_distance, conic (k * switch_distance * d - ...)
  // beyond it, so the pull does not grow without bound far from the goal
  // (Choset's combined quadratic/conic potential).
  kQuadratic,
  // U = k d everywhere: constant pull.
  kConic,
};

// Parameters of the artificial potential field planner (Khatib 1986; Choset
// et al., "Principles of Robot Motion", ch. 4).
// Distances are in cells.
struct PotentialFieldParams {
  AttractiveShape attractive = AttractiveShape::kQuadratic;
  // Attractive gain k_att.
  double attractive_gain = 1.0;
  // Distance to the goal where the quadratic potential turns conic.
  double switch_distance = 10.0;
  // Repulsive gain eta: U_rep = 1/2 eta (1/d - 1/Q*)^2 for d <= Q*. With
  // eta = 10, Q* = 3 the descent reached the goal in 1211 of 4800 Moving AI
  // scenarios (400 on each of 12 maps), against 1147 with eta = 100, Q* = 4
  // and 1089 with eta = 5: a stronger push closes narrow passages, a weaker
  // one lets the pull drive the robot into obstacles.
  double repulsive_gain = 10.0;
  // Influence distance Q* of obstacles, between cell centres.
  double influence_distance = 3.0;
  // Gradient descent step, cells.
  double step_size = 0.5;
  // Give up (EXPANSION_LIMIT) after this many descent steps; 0: 4 * (width +
  // height) / step_size, and at least 8 stall-test windows on small maps.
  int64_t max_steps = 0;
};

// Collects the cells a search expands (takes from its open list or queue to
// close), in expansion order, up to a cap, so tools can draw what a search
// touched. Not thread-safe: one per query. A PlanRequest points to one only
// when the caller asked; the best-first loop checks the pointer once per
// search, the other loops once per expansion.
class ExpansionRecorder {
 public:
  explicit ExpansionRecorder(size_t max_cells) : max_cells_(max_cells) {}

  // Appends `cell`, or notes the truncation once the cap is reached.
  void Record(Cell cell) {
    if (cells_.size() < max_cells_) {
      cells_.push_back(cell);
    } else {
      truncated_ = true;
    }
  }
  const std::vector<Cell>& cells() const { return cells_; }
  // More cells were expanded than the cap let through.
  bool truncated() const { return truncated_; }

 private:
  size_t max_cells_;
  std::vector<Cell> cells_;
  bool truncated_ = false;
};

// One planning query.
struct PlanRequest {
  Cell start;
  Cell goal;
  CostParams cost;
  // Weighted A*: f = g + w * h with w >= 1; the path costs at most w times
  // the optimum. Other planners ignore it.
  double heuristic_weight = 1.0;
  // Real-time planners (RTAA*, LRTA*): expansions of each search episode
  // (>= 1); 0 means the planner's default.
  int32_t lookahead = 0;
  // Planners with PlannerTraits::cost_to_go fill PlanResult::cost_to_go.
  bool want_cost_to_go = false;
  PotentialFieldParams potential;
  // Not owned; null: record nothing. When set, the planners that search cell
  // by cell record every expansion here (one cell per unit of
  // PlanResult::expansions); the incremental planners (lpa_star, dstar_lite,
  // spm), the raster distance_transform and potential_field record nothing.
  ExpansionRecorder* expansion_recorder = nullptr;
  // Not owned; null: planners that need a structure derived from the map
  // (core/search/derived.h) build it for this query. The server passes its
  // per-version cache.
  DerivedStore* derived = nullptr;
  // Kinematic planners (PlannerTraits::kinematic): the exact poses, the
  // footprint and the motion model; start and goal above are the cells of
  // its poses. Null for every other planner.
  std::shared_ptr<const KinematicQuery> kinematic;

  // A request with every option at its default.
  static PlanRequest Between(Cell start, Cell goal, CostParams cost = {}) {
    PlanRequest r;
    r.start = start;
    r.goal = goal;
    r.cost = cost;
    return r;
  }
};

// Why a search ended. kFound and kNoPath are answers; kLocalMinimum is the
// potential field's "stuck" (descent stalled away from the goal); the rest
// mean the stop condition fired first.
enum class PlanOutcome {
  kFound,
  kNoPath,
  kExpansionLimit,
  kTimeout,
  kCancelled,
  kLocalMinimum,
};

std::string_view PlanOutcomeName(PlanOutcome outcome);

struct PlanResult {
  PlanOutcome outcome = PlanOutcome::kNoPath;
  // Start to goal inclusive; empty unless outcome == kFound. Consecutive cells
  // are one legal move apart, unless any_angle is set.
  std::vector<Cell> path;
  // Consecutive path cells are joined by straight segments between their
  // centres that pass line of sight (core/search/line_of_sight.h) instead of single
  // moves: any-angle planners and simplified paths.
  bool any_angle = false;
  // Geometric planners (PlannerTraits::geometric): the path as an exact
  // polyline in cell coordinates, from the start cell's centre to the goal
  // cell's centre, bending only at obstacle corners, clear under the free
  // space rule of core/geometry/free_space.h (it may touch obstacle
  // boundaries, which line of sight does not allow). `path` then lists the
  // cells the polyline crosses, in order (consecutive cells share an edge or
  // a corner and need not be legal moves), any_angle is false, and length
  // and cost are the polyline's. Empty for every other planner.
  std::vector<CellPoint> polyline;
  // Kinematic planners: the path as poses with headings, in cell
  // coordinates, from the start pose to the pose that meets the goal, close
  // enough together (at most a cell apart) to be followed as they are; `path`
  // lists the cells of those poses, deduplicated, and length is the
  // poses' arc length. Empty for every other planner.
  std::vector<PathPose> poses;
  // The smallest clearance, in cells, of the path's cells. Plans with a
  // minimum clearance (PlanQuery::min_clearance_cells): the Euclidean
  // distance from a cell's centre to the nearest blocked or off-map cell's
  // centre (core/map/clearance.h, PathClearance). The voronoi planner
  // otherwise: the octile distance (steps of 1 and sqrt(2)) its distance map
  // keeps (core/geometry/voronoi.h says why octile; it reads up to 8.3%
  // above the Euclidean distance). Negative when not computed.
  double min_clearance = -1.0;
  // Cost under the cost model: sum of step costs, or of SegmentCost() for
  // any-angle paths.
  double cost = 0.0;
  // Geometric length in cells: 1 per straight move, sqrt(2) per diagonal, or
  // the Euclidean length of any-angle segments.
  double length = 0.0;
  int64_t expansions = 0;
  // Real-time planners: search episodes run (one per look-ahead search).
  int64_t episodes = 0;
  // Potential field: the continuous descent trajectory, start to where it
  // ended; `path` holds the cells it passes through.
  std::vector<CellPoint> trajectory;
  // kLocalMinimum: where the descent stalled.
  CellPoint stall_point;
  // When requested and supported: cost-to-go to the goal of every cell,
  // row-major; +infinity for cells that cannot reach it.
  std::vector<double> cost_to_go;
  absl::Duration planning_time;
  // kTimeout or kCancelled while the planner was building (or waiting for
  // another query's build of) a structure derived from the map, not
  // searching: what it was doing, for the caller's message ("building the
  // visibility graph of this map version (49154 vertices)"). Empty otherwise.
  std::string stopped_while;
  bool found() const { return outcome == PlanOutcome::kFound; }
};

}  // namespace pathd

#endif  // PATHD_CORE_SEARCH_PLAN_TYPES_H_
