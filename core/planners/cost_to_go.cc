// Cost-to-go planners: the distance transform (Jarvis 2004, "Distance
// Transform Based Visibility Measures for Covert Path Planning in Known but
// Dynamic Environments") computed by raster passes as in Algorithm 1 of
// Faigl's lecture "Path Planning" (B4M36UIR, Lecture 03, "Distance Transform
// based Path Planning"), and the same field by an exact Dijkstra sweep from
// the goal on the best-first loop of core/search/best_first.h. Both descend
// the field from the start; they differ only in how the field is computed.
#include "core/planners/cost_to_go.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

#include "core/planners/planners.h"
#include "core/search/best_first.h"
#include "core/search/grid_planner.h"
#include "core/search/grid_view.h"

namespace pathd {
namespace {

using internal::CostTable;
using internal::GridView;
using internal::SetMeasuredPath;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr uint32_t kNoCell = SearchScratch::kNoParent;

// The raster passes of Algorithm 1 over a copy of the grid padded with a
// blocked border, so every cell's eight neighbours can be read without bounds
// checks (the lecture's Algorithm 1 assumes such a border and skips the outer
// ring; the padding keeps the outer ring plannable). Cost-to-go of blocked cells stays +inf, so
// a move into one is never the minimum; only the corner-cutting rule needs
// the side cells' passability.
class RasterSweep {
 public:
  RasterSweep(const Grid& grid, Cell goal, const CostParams& cost,
              const StopCondition& stop)
      : width_(grid.width()),
        height_(grid.height()),
        stride_(static_cast<size_t>(grid.width()) + 2),
        cells_(stride_ * (static_cast<size_t>(grid.height()) + 2), kLethalCost),
        ctg_(cells_.size(), kInf),
        table_(cost),
        changed_at_(static_cast<size_t>(grid.height()) + 2, -1),
        forward_at_(changed_at_.size(), -1),
        backward_at_(changed_at_.size(), -1),
        stop_(stop) {
    for (int32_t y = 0; y < height_; ++y) {
      std::memcpy(&cells_[Padded(0, y)], &grid.cells()[grid.Index(0, y)],
                  static_cast<size_t>(width_));
    }
    ctg_[Padded(goal.x, goal.y)] = 0.0;
    changed_at_[static_cast<size_t>(goal.y) + 1] = 0;
  }

  // Runs passes until one changes nothing. Algorithm 1 tests for change after
  // each forward + backward pair; stopping at the first pass (from the second
  // on) that changes nothing is equivalent and saves up to a pass: the pass
  // before it, in the other direction, left every cell no worse than the
  // neighbours that pass reads, and an unchanged pass does the same for the
  // other four.
  template <bool kEight>
  CostToGoField Run() {
    CostToGoField field;
    for (bool changed = true; changed || field.passes < 2; ++field.passes) {
      const PlanOutcome why =
          field.passes % 2 == 0 ? Pass<kEight, -1>(changed) : Pass<kEight, +1>(changed);
      if (why != PlanOutcome::kFound) {
        field.outcome = why;
        break;
      }
    }
    field.expansions = expansions_;
    if (field.outcome == PlanOutcome::kFound) {
      field.values.resize(static_cast<size_t>(width_) * static_cast<size_t>(height_));
      for (int32_t y = 0; y < height_; ++y) {
        std::memcpy(&field.values[static_cast<size_t>(y) * static_cast<size_t>(width_)],
                    &ctg_[Padded(0, y)], static_cast<size_t>(width_) * sizeof(double));
      }
    }
    return field;
  }

 private:
  size_t Padded(int32_t x, int32_t y) const {
    return (static_cast<size_t>(y) + 1) * stride_ + static_cast<size_t>(x) + 1;
  }

  // Rows are the unit of work between polls: a row that would cross the
  // expansion budget is not started, so the count never exceeds it, and the
  // clock is read about every kPollInterval cells (Check()'s own clock read
  // would seldom line up with row-sized steps).
  PlanOutcome BeforeRow() {
    if (stop_.max_expansions() > 0 && expansions_ + width_ > stop_.max_expansions()) {
      return PlanOutcome::kExpansionLimit;
    }
    if (expansions_ >= next_clock_poll_) {
      if (const PlanOutcome why = stop_.Poll(expansions_); why != PlanOutcome::kFound) {
        return why;
      }
      next_clock_poll_ = expansions_ + StopCondition::kPollInterval;
    }
    return PlanOutcome::kFound;
  }

