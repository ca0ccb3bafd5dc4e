// The planner interface every algorithm implements, its request and result
// value types, the stop condition, and the name -> factory registry.
#ifndef PATHD_CORE_PLANNER_H_
#define PATHD_CORE_PLANNER_H_

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "core/cost_model.h"
#include "core/grid.h"
#include "core/search_scratch.h"

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

// Parameters of the artificial potential field planner (seeds 001/003/004).
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
  // centres that pass line of sight (core/line_of_sight.h) instead of single
  // moves: any-angle planners and simplified paths.
  bool any_angle = false;
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
  bool found() const { return outcome == PlanOutcome::kFound; }
};

// Receives a running search's progress, at most once per interval, from the
// stop condition's polls (so every planner reports without plumbing of its
// own). The first report comes one interval after the first poll, so a search
// that ends sooner reports nothing. Thread-compatible: one search polls it.
class ProgressSink {
 public:
  explicit ProgressSink(absl::Duration interval) : interval_(interval) {}
  virtual ~ProgressSink() = default;

  // Called at every poll; calls Report when the interval has passed since the
  // last report (or the first poll).
  void Poll(int64_t expansions, double best_f);

 protected:
  // `expansions` so far (descent steps for the potential field), `best_f` the
  // smallest key on the open list (NaN when the planner has none), `now` the
  // clock reading that passed the rate limit.
  virtual void Report(int64_t expansions, double best_f, absl::Time now) = 0;

 private:
  const absl::Duration interval_;
  // InfinitePast until the first poll arms it.
  absl::Time next_ = absl::InfinitePast();
};

// Deadline, cancellation and expansion budget as one condition, polled by
// every search loop every kPollInterval expansions (and at the budget).
// Thread-compatible; the cancel flag may be set from any thread.
class StopCondition {
 public:
  static constexpr int64_t kPollInterval = 1024;
  // best_f of a search without an ordered open list.
  static constexpr double kNoKey = std::numeric_limits<double>::quiet_NaN();

  StopCondition() = default;
  // `progress`, when not null, is polled with the search's progress and must
  // outlive the search.
  StopCondition(absl::Time deadline, const std::atomic<bool>* cancelled,
                int64_t max_expansions, ProgressSink* progress = nullptr)
      : deadline_(deadline),
        cancelled_(cancelled),
        max_expansions_(max_expansions),
        progress_(progress) {}

  static StopCondition None() { return StopCondition(); }

  // Returns the outcome to stop with, or kFound meaning "keep going". Cheap
  // enough to call every expansion; only reads the clock every kPollInterval.
  // `best_f` is the smallest open-list key, for progress reports.
  PlanOutcome Check(int64_t expansions, double best_f = kNoKey) const {
    if (max_expansions_ > 0 && expansions >= max_expansions_) {
      return PlanOutcome::kExpansionLimit;
    }
    if ((expansions & (kPollInterval - 1)) != 0) return PlanOutcome::kFound;
    return Poll(expansions, best_f);
  }
  // Checks cancellation and the deadline now.
  PlanOutcome CheckNow() const;
  // CheckNow plus a progress report: for loops that poll on their own
  // schedule (row by row) rather than through Check.
  PlanOutcome Poll(int64_t expansions, double best_f = kNoKey) const {
    if (progress_ != nullptr) progress_->Poll(expansions, best_f);
    return CheckNow();
  }

  // The same deadline and cancel flag with another expansion budget (0:
  // none), for callers that split one budget over several searches.
  StopCondition WithMaxExpansions(int64_t max_expansions) const {
    return StopCondition(deadline_, cancelled_, max_expansions);
  }

  absl::Time deadline() const { return deadline_; }
  int64_t max_expansions() const { return max_expansions_; }

 private:
  absl::Time deadline_ = absl::InfiniteFuture();
  const std::atomic<bool>* cancelled_ = nullptr;
  int64_t max_expansions_ = 0;
  ProgressSink* progress_ = nullptr;
};

// What a planner guarantees, so callers and tests can treat it correctly.
struct PlannerTraits {
  // Returns minimum-cost paths under the cost model.
  bool optimal = false;
  // Minimises the number of moves instead of cost (BFS).
  bool fewest_moves = false;
  // Paths may connect non-adjacent cells (any-angle).
  bool any_angle = false;
  // Keeps state between queries (explicit session objects).
  bool incremental = false;
  // Cost at most heuristic_weight times the optimum (weighted A*).
  bool bounded = false;
  // Interleaves bounded look-ahead searches with moves (RTAA*, LRTA*); the
  // path is the executed trajectory and may revisit cells.
  bool real_time = false;
  // Finds a path whenever one exists (given enough budget). False for the
  // potential field, which can stall in a local minimum.
  bool complete = true;
  // Refuses (FAILED_PRECONDITION) maps whose traversable cells do not all
  // cost the same under the request (JPS).
  bool needs_uniform_cost = false;
  // Refuses (FAILED_PRECONDITION) 4-connected requests (JPS).
  bool needs_eight_connected = false;
  // Can return the full cost-to-go field (PlanRequest::want_cost_to_go).
  bool cost_to_go = false;
  // One line for --help and the README.
  std::string_view description;
};

// "optimal", "fewest moves", "bounded", "any-angle", "real-time" or
// "heuristic": what a planner's paths guarantee, for listings.
std::string_view GuaranteeName(const PlannerTraits& traits);

