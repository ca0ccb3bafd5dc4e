// LpaStar, DStarLite and ShortestPathMap over the one incremental search of
// core/incremental/engine.h: validation, the start/goal bookkeeping of each,
// path extraction and the shortest path map's repair-or-rebuild rule.
#include "core/search/path_measure.h"
#include "core/search/endpoints.h"
#include "core/incremental/incremental_search.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/incremental/engine.h"
#include "core/status_macros.h"

namespace pathd {
namespace {

using internal::FieldConfig;
using internal::FocusedConfig;
using internal::IncrementalSearch;
using internal::MoveRules;

using LpaSearch = IncrementalSearch<FocusedConfig<true>>;
using DStarSearch = IncrementalSearch<FocusedConfig<false>>;
using FieldSearch = IncrementalSearch<FieldConfig>;

constexpr double kInf = std::numeric_limits<double>::infinity();

// Repair or rebuild (ShortestPathMap::UpdateMap). A repair costs more per
// expanded cell than a build (hash-map rhs, rescans of underconsistent cells,
// lazy heap duplicates), and how many cells it expands depends on the shape of
// the change more than on its size. Measured with `replan_bench --threshold`
// (tests/bench/replan_bench.cc; goal in the middle; medians of 5; repair time
// over rebuild time):
//   random 1024 x 1024, 20% obstacles (rebuild 114 ms, 1.05 M expansions):
//     k scattered toggles   256: 0.34   1024: 1.95   4096: 4.7
//     k-cell square cluster 4096: 0.06  16384: 0.42  65536: 0.94  262144: 7.6
//   dao/brc202d (rebuild 4.2 ms):
//     k scattered toggles   256: 0.06   1024: 1.36   4096: 6.3
//     k-cell square cluster 4096: 0.38  16384: 7.9
// Scattered changes cross over at 0.05-0.3% of the cells, clusters at 2-6%, so
// no one fraction fits both. Two rules instead:
// 1. More than kRebuildFraction of the cells changed: rebuild at once (every
//    pattern measured is dearer to repair there, or nearly as dear).
constexpr double kRebuildFraction = 0.05;
// 2. Otherwise repair, but give up and rebuild once the repair has expanded
//    kRepairBudget times as many cells as the last build did. A repair
//    expansion costs several times a build expansion (3-8x on the random map,
//    far more on dao/brc202d), so the budget is where a repair has roughly
//    spent what a rebuild costs (ski rental: at worst about twice the better
//    choice, and small repairs never notice). Deterministic, unlike a time
//    limit. 0.2 was tried first: UpdateMap then cost up to 5.7x a rebuild
//    (brc202d, 4096 scattered cells). With 0.05, in the same runs
//    (`replan_bench --threshold --maps dao/brc202d.map,street/Berlin_0_512.map`),
//    UpdateMap took the repair's time below the crossover and at most 1.4x a
//    rebuild beyond it (random map: scattered 1024 1.37x, cluster 16384
//    1.14x; brc202d at most 1.09x; Berlin at most 1.09x), where plain repairs
//    cost up to 18x.
constexpr double kRepairBudget = 0.05;
// Small maps rebuild in microseconds; let their repairs run.
constexpr int64_t kMinRepairBudget = 256;

// A float field orders costs exactly only while float(g + 1) > g.
constexpr double kFieldCostLimit = 16777216.0;  // 2^24

absl::Status CheckGrid(const std::shared_ptr<const Grid>& grid) {
  if (grid == nullptr) return absl::InvalidArgumentError("no map given");
  return absl::OkStatus();
}

// ValidateEndpoints' checks for a search that has only a goal (D* Lite, the
// shortest path map): the goal named as such, then the grid and cost
// parameters.
absl::Status ValidateGoal(const Grid& grid, Cell goal, const CostParams& cost) {
  if (!grid.InBounds(goal)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("goal %s is outside the %d x %d map", CellToString(goal),
                        grid.width(), grid.height()));
  }
  if (!Traversable(grid.cost(goal), cost.unknown_is_free)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("goal %s is on a blocked cell (cost %d)", CellToString(goal),
                        grid.cost(goal)));
  }
  return ValidateEndpoints(grid, PlanRequest::Between(goal, goal, cost));
}

