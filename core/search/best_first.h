// The one best-first search loop of the grid planners, parameterised by
// policies after warthog's unidirectional_search<H, E, Q, L>: a priority (the
// open-list key), the open list (the binary heap, or a radix heap where the
// priority is f = g and keys never decrease), an expansion policy (node ids
// and successors: grid cells, reversed grid moves, JPS jump points), a
// parent-update policy (plain, or Theta*'s any-angle parents with Lazy
// Theta*'s on-pop check), a listener (one call per expansion, compiled away
// when unused) and a halt predicate (the real-time look-ahead's budget). A*, Dijkstra, weighted A*, greedy, Theta*,
// Lazy Theta*, JPS, the RTAA*/LRTA* look-ahead and the backward cost-to-go
// sweep all run on it.
#ifndef PATHD_CORE_SEARCH_BEST_FIRST_H_
#define PATHD_CORE_SEARCH_BEST_FIRST_H_

#include <cstdint>
#include <utility>

#include "core/search/grid_view.h"
#include "core/search/heuristics.h"
#include "core/search/open_list.h"
#include "core/search/planner.h"
#include "core/search/radix_heap.h"
#include "core/search/search_scratch.h"

namespace pathd::internal {

// A goal id that no node has: the search runs until OPEN empties or halts.
inline constexpr uint32_t kNoNode = SearchScratch::kNoParent;

// ---- Priorities: f(g, node) for the open list. ----
// Each is called as priority(g, id, x, y) for node `id` at cell (x, y).

// f = g + h: A* (optimal for a consistent h), Dijkstra with ZeroHeuristic.
template <typename H>
struct AStarPriority {
  H h;
  double operator()(double g, uint32_t, int32_t x, int32_t y) const {
    return g + h(x, y);
  }
};

// f = g + w * h: w > 1 trades path cost (at most w times the optimum,
// Likhachev, Gordon & Thrun 2003) for fewer expansions.
template <typename H>
struct WeightedPriority {
  H h;
  double w;
  double operator()(double g, uint32_t, int32_t x, int32_t y) const {
    return g + w * h(x, y);
  }
};

// f = h: expands whatever looks closest to the goal, whatever it cost to
// reach. Ties on h still go to the larger g, the search's current direction.
template <typename H>
struct GreedyPriority {
  H h;
  double operator()(double, uint32_t, int32_t x, int32_t y) const {
    return h(x, y);
  }
};

// ---- Expansion policies: node ids and successors. ----
// Id(cell) numbers a cell's node, CellOf(id) inverts it, and
// ForEachSuccessor(id, g, visit) calls visit(next_id, nx, ny, next_g) for every
// successor with the g it would get through `id` (reached at cost g).

// Grid cells (row-major indices) and the moves GridView allows; a move costs
// its length times the factor of the cell it enters.
class GridExpansion {
 public:
  explicit GridExpansion(const GridView& view) : view_(view) {}
  uint32_t Id(Cell c) const { return view_.Index(c.x, c.y); }
  Cell CellOf(uint32_t id) const { return view_.CellOf(id); }
  template <typename Visit>
  void ForEachSuccessor(uint32_t id, double g, Visit&& visit) const {
    const Cell at = view_.CellOf(id);
    view_.ForEachNeighbor(
        at.x, at.y,
        [&](uint32_t next, int32_t nx, int32_t ny, double move_length) {
          visit(next, nx, ny, g + move_length * view_.Factor(next));
        });
  }

 private:
  const GridView& view_;
};

// Grid cells with moves reversed, for searches rooted at the goal: legal moves
// are symmetric, so the predecessors of a cell are its neighbours, and each
// pays the factor of the cell it enters, the expanded one.
class ReverseGridExpansion {
 public:
  explicit ReverseGridExpansion(const GridView& view) : view_(view) {}
  uint32_t Id(Cell c) const { return view_.Index(c.x, c.y); }
  Cell CellOf(uint32_t id) const { return view_.CellOf(id); }
  template <typename Visit>
  void ForEachSuccessor(uint32_t id, double g, Visit&& visit) const {
    const double factor = view_.Factor(id);
    const Cell at = view_.CellOf(id);
    view_.ForEachNeighbor(
        at.x, at.y,
        [&](uint32_t prev, int32_t px, int32_t py, double move_length) {
          visit(prev, px, py, g + move_length * factor);
        });
  }

