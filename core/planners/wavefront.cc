// The wave-front planner of the lecture "Path Planning in Discrete Sampled
// Space" (its "Wave-Front Planner"; NF1 of Barraquand, Langlois & Latombe
// 1992): label the goal 2, give every unlabelled free neighbour of a cell
// labelled L the label L + 1 until the start is labelled, then walk from the
// start to a neighbour labelled one less until the goal. The labels count moves, so the path has the fewest
// moves; cell costs only decide what is blocked.
#include "core/planners/wavefront.h"

#include <memory>
#include <vector>

#include "core/planners/planners.h"
#include "core/search/grid_planner.h"
#include "core/search/grid_view.h"
#include "core/search/search_scratch.h"

namespace pathd {
namespace {

using internal::GridView;
using internal::SetMeasuredPath;

constexpr uint32_t kNoCell = SearchScratch::kNoParent;

struct FloodEnd {
  PlanOutcome outcome;
  int64_t expansions;
};

// Floods from `goal`, storing each reached cell's label minus kWavefrontGoal
// (its move count) in its scratch record's g. The FIFO hands out cells in
// label order, so when the next cell to expand carries the start's label the
// layer that labelled the start is complete: the lecture's loop ends exactly
// there. `start` == kNoCell floods every reachable cell. The caller has called
// scratch.BeginSearch(). Each expanded cell goes to `listener`.
template <typename Listener>
FloodEnd Flood(const GridView& view, uint32_t goal, uint32_t start,
               const StopCondition& stop, SearchScratch& scratch, Listener listener) {
  std::vector<uint32_t>& queue = scratch.fifo();
  scratch.At(goal).g = 0.0;
  queue.push_back(goal);
  int64_t expansions = 0;
  for (size_t head = 0; head < queue.size(); ++head) {
    const uint32_t current = queue[head];
    const double moves = scratch.Raw(current).g;
    if (start != kNoCell && scratch.Seen(start) && moves >= scratch.Raw(start).g) {
      return {PlanOutcome::kFound, expansions};
    }
    if (const PlanOutcome why = stop.Check(expansions); why != PlanOutcome::kFound) {
      return {why, expansions};
    }
    ++expansions;
    listener.OnExpand(current);
    const Cell at = view.CellOf(current);
    view.ForEachNeighbor(at.x, at.y, [&](uint32_t next, int32_t, int32_t, double) {
      if (scratch.Seen(next)) return;
      scratch.At(next).g = moves + 1.0;
      queue.push_back(next);
    });
  }
  const bool reached = start == kNoCell || scratch.Seen(start);
  return {reached ? PlanOutcome::kFound : PlanOutcome::kNoPath, expansions};
}

// Walks from the labelled `start` down the labels to the goal. The lecture allows
// "any connected cell with label L - 1"; this takes the first in the cost
// model's move order (+x, -x, +y, -y, then the diagonals (+1,+1), (+1,-1),
// (-1,+1), (-1,-1)). Such a neighbour always exists: the cell that labelled a
// cell is one move away and legal moves are symmetric.
std::vector<Cell> Descend(const GridView& view, const SearchScratch& scratch,
                          uint32_t start) {
  std::vector<Cell> path{view.CellOf(start)};
  uint32_t at = start;
  for (double moves = scratch.Raw(start).g; moves > 0.0; moves -= 1.0) {
    uint32_t down = kNoCell;
    const Cell c = view.CellOf(at);
    view.ForEachNeighbor(c.x, c.y, [&](uint32_t next, int32_t, int32_t, double) {
      if (down == kNoCell && scratch.Seen(next) && scratch.Raw(next).g == moves - 1.0) {
        down = next;
      }
    });
    at = down;
    path.push_back(view.CellOf(at));
  }
  return path;
}

class WavefrontPlanner final : public GridPlanner {
 public:
  WavefrontPlanner()
      : GridPlanner("wavefront",
                    PlannerTraits{
                        .fewest_moves = true,
                        .description =
                            "wave-front planner (NF1; Barraquand, Langlois & "
                            "Latombe 1992): labels flooded from the goal until "
                            "the start is labelled, path down the labels; "
                            "fewest moves, ignores cell costs except for "
                            "blocking"}) {}

 protected:
  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    [[maybe_unused]] const Grid& grid = q.grid;
    [[maybe_unused]] const PlanRequest& request = q.request;
    [[maybe_unused]] const StopCondition& stop = q.stop;
    [[maybe_unused]] SearchScratch& scratch = q.scratch;
    const GridView view(grid, request.cost);
    scratch.BeginSearch(grid.size());
    const uint32_t start = view.Index(request.start.x, request.start.y);
    const FloodEnd end = internal::WithExpansionListener(
        request.expansion_recorder, view, [&](auto listener) {
          return Flood(view, view.Index(request.goal.x, request.goal.y), start, stop,
                       scratch, listener);
        });

    PlanResult result;
    result.outcome = end.outcome;
    result.expansions = end.expansions;
    if (result.found()) {
      SetMeasuredPath(grid, request.cost, Descend(view, scratch, start), &result);
    }
    return result;
  }
};

}  // namespace

WavefrontLabelling WavefrontLabels(const Grid& grid, Cell goal, const CostParams& cost,
                                   std::optional<Cell> start, const StopCondition& stop) {
  const GridView view(grid, cost);
  SearchScratch scratch;
  scratch.BeginSearch(grid.size());
  const FloodEnd end =
      Flood(view, view.Index(goal.x, goal.y),
            start.has_value() ? view.Index(start->x, start->y) : kNoCell, stop, scratch,
            internal::NullListener());

  WavefrontLabelling labelling;
  labelling.outcome = end.outcome;
  labelling.expansions = end.expansions;
  labelling.labels.resize(grid.size());
  const std::vector<uint8_t>& cells = grid.cells();
  for (size_t i = 0; i < cells.size(); ++i) {
    if (!Traversable(cells[i], cost.unknown_is_free)) {
      labelling.labels[i] = kWavefrontObstacle;
    } else if (scratch.Seen(i)) {
      labelling.labels[i] = kWavefrontGoal + static_cast<int32_t>(scratch.Raw(i).g);
    } else {
      labelling.labels[i] = kWavefrontUnlabelled;
    }
  }
  return labelling;
}

std::unique_ptr<Planner> MakeWavefrontPlanner() {
  return std::make_unique<WavefrontPlanner>();
}

}  // namespace pathd