// UpdateMap's preconditions: a map of the same size, every changed cell on it.
absl::Status ValidateUpdate(const Grid& current, const std::shared_ptr<const Grid>& grid,
                            absl::Span<const Cell> changed) {
  PATHD_RETURN_IF_ERROR(CheckGrid(grid));
  if (grid->width() != current.width() || grid->height() != current.height()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "the new map is %d x %d but the search state is for %d x %d",
        grid->width(), grid->height(), current.width(), current.height()));
  }
  for (const Cell c : changed) {
    if (!grid->InBounds(c)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("changed cell %s is outside the %d x %d map",
                          CellToString(c), grid->width(), grid->height()));
    }
  }
  return absl::OkStatus();
}

bool Blocked(const Grid& grid, Cell c, const CostParams& cost) {
  return !Traversable(grid.cost(c), cost.unknown_is_free);
}

// Fills path, cost and length, measured exactly on the grid. `expected` is
// the search's own cost of the path (NaN to skip the comparison): a path that
// is not a legal move chain or does not cost what the search says means the
// state is broken.
absl::Status SetPath(const Grid& grid, const CostParams& cost, std::vector<Cell> path,
                     double expected, PlanResult* result) {
  const PathMeasure m = MeasurePath(grid, path, cost);
  if (!m.valid) {
    return absl::InternalError(absl::StrFormat(
        "incremental search state broken: extracted path has an illegal step "
        "at %s",
        CellToString(path[m.first_invalid])));
  }
  if (!std::isnan(expected) &&
      std::abs(m.cost - expected) > 1e-9 * (1.0 + expected)) {
    return absl::InternalError(absl::StrFormat(
        "incremental search state broken: the path from %s costs %.12g but g "
        "says %.12g",
        CellToString(path.front()), m.cost, expected));
  }
  result->outcome = PlanOutcome::kFound;
  result->path = std::move(path);
  result->cost = m.cost;
  result->length = m.length;
  return absl::OkStatus();
}

absl::Status StopStatus(PlanOutcome why, int64_t expansions) {
  const std::string what = absl::StrFormat(
      "shortest path map build stopped after %d expansions", expansions);
  switch (why) {
    case PlanOutcome::kTimeout:
      return absl::DeadlineExceededError(what + ": deadline");
    case PlanOutcome::kCancelled:
      return absl::CancelledError(what + ": cancelled");
    default:
      return absl::ResourceExhaustedError(what + ": expansion budget");
  }
}

// Every finite cost-to-go is below the float limit. Checked over the whole
// field after each build, O(cells); repairs are not checked (a repair that
// pushes costs past 2^24 makes the descent guard report INTERNAL instead).
absl::Status CheckFieldRange(const FieldSearch& search) {
  for (const float v : search.store().field()) {
    if (v != std::numeric_limits<float>::infinity() && v >= kFieldCostLimit) {
      return absl::OutOfRangeError(absl::StrFormat(
          "a cost-to-go reaches %g, beyond the %g a float field orders exactly",
          static_cast<double>(v), kFieldCostLimit));
    }
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<std::vector<Cell>> ChangedCells(const Grid& before, const Grid& after) {
  if (before.width() != after.width() || before.height() != after.height()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "maps differ in size: %d x %d and %d x %d", before.width(), before.height(),
        after.width(), after.height()));
  }
  std::vector<Cell> changed;
  const std::vector<uint8_t>& a = before.cells();
  const std::vector<uint8_t>& b = after.cells();
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i] != b[i]) changed.push_back(before.CellAt(i));
  }
  return changed;
}

// ---------------------------------------------------------------------------
// LpaStar