  // One raster pass. kStep -1: forward, top-left to bottom-right, each cell
  // taking the best of W, N, NW, NE; +1: backward, bottom-right to top-left,
  // E, S, SE, SW. Those are the neighbours this pass has already updated.
  //
  // A row is skipped when neither it nor the row it reads (N or S) changed
  // since its last sweep in the same direction: every cell was then already
  // no worse than those neighbours, so the sweep would change nothing. The
  // values and the pass count are those of sweeping every row; on mazes, where
  // each pass advances the front along a few corridors, most rows are skipped.
  //
  // Branches rather than selects: blocked cells come in runs and the vertical
  // neighbour decides both diagonals, so they predict well, and on the Moving
  // AI maps this measured faster than computing every candidate.
  template <bool kEight, int kStep>
  PlanOutcome Pass(bool& changed) {
    changed = false;
    for (int32_t i = 0; i < height_; ++i) {
      const int32_t y = kStep < 0 ? i : height_ - 1 - i;
      const size_t row = static_cast<size_t>(y) + 1;  // padded
      int64_t& swept_at = kStep < 0 ? forward_at_[row] : backward_at_[row];
      if (std::max(changed_at_[row], changed_at_[row + kStep]) <= swept_at) continue;
      if (const PlanOutcome why = BeforeRow(); why != PlanOutcome::kFound) return why;
      swept_at = ++stamp_;

      const uint8_t* c = &cells_[Padded(0, y)];
      const uint8_t* cv = kStep < 0 ? c - stride_ : c + stride_;
      double* d = &ctg_[Padded(0, y)];
      const double* dv = kStep < 0 ? d - stride_ : d + stride_;
      // The neighbour just updated, kept in a register: it is the one
      // dependency from cell to cell.
      double side = d[kStep < 0 ? -1 : width_];
      bool row_changed = false;
      for (int32_t j = 0; j < width_; ++j) {
        const int32_t x = kStep < 0 ? j : width_ - 1 - j;
        if (!table_.Passable(c[x])) {
          side = kInf;
          continue;
        }
        double best = std::min(d[x], side + table_.Factor(c[x + kStep]));
        if (table_.Passable(cv[x])) {
          best = std::min(best, dv[x] + table_.Factor(cv[x]));
          if constexpr (kEight) {
            if (table_.Passable(c[x - 1])) {
              best = std::min(best, dv[x - 1] + kSqrt2 * table_.Factor(cv[x - 1]));
            }
            if (table_.Passable(c[x + 1])) {
              best = std::min(best, dv[x + 1] + kSqrt2 * table_.Factor(cv[x + 1]));
            }
          }
        }
        row_changed |= best < d[x];
        d[x] = best;
        side = best;
      }
      expansions_ += width_;
      if (row_changed) {
        changed_at_[row] = stamp_;
        changed = true;
      }
    }
    return PlanOutcome::kFound;
  }

  int32_t width_;
  int32_t height_;
  size_t stride_;
  std::vector<uint8_t> cells_;
  std::vector<double> ctg_;
  const CostTable table_;
  // Per padded row: the stamp of the sweep that last changed it (-1: never,
  // 0: the goal's row at the start) and of its last forward and backward
  // sweep. Stamps count row sweeps.
  std::vector<int64_t> changed_at_;
  std::vector<int64_t> forward_at_;
  std::vector<int64_t> backward_at_;
  int64_t stamp_ = 0;
  const StopCondition& stop_;
  int64_t expansions_ = 0;
  int64_t next_clock_poll_ = 0;
};

// The tail both planners share: descend the field from the start, measure the
// path, hand the field out when asked for.
PlanResult FinishFromField(const Grid& grid, const PlanRequest& request,
                           CostToGoField field) {
  PlanResult result;
  result.outcome = field.outcome;
  result.expansions = field.expansions;
  if (result.found()) {
    std::vector<Cell> path =
        DescendCostToGo(grid, request.cost, field.values, request.start);
    if (path.empty()) {
      result.outcome = PlanOutcome::kNoPath;
    } else {
      SetMeasuredPath(grid, request.cost, std::move(path), &result);
    }
    if (request.want_cost_to_go) result.cost_to_go = std::move(field.values);
  }
  return result;
}

class DistanceTransformPlanner final : public GridPlanner {
 public:
  DistanceTransformPlanner()
      : GridPlanner("distance_transform",
                    PlannerTraits{
                        .optimal = true,
                        .cost_to_go = true,
                        .description =
                            "distance transform (Jarvis 2004): the goal's "
                            "cost-to-go field by forward/backward raster passes "
                            "until nothing changes, path down the field; "
                            "optimal, whole map per query, passes grow with "
                            "the map's winding"}) {}

 protected:
  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    return FinishFromField(
        q.grid, q.request,
        RasterDistanceTransform(q.grid, q.request.goal, q.request.cost, q.stop));
  }
};

class DistanceTransformExactPlanner final : public GridPlanner {
 public:
  DistanceTransformExactPlanner()
      : GridPlanner("distance_transform_exact",
                    PlannerTraits{
                        .optimal = true,
                        .cost_to_go = true,
                        .description =
                            "the distance transform's cost-to-go field by a "
                            "Dijkstra sweep from the goal over the whole map, "
                            "path down the field; optimal"}) {}

