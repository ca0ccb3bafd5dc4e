// Incremental search state kept between queries: LPA* (fixed start and goal),
// D* Lite (fixed goal, moving start) and the shortest path map (the full
// goal-rooted cost-to-go field). All three repair themselves after a map
// change given the new grid and the list of cells whose cost changed, instead
// of searching from scratch (Koenig, Likhachev & Furcy 2004, "Lifelong
// Planning A*"; Koenig & Likhachev 2002, "D* Lite").
//
// Cost model as everywhere (core/map/cost_model.h): entering a cell costs
// move_length * CellFactor; diagonals need both side cells traversable. Costs
// are directed (they depend on the entered cell), so D* Lite and the shortest
// path map, which search backwards from the goal, use c(u, s') for the move
// u -> s' when computing rhs(u) = min over successors s' of c(u, s') + g(s').
//
// Thread-compatible: one object must not be used by two threads at once; the
// const accessors may be called concurrently with each other.
#ifndef PATHD_CORE_INCREMENTAL_INCREMENTAL_SEARCH_H_
#define PATHD_CORE_INCREMENTAL_INCREMENTAL_SEARCH_H_

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/types/span.h"
#include "core/search/endpoints.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/planner.h"

namespace pathd {

namespace internal {
class IncrementalAccess;
}  // namespace internal

// Cells whose cost differs between two grids of the same size, in row-major
// order. INVALID_ARGUMENT when the sizes differ.
absl::StatusOr<std::vector<Cell>> ChangedCells(const Grid& before,
                                               const Grid& after);

// What the last repair or search of an incremental object did.
struct RepairStats {
  // Vertices expanded (popped and made consistent or underconsistent).
  int64_t expansions = 0;
  // Cells in the change list that was applied (0 for a plain query).
  int64_t changed_cells = 0;
  // The shortest path map chose to rebuild the field from scratch instead of
  // repairing it (the change was too large for a repair to pay off).
  bool rebuilt = false;
};

// Lifelong Planning A*: start and goal fixed, the map changes. Forward search
// from the start with the octile/Manhattan heuristic towards the goal.
class LpaStar {
 public:
  ~LpaStar();

  // INVALID_ARGUMENT (as ValidateEndpoints) when start or goal is off the map
  // or blocked, or the cost parameters are invalid. No search runs yet.
  static absl::StatusOr<std::unique_ptr<LpaStar>> Create(
      std::shared_ptr<const Grid> grid, Cell start, Cell goal, CostParams cost);

  // Switches to `grid` (same size), where `changed` lists every cell whose
  // cost differs from the current grid (cells may repeat). Updates the
  // affected vertices only; the search runs on the next Plan().
  // INVALID_ARGUMENT for a different size or a changed cell off the map.
  absl::Status UpdateMap(std::shared_ptr<const Grid> grid,
                         absl::Span<const Cell> changed);

  // Brings the search up to date (ComputeShortestPath) and extracts the path.
  // A stop (deadline, cancel, budget) leaves the state valid: the next Plan()
  // continues. kNoPath when the goal is unreachable or has become blocked.
  // INTERNAL when path extraction finds the invariants broken (never loops).
  absl::StatusOr<PlanResult> Plan(const StopCondition& stop);

  const RepairStats& last_stats() const;
  const Grid& grid() const;
  // Bytes held by the search state (per-cell arrays and the open list).
  size_t MemoryBytes() const;

  // For tests: g and rhs of a cell (+infinity when unset).
  double g(Cell c) const;
  double rhs(Cell c) const;

 private:
  friend class internal::IncrementalAccess;
  struct State;
  explicit LpaStar(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

// D* Lite: the goal is fixed, the start (the robot) moves and the map
// changes. Backward search from the goal with the km key modifier, so moving
// the start does not reorder the open list.
class DStarLite {
 public:
  ~DStarLite();

  // INVALID_ARGUMENT when the goal is off the map or blocked, or the cost
  // parameters are invalid.
  static absl::StatusOr<std::unique_ptr<DStarLite>> Create(
      std::shared_ptr<const Grid> grid, Cell goal, CostParams cost);

  // Moves the robot to `start` (any cell; km += h(last, start)).
  // INVALID_ARGUMENT when off the map; a blocked start is reported by Plan().
  absl::Status SetStart(Cell start);

  // As LpaStar::UpdateMap.
  absl::Status UpdateMap(std::shared_ptr<const Grid> grid,
                         absl::Span<const Cell> changed);

  // Repairs (ComputeShortestPath) and extracts the path from the current
  // start. FAILED_PRECONDITION before the first SetStart; INVALID_ARGUMENT
  // "start ... is blocked" when the start cell is not traversable; otherwise as
  // LpaStar::Plan.
  absl::StatusOr<PlanResult> Plan(const StopCondition& stop);

  Cell goal() const;
  const CostParams& cost() const;
  const RepairStats& last_stats() const;
  const Grid& grid() const;
  size_t MemoryBytes() const;

  // For tests: g and rhs of a cell (cost-to-go estimates), and km.
  double g(Cell c) const;
  double rhs(Cell c) const;
  double km() const;

 private:
  friend class internal::IncrementalAccess;
  struct State;
  explicit DStarLite(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

// The shortest path map of a goal: the exact cost-to-go of every cell, kept
// as 4-byte floats. Any start is answered by descending the field, O(path
// length); a map change is repaired by the same incremental machinery run
// without a focusing heuristic until no vertex is inconsistent, or the field
// is rebuilt when the change is large enough that a rebuild is cheaper.
class ShortestPathMap {
 public:
  ~ShortestPathMap();

  // Builds the full field. INVALID_ARGUMENT as DStarLite::Create. A stop
  // returns its outcome as an error status (DEADLINE_EXCEEDED, CANCELLED,
  // RESOURCE_EXHAUSTED for the budget).
  static absl::StatusOr<std::unique_ptr<ShortestPathMap>> Build(
      std::shared_ptr<const Grid> grid, Cell goal, CostParams cost,
      const StopCondition& stop);

  // As LpaStar::UpdateMap, but repairs the field before returning.
  absl::Status UpdateMap(std::shared_ptr<const Grid> grid,
                         absl::Span<const Cell> changed);

  // A copy to repair while readers keep using this one.
  std::unique_ptr<ShortestPathMap> Clone() const;

  // The optimal path from `start` by descending the field: kFound with the
  // path, cost and length measured exactly; kNoPath when start cannot reach the
  // goal; INVALID_ARGUMENT when start is off the map or blocked; INTERNAL when
  // the descent finds the field broken. expansions = cells visited.
  absl::StatusOr<PlanResult> PathFrom(Cell start) const;

  // Cost to the goal (+infinity when unreachable); precondition: in bounds.
  float CostToGo(Cell c) const;
  // The whole field, row-major.
  absl::Span<const float> field() const;

  Cell goal() const;
  const CostParams& cost() const;
  const RepairStats& last_stats() const;
  const Grid& grid() const;
  size_t MemoryBytes() const;

 private:
  friend class internal::IncrementalAccess;
  struct State;
  explicit ShortestPathMap(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

}  // namespace pathd

#endif  // PATHD_CORE_INCREMENTAL_INCREMENTAL_SEARCH_H_