struct LpaStar::State {
  LpaSearch search;
  Cell start;
  Cell goal;
  RepairStats stats;
  // Changed cells applied since the last completed Plan().
  int64_t pending_changed = 0;
};

LpaStar::LpaStar(std::unique_ptr<State> state) : state_(std::move(state)) {}
LpaStar::~LpaStar() = default;

absl::StatusOr<std::unique_ptr<LpaStar>> LpaStar::Create(std::shared_ptr<const Grid> grid,
                                                         Cell start, Cell goal,
                                                         CostParams cost) {
  PATHD_RETURN_IF_ERROR(CheckGrid(grid));
  PATHD_RETURN_IF_ERROR(ValidateEndpoints(*grid, PlanRequest::Between(start, goal, cost)));
  auto state = std::make_unique<State>(
      State{LpaSearch(std::move(grid), cost, MoveRules(), start), start, goal, {}, 0});
  state->search.SetTarget(goal);
  state->search.Reset();
  return std::unique_ptr<LpaStar>(new LpaStar(std::move(state)));
}

absl::Status LpaStar::UpdateMap(std::shared_ptr<const Grid> grid,
                                absl::Span<const Cell> changed) {
  PATHD_RETURN_IF_ERROR(ValidateUpdate(state_->search.grid(), grid, changed));
  state_->search.SwitchGrid(std::move(grid), changed);
  state_->pending_changed += static_cast<int64_t>(changed.size());
  return absl::OkStatus();
}

absl::StatusOr<PlanResult> LpaStar::Plan(const StopCondition& stop) {
  const absl::Time started = absl::Now();
  State& s = *state_;
  PlanResult result;
  result.outcome = PlanOutcome::kNoPath;
  s.stats = RepairStats{0, s.pending_changed, false};
  // A blocked end cannot be reached whatever the search finds; the pending
  // repairs wait in the open list until the map frees it.
  if (!Blocked(s.search.grid(), s.start, s.search.cost()) &&
      !Blocked(s.search.grid(), s.goal, s.search.cost())) {
    const LpaSearch::ComputeEnd end = s.search.Compute(stop);
    s.stats.expansions = end.expansions;
    result.expansions = end.expansions;
    if (end.outcome != PlanOutcome::kFound) {
      result.outcome = end.outcome;
      result.planning_time = absl::Now() - started;
      return result;
    }
    const uint32_t goal = s.search.model().Index(s.goal);
    const double g = s.search.g(goal);
    if (g != kInf) {
      // The search runs forward, so the descent goes from the goal back to
      // the start.
      PATHD_ASSIGN_OR_RETURN(std::vector<Cell> path, s.search.Descend(goal));
      std::reverse(path.begin(), path.end());
      PATHD_RETURN_IF_ERROR(
          SetPath(s.search.grid(), s.search.cost(), std::move(path), g, &result));
    }
  }
  s.pending_changed = 0;
  result.planning_time = absl::Now() - started;
  return result;
}

const RepairStats& LpaStar::last_stats() const { return state_->stats; }
const Grid& LpaStar::grid() const { return state_->search.grid(); }
size_t LpaStar::MemoryBytes() const { return sizeof(State) + state_->search.MemoryBytes(); }
double LpaStar::g(Cell c) const { return state_->search.g(state_->search.model().Index(c)); }
double LpaStar::rhs(Cell c) const {
  return state_->search.rhs(state_->search.model().Index(c));
}

// ---------------------------------------------------------------------------
// DStarLite

struct DStarLite::State {
  DStarSearch search;
  Cell goal;
  // The robot; unset before the first SetStart.
  std::optional<Cell> start;
  RepairStats stats;
  int64_t pending_changed = 0;
};

DStarLite::DStarLite(std::unique_ptr<State> state) : state_(std::move(state)) {}
DStarLite::~DStarLite() = default;