 protected:
  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    [[maybe_unused]] const Grid& grid = q.grid;
    [[maybe_unused]] const PlanRequest& request = q.request;
    [[maybe_unused]] const StopCondition& stop = q.stop;
    [[maybe_unused]] SearchScratch& scratch = q.scratch;
    return FinishFromField(grid, request,
                           DijkstraCostToGo(grid, request.goal, request.cost, stop,
                                            scratch, request.expansion_recorder));
  }
};

}  // namespace

CostToGoField RasterDistanceTransform(const Grid& grid, Cell goal, const CostParams& cost,
                                      const StopCondition& stop) {
  RasterSweep sweep(grid, goal, cost, stop);
  return cost.connectivity == Connectivity::kFour ? sweep.Run<false>()
                                                  : sweep.Run<true>();
}

CostToGoField DijkstraCostToGo(const Grid& grid, Cell goal, const CostParams& cost,
                               const StopCondition& stop, SearchScratch& scratch,
                               ExpansionRecorder* recorder) {
  return internal::DijkstraCostToGoOn<internal::MonotoneOpenList>(grid, goal, cost, stop,
                                                                  scratch, recorder);
}

namespace internal {
namespace {

// Writes each cell's cost-to-go into the field when the sweep expands it
// (its g is final then, and its record in cache), then tells `inner`.
// Expanded cells are exactly those the sweep reached, as it runs until OPEN
// is empty; a pass over every record afterwards cost more than the sweep on
// maps that are mostly unreachable (dao/brc202d).
template <typename Inner>
struct FieldWriter {
  double* values;
  const SearchScratch& scratch;
  Inner inner;
  void OnExpand(uint32_t id) {
    values[id] = scratch.Raw(id).g;
    inner.OnExpand(id);
  }
};

}  // namespace

template <typename Open>
CostToGoField DijkstraCostToGoOn(const Grid& grid, Cell goal, const CostParams& cost,
                                 const StopCondition& stop, SearchScratch& scratch,
                                 ExpansionRecorder* recorder) {
  const GridView view(grid, cost);
  const internal::ReverseGridExpansion expansion(view);
  const internal::AStarPriority<internal::ZeroHeuristic> priority{};
  scratch.BeginSearch(grid.size());
  Open open(scratch);
  internal::PushRoot(scratch, open, expansion.Id(goal), goal, priority);
  CostToGoField field;
  field.values.assign(grid.size(), kInf);
  const PlanOutcome outcome = internal::WithExpansionListener(
      recorder, expansion, [&](auto listener) {
        FieldWriter<decltype(listener)> writer{field.values.data(), scratch, listener};
        return internal::BestFirstSearch(scratch, open, internal::kNoNode, stop,
                                         field.expansions, priority, expansion,
                                         internal::PlainParentUpdate(), writer);
      });
  // Without a goal the search ends when OPEN empties: the field is complete.
  field.outcome = outcome == PlanOutcome::kNoPath ? PlanOutcome::kFound : outcome;
  if (field.outcome != PlanOutcome::kFound) field.values = {};
  return field;
}

template CostToGoField DijkstraCostToGoOn<OpenList>(const Grid&, Cell, const CostParams&,
                                                    const StopCondition&, SearchScratch&,
                                                    ExpansionRecorder*);
template CostToGoField DijkstraCostToGoOn<MonotoneOpenList>(const Grid&, Cell,
                                                            const CostParams&,
                                                            const StopCondition&,
                                                            SearchScratch&,
                                                            ExpansionRecorder*);

}  // namespace internal

std::vector<Cell> DescendCostToGo(const Grid& grid, const CostParams& cost,
                                  const std::vector<double>& field, Cell start) {
  const GridView view(grid, cost);
  uint32_t at = view.Index(start.x, start.y);
  if (!(field[at] < kInf)) return {};
  std::vector<Cell> path{start};
  while (field[at] > 0.0) {
    uint32_t best = kNoCell;
    double best_total = kInf;
    const Cell c = view.CellOf(at);
    view.ForEachNeighbor(
        c.x, c.y, [&](uint32_t next, int32_t, int32_t, double move_length) {
          const double total = move_length * view.Factor(next) + field[next];
          if (total < best_total) {
            best_total = total;
            best = next;
          }
        });
    // In a complete field the minimising neighbour is strictly lower (every
    // move costs at least 1), so the walk cannot cycle; a field that does not
    // fall is not this grid's.
    if (best == kNoCell || !(field[best] < field[at])) return {};
    at = best;
    path.push_back(view.CellOf(at));
  }
  return path;
}

std::unique_ptr<Planner> MakeDistanceTransformPlanner() {
  return std::make_unique<DistanceTransformPlanner>();
}
std::unique_ptr<Planner> MakeDistanceTransformExactPlanner() {
  return std::make_unique<DistanceTransformExactPlanner>();
}

}  // namespace pathd
