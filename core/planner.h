// The planner interface every algorithm implements, its request and result
// value types, the stop condition, and the name -> factory registry.
#ifndef PATHD_CORE_PLANNER_H_
#define PATHD_CORE_PLANNER_H_

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "core/cost_model.h"
#include "core/grid.h"
#include "core/search_scratch.h"

namespace pathd {

// One planning query.
struct PlanRequest {
  Cell start;
  Cell goal;
  CostParams cost;
};

// Why a search ended. kFound and kNoPath are answers; the rest mean the stop
// condition fired first.
enum class PlanOutcome { kFound, kNoPath, kExpansionLimit, kTimeout, kCancelled };

std::string_view PlanOutcomeName(PlanOutcome outcome);

struct PlanResult {
  PlanOutcome outcome = PlanOutcome::kNoPath;
  // Start to goal inclusive; empty unless outcome == kFound.
  std::vector<Cell> path;
  // Sum of step costs under the cost model.
  double cost = 0.0;
  // Geometric length: 1 per straight move, sqrt(2) per diagonal.
  double length = 0.0;
  int64_t expansions = 0;
  absl::Duration planning_time;
  bool found() const { return outcome == PlanOutcome::kFound; }
};

// Deadline, cancellation and expansion budget as one condition, polled by
// every search loop every kPollInterval expansions (and at the budget).
// Thread-compatible; the cancel flag may be set from any thread.
class StopCondition {
 public:
  static constexpr int64_t kPollInterval = 1024;

  StopCondition() = default;
  StopCondition(absl::Time deadline, const std::atomic<bool>* cancelled,
                int64_t max_expansions)
      : deadline_(deadline), cancelled_(cancelled), max_expansions_(max_expansions) {}

  static StopCondition None() { return StopCondition(); }

  // Returns the outcome to stop with, or kFound meaning "keep going". Cheap
  // enough to call every expansion; only reads the clock every kPollInterval.
  PlanOutcome Check(int64_t expansions) const {
    if (max_expansions_ > 0 && expansions >= max_expansions_) {
      return PlanOutcome::kExpansionLimit;
    }
    if ((expansions & (kPollInterval - 1)) != 0) return PlanOutcome::kFound;
    return CheckNow();
  }
  // Checks cancellation and the deadline now.
  PlanOutcome CheckNow() const;

  absl::Time deadline() const { return deadline_; }
  int64_t max_expansions() const { return max_expansions_; }

 private:
  absl::Time deadline_ = absl::InfiniteFuture();
  const std::atomic<bool>* cancelled_ = nullptr;
  int64_t max_expansions_ = 0;
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
  // One line for --help and the README.
  std::string_view description;
};

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

// INVALID_ARGUMENT naming "start" or "goal" when one is off the grid or on a
// cell that is not traversable under request.cost, or naming the field when
// the cost parameters are invalid (weight negative or not finite,
// connectivity not 4/8) or the grid is empty or too large to search.
absl::Status ValidateEndpoints(const Grid& grid, const PlanRequest& request);

// Measures a cell path: every consecutive pair must be a legal move (adjacent
// under the connectivity, traversable, no corner cutting).
PathMeasure MeasurePath(const Grid& grid, const std::vector<Cell>& path,
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