absl::StatusOr<std::unique_ptr<DStarLite>> DStarLite::Create(
    std::shared_ptr<const Grid> grid, Cell goal, CostParams cost) {
  return internal::IncrementalAccess::CreateDStarLite(std::move(grid), goal, cost,
                                                      MoveRules());
}

absl::StatusOr<std::unique_ptr<DStarLite>> internal::IncrementalAccess::CreateDStarLite(
    std::shared_ptr<const Grid> grid, Cell goal, CostParams cost,
    const MoveRules& rules) {
  PATHD_RETURN_IF_ERROR(CheckGrid(grid));
  PATHD_RETURN_IF_ERROR(ValidateGoal(*grid, goal, cost));
  auto state = std::make_unique<DStarLite::State>(DStarLite::State{
      DStarSearch(std::move(grid), cost, rules, goal), goal, std::nullopt, {}, 0});
  state->search.Reset();
  return std::unique_ptr<DStarLite>(new DStarLite(std::move(state)));
}

absl::Status DStarLite::SetStart(Cell start) {
  State& s = *state_;
  if (!s.search.grid().InBounds(start)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "start %s is outside the %d x %d map", CellToString(start),
        s.search.grid().width(), s.search.grid().height()));
  }
  if (!s.start.has_value()) {
    // The keys so far were computed without a start to focus on: start over
    // (nothing has been searched yet, only map updates applied).
    s.search.SetTarget(start);
    s.search.Reset();
  } else {
    // km keeps the old keys lower bounds of the new ones (h is consistent),
    // so the open list need not be re-sorted.
    s.search.AddKm(s.search.Heuristic(*s.start, start));
    s.search.SetTarget(start);
  }
  s.start = start;
  return absl::OkStatus();
}

absl::Status DStarLite::UpdateMap(std::shared_ptr<const Grid> grid,
                                  absl::Span<const Cell> changed) {
  PATHD_RETURN_IF_ERROR(ValidateUpdate(state_->search.grid(), grid, changed));
  state_->search.SwitchGrid(std::move(grid), changed);
  state_->pending_changed += static_cast<int64_t>(changed.size());
  return absl::OkStatus();
}

absl::StatusOr<PlanResult> DStarLite::Plan(const StopCondition& stop) {
  const absl::Time started = absl::Now();
  State& s = *state_;
  if (!s.start.has_value()) {
    return absl::FailedPreconditionError("D* Lite: SetStart before Plan");
  }
  const Cell start = *s.start;
  if (Blocked(s.search.grid(), start, s.search.cost())) {
    return absl::InvalidArgumentError(
        absl::StrFormat("start %s is blocked (cost %d)", CellToString(start),
                        s.search.grid().cost(start)));
  }
  PlanResult result;
  result.outcome = PlanOutcome::kNoPath;
  s.stats = RepairStats{0, s.pending_changed, false};
  if (!Blocked(s.search.grid(), s.goal, s.search.cost())) {
    const DStarSearch::ComputeEnd end = s.search.Compute(stop);
    s.stats.expansions = end.expansions;
    result.expansions = end.expansions;
    if (end.outcome != PlanOutcome::kFound) {
      result.outcome = end.outcome;
      result.planning_time = absl::Now() - started;
      return result;
    }
    const uint32_t from = s.search.model().Index(start);
    const double g = s.search.g(from);
    if (g != kInf) {
      PATHD_ASSIGN_OR_RETURN(std::vector<Cell> path, s.search.Descend(from));
      PATHD_RETURN_IF_ERROR(
          SetPath(s.search.grid(), s.search.cost(), std::move(path), g, &result));
    }
  }
  s.pending_changed = 0;
  result.planning_time = absl::Now() - started;
  return result;
}

Cell DStarLite::goal() const { return state_->goal; }
const CostParams& DStarLite::cost() const { return state_->search.cost(); }
const RepairStats& DStarLite::last_stats() const { return state_->stats; }
const Grid& DStarLite::grid() const { return state_->search.grid(); }
size_t DStarLite::MemoryBytes() const {
  return sizeof(State) + state_->search.MemoryBytes();
}
double DStarLite::g(Cell c) const {
  return state_->search.g(state_->search.model().Index(c));
}
double DStarLite::rhs(Cell c) const {
  return state_->search.rhs(state_->search.model().Index(c));
}
double DStarLite::km() const { return state_->search.km(); }