 private:
  const GridView& view_;
};

// ---- Parent-update policies. ----
// OnPop(entry, open) runs on each node taken off OPEN before it counts as
// expanded: it may correct entry.g (and the node's record) or put the node
// back into `open` and return false to skip it. Prepare(id) runs once per
// expansion before the successors; Offer(...) returns the g and parent a
// successor is offered (the loop keeps it only when it beats the node's g).

struct Offer {
  double g;
  uint32_t parent;
};

// The expanded node is every successor's parent (A* and friends, JPS).
struct PlainParentUpdate {
  template <typename Open>
  bool OnPop(SearchScratch::OpenEntry&, Open&) {
    return true;
  }
  void Prepare(uint32_t) {}
  Offer OfferTo(uint32_t id, uint32_t, int32_t, int32_t, double next_g,
                const SearchScratch::Node&) {
    return Offer{next_g, id};
  }
};

// ---- Halt predicates. ----
// halt(open, expansions) is asked before every pop (OPEN not empty) and ends
// the search with kFound when true.

struct NeverHalt {
  template <typename Open>
  bool operator()(const Open&, int64_t) const {
    return false;
  }
};

// Seeds the search with its root node at g = 0. The caller has called
// scratch.BeginSearch().
template <typename Open, typename Priority>
void PushRoot(SearchScratch& scratch, Open& open, uint32_t id, Cell cell,
              const Priority& priority) {
  scratch.At(id).g = 0.0;
  open.Push(id, priority(0.0, id, cell.x, cell.y), 0.0);
}

// Runs best-first search on the seeded `open` until the node `goal` is taken
// off it (kFound; kNoNode: never), OPEN empties (kNoPath), `halt` holds
// (kFound) or `stop` fires (its outcome). Nodes are expanded in increasing
// priority (ties to the larger g) and never reopened, so with the plain
// parent update the path is optimal only for a priority g + h with h
// consistent. `expansions` is read as the count so far (stop is polled on the
// running total) and advanced by the nodes expanded here. `open` is an
// OpenList, or a MonotoneOpenList (core/search/radix_heap.h) when the
// priority is f = g. Precondition: the expansion policy's ids index the
// records of `scratch`.
template <typename Open, typename Priority, typename Expansion,
          typename ParentUpdate = PlainParentUpdate,
          typename Listener = NullListener, typename Halt = NeverHalt>
PlanOutcome BestFirstSearch(SearchScratch& scratch, Open& open,
                            uint32_t goal, const StopCondition& stop,
                            int64_t& expansions, const Priority& priority,
                            const Expansion& expansion,
                            ParentUpdate&& update = ParentUpdate(),
                            Listener&& listener = Listener(),
                            Halt&& halt = Halt()) {
  // A local count: the caller's may live where every store in the loop could
  // alias it.
  int64_t expanded = expansions;
  PlanOutcome outcome = PlanOutcome::kNoPath;
  while (!open.empty()) {
    if (halt(open, expanded)) {
      outcome = PlanOutcome::kFound;
      break;
    }
    if (const PlanOutcome why = stop.Check(expanded, open.Top().f);
        why != PlanOutcome::kFound) {
      outcome = why;
      break;
    }
    SearchScratch::OpenEntry best = open.Pop();
    if (!update.OnPop(best, open)) continue;
    ++expanded;
    listener.OnExpand(best.index);
    if (best.index == goal) {
      outcome = PlanOutcome::kFound;
      break;
    }
    update.Prepare(best.index);
    expansion.ForEachSuccessor(
        best.index, best.g,
        [&](uint32_t next, int32_t nx, int32_t ny, double next_g) {
          SearchScratch::Node& node = scratch.At(next);
          if (node.open_pos == SearchScratch::kClosed) return;
          const Offer offer =
              update.OfferTo(best.index, next, nx, ny, next_g, node);
          if (offer.g >= node.g) return;
          node.g = offer.g;
          node.parent = offer.parent;
          open.Push(next, priority(offer.g, next, nx, ny), offer.g);
        });
  }
  expansions = expanded;
  return outcome;
}

// Best-first search over grid cells from request.start to request.goal with
// the plain parent update: A*, Dijkstra, weighted A* and greedy, which differ
// only in `priority`. Records expansions when the request asks. Sets the
// result's outcome, expansions, path, cost and length (not planning_time).
// `Open` is the open list's type: OpenList, or MonotoneOpenList for f = g.
// Precondition: ValidateEndpoints passed and the grid has fewer than
// 2^32 - 1 cells.
template <typename Open = OpenList, typename Priority>
PlanResult GridBestFirstSearch(const Grid& grid, const PlanRequest& request,
                               const StopCondition& stop,
                               SearchScratch& scratch,
                               const Priority& priority) {
  const GridView view(grid, request.cost);
  const GridExpansion expansion(view);
  scratch.BeginSearch(grid.size());
  Open open(scratch);
  const uint32_t goal = expansion.Id(request.goal);
  PushRoot(scratch, open, expansion.Id(request.start), request.start, priority);
  PlanResult result;
  result.outcome = WithExpansionListener(
      request.expansion_recorder, expansion, [&](auto listener) {
        return BestFirstSearch(scratch, open, goal, stop, result.expansions,
                               priority, expansion, PlainParentUpdate(),
                               listener);
      });
  if (result.found()) {
    result.path = TracePath(view, scratch, goal, grid.size());
    result.cost = scratch.Raw(goal).g;
    result.length = PathLength(result.path);
  }
  return result;
}

}  // namespace pathd::internal

#endif  // PATHD_CORE_SEARCH_BEST_FIRST_H_
