// The value types of one planning query: the request with its options, the
// outcome and the result, and the recorder of expanded cells.
#ifndef PATHD_CORE_SEARCH_PLAN_TYPES_H_
#define PATHD_CORE_SEARCH_PLAN_TYPES_H_

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
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

// Parameters of the ant_colony planner: Dorigo & Gambardella's Ant Colony
// System ("Ant colony system: a cooperative learning approach to the
// traveling salesman problem", IEEE TEC 1997) on the grid graph
// (core/planners/nature/ant_colony.h). ValidateAntColonyParams says what is
// refused.
struct AntColonyParams {
  // Ants walking per iteration.
  int32_t ants = 20;
  // Iterations at most.
  int32_t iterations = 100;
  // Stop once this many iterations in a row have not improved the best path;
  // 0: never stop early.
  int32_t stall_iterations = 25;
  // Exponent of the pheromone in the transition rule.
  double alpha = 1.0;
  // Exponent of the desirability eta (Dorigo & Gambardella's 2).
  double beta = 2.0;
  // Global evaporation rho on the best path's edges, in (0, 1].
  double rho = 0.1;
  // Local evaporation xi on every edge an ant takes, in (0, 1].
  double xi = 0.1;
  // Probability of the greedy (exploiting) choice, in [0, 1].
  double q0 = 0.9;
  // Initial pheromone tau0 > 0; 0: 1 / (ants * octile(start, goal)), the
  // paper's 1 / (n * L_nn) with the octile distance for L_nn.
  double tau0 = 0.0;
  // Moves an ant may make before it is given up (0: 4 * (width + height)).
  int64_t max_steps = 0;
  // Seed of the pseudo-random choices: one seed, one answer.
  uint64_t seed = 1;
};

// What an ant_colony run did; filled by that planner only.
struct AntColonyStats {
  int32_t iterations_run = 0;
  // The 1-based iteration whose ant found the best path returned: no later
  // iteration found a cheaper one ("iterations to convergence"); 0 when no
  // ant reached the goal.
  int32_t best_iteration = 0;
  int64_t ants_reached_goal = 0;
  // Ants stuck with every neighbour visited or blocked, or out of steps.
  int64_t ants_died = 0;
  // Cost of the best path found (+inf when none).
  double best_cost = 0.0;
  // Why the iterations ended: "iterations", "stalled", or the stop
  // condition's outcome name.
  std::string stopped_by;
};

// Parameters of the reaction_diffusion planner
// (core/planners/nature/reaction_diffusion.h): the bistable Nagumo
// equation du/dt = D lap(u) + k u (1 - u) (u - a) on the free cells, started
// at the goal. ValidateReactionDiffusionParams says what is refused.
struct ReactionDiffusionParams {
  // Diffusion coefficient D, cells^2 per unit time.
  double diffusion = 1.0;
  // Reaction rate k.
  double reaction_rate = 0.5;
  // Excitation threshold a, in (0, 0.5): a cell pushed past it switches to
  // the excited state; the front moves at sqrt(D k / 2) (1 - 2 a) cells per
  // unit time.
  double threshold = 0.1;
  // Explicit Euler time step; dt (10/3 D + k) <= 1 keeps the update stable.
  double time_step = 0.2;
  // Time steps at most (0: enough for the front to cross the map's free
  // cells at the plane-wave speed four times over).
  int64_t max_steps = 0;
};

// How the reaction_diffusion front differs from the exact wave front
// (Dijkstra's cost-to-go on the same costs); filled by that planner only.
struct ReactionDiffusionStats {
  int64_t steps = 0;
  // Cells the front reached (u crossed 1/2) before it stopped.
  int64_t reached_cells = 0;
  // The front's plane-wave speed sqrt(D k / 2) (1 - 2 a), cells per unit time:
  // arrival time T becomes the cost estimate speed * T.
  double front_speed = 0.0;
  // Over reached cells other than the goal: |speed * T - d| / d with d the
  // exact cost-to-go, the largest and the mean.
  double max_relative_error = 0.0;
  double mean_relative_error = 0.0;
  // Exact optimum from start to goal (+inf when unreachable), and the
  // returned path's cost over it (0 when no path).
  double optimal_cost = 0.0;
  double cost_ratio = 0.0;
  // Moves of the path that do not descend T: climbs out of the shallow pits
  // the lattice leaves in the arrival time (reaction_diffusion.cc).
  int64_t escapes = 0;
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
  AntColonyParams ant_colony;
  ReactionDiffusionParams reaction_diffusion;
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
  // Filled by ant_colony / reaction_diffusion only.
  std::optional<AntColonyStats> ant_colony;
  std::optional<ReactionDiffusionStats> reaction_diffusion;
  // Why a search ended without a path, in words, when the outcome alone
  // would mislead (ant_colony: no ant reached a goal that may be
  // reachable); the server's reason then. Empty otherwise.
  std::string reason;
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