PlanOutcome internal::IncrementalAccess::ComputeShortestPath(DStarLite& dstar,
                                                            const StopCondition& stop) {
  return dstar.state_->search.Compute(stop).outcome;
}

void internal::IncrementalAccess::CorruptG(DStarLite& dstar, Cell c, double value) {
  DStarSearch& search = dstar.state_->search;
  search.store().set_g(search.model().Index(c), value);
}

// ---------------------------------------------------------------------------
// ShortestPathMap

struct ShortestPathMap::State {
  FieldSearch search;
  Cell goal;
  RepairStats stats;
  // Expansions of the last build: the cells that reach the goal.
  int64_t build_expansions = 0;
};

ShortestPathMap::ShortestPathMap(std::unique_ptr<State> state)
    : state_(std::move(state)) {}
ShortestPathMap::~ShortestPathMap() = default;

namespace {

// Builds the field from scratch on the search's current grid: the
// incremental search from its initial state, which is Dijkstra's algorithm
// with rhs as the tentative distance (on a radix heap: ComputeFromReset).
absl::Status BuildField(FieldSearch& search, const StopCondition& stop,
                        RepairStats* stats, int64_t* build_expansions) {
  search.Reset();
  const FieldSearch::ComputeEnd end = search.ComputeFromReset(stop);
  stats->expansions += end.expansions;
  *build_expansions = end.expansions;
  if (end.outcome != PlanOutcome::kFound) return StopStatus(end.outcome, end.expansions);
  search.store().Settle();
  return CheckFieldRange(search);
}

}  // namespace

absl::StatusOr<std::unique_ptr<ShortestPathMap>> ShortestPathMap::Build(
    std::shared_ptr<const Grid> grid, Cell goal, CostParams cost,
    const StopCondition& stop) {
  PATHD_RETURN_IF_ERROR(CheckGrid(grid));
  PATHD_RETURN_IF_ERROR(ValidateGoal(*grid, goal, cost));
  auto state = std::make_unique<State>(
      State{FieldSearch(std::move(grid), cost, MoveRules(), goal), goal, {}});
  state->stats.rebuilt = true;
  PATHD_RETURN_IF_ERROR(
      BuildField(state->search, stop, &state->stats, &state->build_expansions));
  return std::unique_ptr<ShortestPathMap>(new ShortestPathMap(std::move(state)));
}

absl::Status ShortestPathMap::UpdateMap(std::shared_ptr<const Grid> grid,
                                        absl::Span<const Cell> changed) {
  State& s = *state_;
  PATHD_RETURN_IF_ERROR(ValidateUpdate(s.search.grid(), grid, changed));
  s.stats = RepairStats{0, static_cast<int64_t>(changed.size()), false};
  const double cells = static_cast<double>(s.search.grid().size());
  if (static_cast<double>(changed.size()) > kRebuildFraction * cells) {
    s.stats.rebuilt = true;
    s.search.SwitchGrid(std::move(grid), {});
    return BuildField(s.search, StopCondition::None(), &s.stats, &s.build_expansions);
  }
  s.search.SwitchGrid(std::move(grid), changed);
  const auto budget = std::max(
      kMinRepairBudget,
      static_cast<int64_t>(kRepairBudget * static_cast<double>(s.build_expansions)));
  const FieldSearch::ComputeEnd end =
      s.search.Compute(StopCondition(absl::InfiniteFuture(), nullptr, budget));
  s.stats.expansions = end.expansions;
  if (end.outcome != PlanOutcome::kFound) {
    // Over budget: the rest of the repair would likely cost more than a
    // rebuild. The grid is already switched.
    s.stats.rebuilt = true;
    return BuildField(s.search, StopCondition::None(), &s.stats, &s.build_expansions);
  }
  s.search.store().Settle();
  return absl::OkStatus();
}