// A planning algorithm. Plan() is a pure function of the grid, the request and
// scratch memory: an instance holds no per-query state, so one may be shared
// by threads as long as each thread passes its own SearchScratch.
class Planner {
 public:
  virtual ~Planner() = default;
  virtual std::string_view name() const = 0;
  virtual const PlannerTraits& traits() const = 0;

  // Plans from request.start to request.goal. Returns INVALID_ARGUMENT when
  // start or goal is off the grid or not traversable (ValidateEndpoints); a
  // search that ends without a path is an OK result with outcome != kFound.
  virtual absl::StatusOr<PlanResult> Plan(const Grid& grid,
                                          const PlanRequest& request,
                                          const StopCondition& stop,
                                          SearchScratch& scratch) const = 0;
};

// Which endpoint a rejected request got wrong. Validation attaches it to its
// INVALID_ARGUMENT status (as a payload, which survives being passed up
// unchanged), so callers can report a typed reason without parsing messages.
enum class EndpointFault {
  kStartOutsideMap,
  kGoalOutsideMap,
  kStartBlocked,
  kGoalBlocked,
};

// `status` with `fault` attached.
absl::Status WithEndpointFault(absl::Status status, EndpointFault fault);
// The fault attached to `status`, nullopt when none is.
std::optional<EndpointFault> EndpointFaultOf(const absl::Status& status);
// The fault of endpoint `what` ("start" or "goal"; nullopt for any other
// name) being outside the map or blocked.
std::optional<EndpointFault> EndpointFaultFor(std::string_view what, bool outside);

// INVALID_ARGUMENT naming "start" or "goal" when one is off the grid or on a
// cell that is not traversable under request.cost, or naming the field when
// the cost parameters are invalid (weight negative or not finite,
// connectivity not 4/8, heuristic_weight < 1, lookahead < 0, potential-field
// parameters not positive and finite) or the grid is empty or too large to
// search. Endpoint errors carry their EndpointFault.
absl::Status ValidateEndpoints(const Grid& grid, const PlanRequest& request);

// ValidateEndpoints plus the planner's own preconditions from its traits:
// FAILED_PRECONDITION naming the planner and the first weighted cell when it
// needs uniform cost, or when it needs 8-connectivity. Every planner's Plan()
// calls this first.
absl::Status ValidateRequest(const Grid& grid, const PlanRequest& request,
                             std::string_view planner, const PlannerTraits& traits);

// Why two consecutive cells of a path are not one legal move apart.
// Traversability of the cells themselves is not part of it.
enum class MoveFault {
  kNone,
  // The same cell twice, or cells more than one apart in x or y.
  kNotAdjacent,
  // A diagonal move on a 4-connected grid.
  kDiagonalOnFourConnected,
  // A diagonal move with a side cell off the grid or not traversable.
  kCornerCut,
};

// "not adjacent", "diagonal on a 4-connected grid", "cuts a corner" ("legal"
// for kNone), for messages.
std::string_view MoveFaultName(MoveFault fault);

// The move rule every planner's neighbour generation follows, for checking
// given paths: the fault of the move a -> b, kNone when it is legal.
MoveFault CheckMove(const Grid& grid, Cell a, Cell b, const CostParams& cost);

// The nearest cell to `target` the robot centre may occupy under `cost`
// (on the grid and Traversable), by the Euclidean distance between cell
// centres, at most `max_distance` cells (inclusive); ties go to the smaller
// y, then the smaller x. `target` itself when it qualifies; nullopt when no
// cell does. Visits rings of growing Chebyshev radius and stops once no
// further ring can be nearer, so the cost is O(d^2) for the answer's distance
// d, O(max_distance^2) when there is none.
std::optional<Cell> NearestTraversableCell(const Grid& grid, Cell target,
                                           double max_distance,
                                           const CostParams& cost);

// Measures a cell path: every consecutive pair must be a legal move (adjacent
// under the connectivity, traversable, no corner cutting).
PathMeasure MeasurePath(const Grid& grid, const std::vector<Cell>& path,
                        const CostParams& cost);

// Measures an any-angle path: every consecutive pair must have line of sight
// (core/line_of_sight.h); cost sums SegmentCost, length the Euclidean lengths.
PathMeasure MeasureAnyAnglePath(const Grid& grid, const std::vector<Cell>& path,
                                const CostParams& cost);

// MeasureAnyAnglePath when result.any_angle, else MeasurePath.
PathMeasure MeasureResultPath(const Grid& grid, const PlanResult& result,
                              const CostParams& cost);

// Name -> factory registry. Thread-safe after start-up: registration happens
// in RegisterBuiltinPlanners() before any lookup.
class PlannerRegistry {
 public:
  using Factory = std::function<std::unique_ptr<Planner>()>;

  // The process-wide registry with every built-in planner registered.
  static const PlannerRegistry& Default();

  // Registers a planner under its name(); fails with ALREADY_EXISTS on a
  // duplicate name.
  absl::Status Register(Factory factory);

  // Creates the planner called `name`; NOT_FOUND lists the known names.
  absl::StatusOr<std::unique_ptr<Planner>> Create(std::string_view name) const;
  // A shared instance (planners are stateless), or nullptr for unknown names.
  const Planner* Get(std::string_view name) const;
  // Registered names, sorted.
  std::vector<std::string> Names() const;

 private:
  std::vector<std::unique_ptr<Planner>> planners_;
  std::vector<Factory> factories_;
};

}  // namespace pathd

#endif  // PATHD_CORE_PLANNER_H_
