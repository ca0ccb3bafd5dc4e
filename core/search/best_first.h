// The one best-first search loop behind A*, Dijkstra, weighted A* and greedy
// best-first: a binary-heap open list with decrease-key over the per-thread
// SearchScratch, parameterised by a priority policy (the open-list key of a
// node from its g and cell) and an expansion listener that compiles away when
// unused (after warthog's unidirectional_search<H, E, Q, L>).
#ifndef PATHD_CORE_SEARCH_BEST_FIRST_H_
#define PATHD_CORE_SEARCH_BEST_FIRST_H_

#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>
#include <vector>

#include "absl/time/clock.h"
#include "core/search/endpoints.h"
#include "core/search/planner.h"
#include "core/search/grid_view.h"
#include "core/search/search_scratch.h"

namespace pathd::internal {

// Binary min-heap on (f, -g) stored in scratch.open(); each node's position is
// kept in its SearchScratch record for O(log n) decrease-key. Ties on f go to
// the larger g (the deeper node), which makes A* reach the goal with fewer
// expansions on open ground.
class OpenList {
 public:
  explicit OpenList(SearchScratch& scratch) : scratch_(scratch), heap_(scratch.open()) {}

  bool empty() const { return heap_.empty(); }
  size_t size() const { return heap_.size(); }

  // Inserts `index` or changes its key if it is already open. A lower g
  // usually lowers f, but not under every priority (greedy's f = h keeps f and
  // loses the larger-g tie-break), so the entry may have to move either way.
  void Push(uint32_t index, double f, double g) {
    SearchScratch::Node& node = scratch_.Raw(index);
    if (node.open_pos >= 0) {
      SearchScratch::OpenEntry& entry = heap_[node.open_pos];
      const SearchScratch::OpenEntry updated{f, g, index};
      const bool better = Before(updated, entry);
      entry = updated;
      if (better) {
        SiftUp(node.open_pos);
      } else {
        SiftDown(node.open_pos);
      }
      return;
    }
    heap_.push_back({f, g, index});
    SiftUp(static_cast<int32_t>(heap_.size() - 1));
  }

  // Removes and returns the best entry; the node is marked closed.
  SearchScratch::OpenEntry Pop() {
    SearchScratch::OpenEntry top = heap_.front();
    scratch_.Raw(top.index).open_pos = SearchScratch::kClosed;
    const SearchScratch::OpenEntry last = heap_.back();
    heap_.pop_back();
    if (!heap_.empty()) {
      heap_[0] = last;
      scratch_.Raw(last.index).open_pos = 0;
      SiftDown(0);
    }
    return top;
  }

  const SearchScratch::OpenEntry& Top() const { return heap_.front(); }

 private:
  static bool Before(const SearchScratch::OpenEntry& a,
                     const SearchScratch::OpenEntry& b) {
    return a.f < b.f || (a.f == b.f && a.g > b.g);
  }

  void SiftUp(int32_t pos) {
    const SearchScratch::OpenEntry moving = heap_[pos];
    while (pos > 0) {
      const int32_t parent = (pos - 1) / 2;
      if (!Before(moving, heap_[parent])) break;
      heap_[pos] = heap_[parent];
      scratch_.Raw(heap_[pos].index).open_pos = pos;
      pos = parent;
    }
    heap_[pos] = moving;
    scratch_.Raw(moving.index).open_pos = pos;
  }

  void SiftDown(int32_t pos) {
    const SearchScratch::OpenEntry moving = heap_[pos];
    const int32_t n = static_cast<int32_t>(heap_.size());
    while (true) {
      int32_t child = 2 * pos + 1;
      if (child >= n) break;
      if (child + 1 < n && Before(heap_[child + 1], heap_[child])) ++child;
      if (!Before(heap_[child], moving)) break;
      heap_[pos] = heap_[child];
      scratch_.Raw(heap_[pos].index).open_pos = pos;
      pos = child;
    }
    heap_[pos] = moving;
    scratch_.Raw(moving.index).open_pos = pos;
  }

  SearchScratch& scratch_;
  std::vector<SearchScratch::OpenEntry>& heap_;
};

// Runs best-first search from request.start to request.goal, expanding nodes
// in increasing order of `priority(g, x, y)` (ties to the larger g). Closed
// nodes are never reopened, so the path is optimal only for a priority
// g + h(x, y) with h consistent, and within w times the optimum for
// g + w * h(x, y) (Likhachev, Gordon & Thrun 2003). Precondition:
// ValidateEndpoints passed and the grid has fewer than 2^32 - 1 cells.
template <typename Priority, typename Listener = NullListener>
PlanResult BestFirstSearch(const Grid& grid, const PlanRequest& request,
                           const StopCondition& stop, SearchScratch& scratch,
                           Priority&& priority, Listener&& listener = Listener()) {
  if constexpr (std::is_same_v<std::decay_t<Listener>, NullListener>) {
    // Decided once per search, so the loop that records nothing tests
    // nothing per expansion.
    if (request.expansion_recorder != nullptr) {
      return BestFirstSearch(grid, request, stop, scratch, priority,
                             RecordingListener{*request.expansion_recorder,
                                               grid.width()});
    }
  }
  const absl::Time started = absl::Now();
  const GridView view(grid, request.cost);
  scratch.BeginSearch(grid.size());
  OpenList open(scratch);

  const uint32_t start = view.Index(request.start.x, request.start.y);
  const uint32_t goal = view.Index(request.goal.x, request.goal.y);
  SearchScratch::Node& root = scratch.At(start);
  root.g = 0.0;
  open.Push(start, priority(0.0, request.start.x, request.start.y), 0.0);

  PlanResult result;
  result.outcome = PlanOutcome::kNoPath;
  int64_t expansions = 0;
  while (!open.empty()) {
    if (const PlanOutcome why = stop.Check(expansions, open.Top().f);
        why != PlanOutcome::kFound) {
      result.outcome = why;
      break;
    }
    const SearchScratch::OpenEntry best = open.Pop();
    ++expansions;
    listener.OnExpand(best.index);
    if (best.index == goal) {
      result.outcome = PlanOutcome::kFound;
      break;
    }
    const Cell at = view.CellOf(best.index);
    const double g = best.g;
    view.ForEachNeighbor(at.x, at.y, [&](uint32_t next, int32_t nx, int32_t ny,
                                         double move_length) {
      SearchScratch::Node& node = scratch.At(next);
      if (node.open_pos == SearchScratch::kClosed) return;
      const double next_g = g + move_length * view.Factor(next);
      if (next_g >= node.g) return;
      node.g = next_g;
      node.parent = best.index;
      open.Push(next, priority(next_g, nx, ny), next_g);
    });
  }

  result.expansions = expansions;
  if (result.outcome == PlanOutcome::kFound) {
    result.path = TracePath(view, scratch, goal, grid.size());
    result.cost = scratch.Raw(goal).g;
    result.length = PathLength(result.path);
  }
  result.planning_time = absl::Now() - started;
  return result;
}

}  // namespace pathd::internal

#endif  // PATHD_CORE_SEARCH_BEST_FIRST_H_