std::unique_ptr<ShortestPathMap> ShortestPathMap::Clone() const {
  return std::unique_ptr<ShortestPathMap>(
      new ShortestPathMap(std::make_unique<State>(*state_)));
}

absl::StatusOr<PlanResult> ShortestPathMap::PathFrom(Cell start) const {
  const absl::Time started = absl::Now();
  const FieldSearch& search = state_->search;
  const Grid& grid = search.grid();
  if (!grid.InBounds(start)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("start %s is outside the %d x %d map", CellToString(start),
                        grid.width(), grid.height()));
  }
  if (Blocked(grid, start, search.cost())) {
    return absl::InvalidArgumentError(
        absl::StrFormat("start %s is on a blocked cell (cost %d)", CellToString(start),
                        grid.cost(start)));
  }
  PlanResult result;
  result.outcome = PlanOutcome::kNoPath;
  const uint32_t from = search.model().Index(start);
  if (search.g(from) != std::numeric_limits<float>::infinity()) {
    PATHD_ASSIGN_OR_RETURN(std::vector<Cell> path, search.Descend(from));
    result.expansions = static_cast<int64_t>(path.size());
    // The field holds floats; the path is measured in double, and it is
    // optimal up to the field's rounding (relative 1e-6 or better on maps
    // whose costs stay well below 2^24), so no comparison with g here.
    PATHD_RETURN_IF_ERROR(SetPath(grid, search.cost(), std::move(path),
                                  std::numeric_limits<double>::quiet_NaN(), &result));
  }
  result.planning_time = absl::Now() - started;
  return result;
}

float ShortestPathMap::CostToGo(Cell c) const {
  return state_->search.g(state_->search.model().Index(c));
}
absl::Span<const float> ShortestPathMap::field() const {
  return state_->search.store().field();
}
Cell ShortestPathMap::goal() const { return state_->goal; }
const CostParams& ShortestPathMap::cost() const { return state_->search.cost(); }
const RepairStats& ShortestPathMap::last_stats() const { return state_->stats; }
const Grid& ShortestPathMap::grid() const { return state_->search.grid(); }
size_t ShortestPathMap::MemoryBytes() const {
  return sizeof(State) + state_->search.MemoryBytes();
}

void internal::IncrementalAccess::CorruptField(ShortestPathMap& map, Cell c,
                                               float value) {
  FieldSearch& search = map.state_->search;
  search.store().CorruptForTest(search.model().Index(c), value);
}

absl::StatusOr<std::vector<double>> internal::IncrementalAccess::PathCosts(
    const ShortestPathMap& map) {
  const FieldSearch& search = map.state_->search;
  const size_t cells = search.grid().size();
  std::vector<double> cost(cells, kInf);
  cost[search.root()] = 0.0;
  // Each cell's path is one move to its Downhill neighbour and then that
  // neighbour's path: follow the moves to a cell already costed, then unwind.
  // Every step must lower g, so the chains end (as in Descend).
  std::vector<std::pair<uint32_t, double>> chain;
  for (uint32_t i = 0; i < cells; ++i) {
    if (cost[i] != kInf || search.g(i) == std::numeric_limits<float>::infinity()) {
      continue;
    }
    chain.clear();
    uint32_t at = i;
    while (cost[at] == kInf) {
      const auto next = search.Downhill(at);
      if (!next.has_value() || !(search.g(next->cell) < search.g(at))) {
        return absl::InternalError(absl::StrFormat(
            "shortest path map broken: no neighbour of %s has a lower cost-to-go",
            CellToString(search.model().CellOf(at))));
      }
      chain.emplace_back(at, next->cost);
      at = next->cell;
    }
    double total = cost[at];
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
      total += it->second;
      cost[it->first] = total;
    }
  }
  return cost;
}

}  // namespace pathd
