// Many-to-many cost tables (OSRM's `table`): the cheapest cost and its path's
// length between N sources and M destinations, by one goal-rooted
// cost-to-go field per destination (the backward method, which a caller can
// serve from a cache of fields) or one multi-target Dijkstra search per
// source (the forward method). Pure functions of a grid; thread-compatible.
#ifndef PATHD_CORE_FLEET_TABLE_H_
#define PATHD_CORE_FLEET_TABLE_H_

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/types/span.h"
#include "core/incremental/incremental_search.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/plan_types.h"
#include "core/search/stop_condition.h"

namespace pathd {

enum class TableMethod { kAuto, kBackward, kForward };

// The method kAuto runs: kBackward when destinations <= sources (M fields
// then beat N searches, and the fields are what a cache keeps), else
// kForward. A forward search from a source stops when its farthest
// destination is settled, a field covers the whole reachable map, so on a
// square table the fields cost more per search but are the ones a repeated
// table finds in the cache.
TableMethod ChooseTableMethod(size_t sources, size_t destinations);

// One source-destination pair.
struct TableCell {
  bool reachable = false;
  // Under the cost model (DESIGN.md), in cells; 0 when unreachable.
  double cost = 0.0;
  // Geometric length of the cheapest path found (1 per straight and sqrt(2)
  // per diagonal move). Paths of equal cost may differ in length; each
  // method reports the one it found.
  double length = 0.0;
};

// A table and what computing it took.
struct CostTable {
  // kFound when complete, else the stop condition's outcome (entries then
  // are not all set).
  PlanOutcome outcome = PlanOutcome::kFound;
  TableMethod method = TableMethod::kForward;
  size_t rows = 0;
  size_t columns = 0;
  // Row-major: entries[i * columns + j] is source i to destination j.
  std::vector<TableCell> entries;
  // Cells settled by the searches and field builds.
  int64_t expansions = 0;
  // kBackward: destinations whose field the provider had already.
  int32_t fields_cached = 0;

  const TableCell& at(size_t i, size_t j) const { return entries[i * columns + j]; }
};

// A destination's cost-to-go field as the backward method gets it.
struct FieldLookup {
  // kFound: `field` is set; otherwise the build was stopped.
  PlanOutcome outcome = PlanOutcome::kFound;
  std::shared_ptr<const ShortestPathMap> field;
  bool cached = false;
  int64_t expansions = 0;
};
// Provides the field of goal `goal` on the table's grid (the server: its
// shortest path map cache). Errors end the table.
using FieldProvider =
    std::function<absl::StatusOr<FieldLookup>(Cell goal, const StopCondition& stop)>;

// The table from every source to every destination on `grid` under `cost`.
// Preconditions: every source and destination is on the grid and
// traversable (the caller validates and names them). kBackward reads each
// destination's field from `fields` (empty: ShortestPathMap::Build on
// `grid`) and descends each source's path in it for the length; kForward
// runs a Dijkstra search per source until every destination is settled.
// `stop`'s expansion budget applies to each search or field build (as to
// one Plan), its deadline and cancellation to the whole table. Errors:
// those of the provider, INTERNAL when a field is broken.
absl::StatusOr<CostTable> ComputeTable(std::shared_ptr<const Grid> grid,
                                       const CostParams& cost,
                                       absl::Span<const Cell> sources,
                                       absl::Span<const Cell> destinations,
                                       TableMethod method, const FieldProvider& fields,
                                       const StopCondition& stop);

// Dijkstra's algorithm from one source over the cost model's moves, with
// the length of the path found to each cell: the forward table's search and
// the isochrone's. The grid is prepared once (a padded table of step
// factors, so neighbours need no bounds checks) and each Run resets only
// the cells it touched, so many runs on one grid cost their searches only.
// Thread-compatible; `grid` must outlive it.
class ForwardDijkstra {
 public:
  ForwardDijkstra(const Grid& grid, const CostParams& cost);

  // Searches from `source` (on the grid, traversable) until every cell of
  // `targets` is settled (empty targets: until the open list is empty or
  // its smallest cost exceeds `max_cost`). Returns kFound, or the stop
  // condition's outcome; `*expansions` gets the cells settled.
  PlanOutcome Run(Cell source, absl::Span<const Cell> targets, double max_cost,
                  const StopCondition& stop, int64_t* expansions);

  // After Run: the cheapest cost from the source and the length of the path
  // found, +infinity for cells the run did not settle.
  double cost(Cell c) const;
  double length(Cell c) const;

 private:
  size_t Padded(Cell c) const {
    return static_cast<size_t>(c.y + 1) * stride_ + static_cast<size_t>(c.x + 1);
  }

  const Grid& grid_;
  const int moves_;
  size_t stride_ = 0;
  // Per padded cell: the factor of entering it (0: blocked or outside).
  std::vector<double> factor_;
  std::vector<double> dist_;
  std::vector<double> length_;
  std::vector<uint8_t> settled_;
  std::vector<uint8_t> target_;
  std::vector<uint32_t> touched_;
  // Padded offsets and lengths of the moves, in kMoves order.
  int64_t offset_[8] = {};
  double step_[8] = {};
  int64_t side_a_[8] = {};
  int64_t side_b_[8] = {};
};

// A whole run's costs and lengths, row-major over the grid (+infinity where
// not settled).
struct CostField {
  PlanOutcome outcome = PlanOutcome::kFound;
  std::vector<double> cost;
  std::vector<double> length;
  int64_t expansions = 0;
};
CostField DijkstraFrom(const Grid& grid, const CostParams& cost, Cell source,
                       absl::Span<const Cell> targets, double max_cost,
                       const StopCondition& stop);

}  // namespace pathd

#endif  // PATHD_CORE_FLEET_TABLE_H_
