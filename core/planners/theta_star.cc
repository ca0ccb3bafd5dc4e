// Theta* (Nash, Daniel, Koenig & Felner, AAAI 2007; Daniel, Nash, Koenig &
// Felner, JAIR 39, 2010) and Lazy Theta* (Nash, Koenig & Tovey, AAAI 2010):
// any-angle search as a parent-update policy (ThetaParentUpdate below) on the
// best-first loop and open list of core/search/best_first.h, with the
// Euclidean heuristic; Lazy Theta*'s line-of-sight check is the policy's
// on-pop hook. A successor may link straight to its parent's parent when the
// segment between them passes LineOfSight, so paths follow segments at any
// angle between the vertex cells; segment costs are SegmentCost.
//
// Both variants differ from the papers in two ways, to guarantee that a path
// never costs more than the grid optimum under the request's connectivity
// (octile distance on 8-connected uniform maps, Manhattan on 4-connected
// ones, Dijkstra's cost on weighted maps):
//  - The grid move (path 1) is always a candidate, not only when the parent's
//    parent is out of sight. On uniform maps path 2 is never worse when in
//    sight (triangle inequality), but on weighted maps a segment pays its
//    dearest cell over its whole length and can be.
//  - Lazy Theta* assumes line of sight when it generates a successor and
//    checks it when it expands it, falling back to the best expanded
//    neighbour. The fallback can raise g; the node is then put back into the
//    open list with its true f unless that still is the smallest, so cells
//    are expanded in order of true f as in Theta*.
// With both, induction over expansions shows that every expanded cell s has
// g(s) <= d(s), the grid distance from the start: the first unexpanded cell p
// on a shortest grid path to s was offered g(p) <= d(p) by its expanded
// predecessor, and s was chosen first, so g(s) + h(s) <= d(p) + h(p) <= d(s)
// + h(s) because the Euclidean heuristic h never exceeds grid distance.
//
// 4-connectivity: the grid neighbours (path 1) are the four straight moves;
// shortcuts (path 2) use the same LineOfSight rule, so segments may still run
// diagonally, and the bound above is the Manhattan optimum.
#include <cstdint>
#include <limits>
#include <memory>

#include "core/planners/planners.h"
#include "core/search/best_first.h"
#include "core/search/grid_planner.h"
#include "core/search/grid_view.h"
#include "core/search/heuristics.h"
#include "core/search/line_of_sight.h"

namespace pathd {
namespace {

using internal::EuclideanHeuristic;
using internal::GridView;
using internal::OpenList;

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// LineOfSight and SegmentCost in one walk, with the per-query tables: the
// segment's cost, or -1 when it is blocked. Bit-identical to SegmentCost, so
// the search's g equals what MeasureAnyAnglePath reports. Walks from b back to
// a: a is an expanded cell with a clear segment to its successor next to b,
// so an obstacle, if any, tends to be near b and the walk stops early.
// Precondition: a is traversable.
double ProbeSegment(const GridView& view, Cell a, Cell b) {
  const int64_t a_index = view.Index(a.x, a.y);
  double factor = 1.0;
  // Both ends are on the grid, so every cell in between is.
  const bool clear = ForEachCellOnSegmentIndexed(
      b, a, view.width(),
      [&](int32_t, int32_t, int64_t index, bool corner_only) {
        if (index == a_index) return true;  // the cell the segment leaves
        const auto i = static_cast<uint32_t>(index);
        if (!view.PassableAt(i)) return false;
        if (!corner_only) {
          const double f = view.Factor(i);
          if (f > factor) factor = f;
        }
        return true;
      });
  return clear ? SegmentLength(a, b) * factor : -1.0;
}

// Theta*'s parent update (kLazy: Lazy Theta*'s) over the caller's
// SearchScratch. Single use; not thread-safe.
template <bool kLazy>
class ThetaParentUpdate {
 public:
  ThetaParentUpdate(const GridView& view, SearchScratch& scratch,
                    EuclideanHeuristic h)
      : view_(view), scratch_(scratch), h_(h) {}

  // Lazy Theta*'s SetVertex for a cell just taken off the open list: checks
  // the assumed segment from its parent and, when it is blocked or dearer than
  // assumed, takes the best path 1 through an expanded neighbour instead (the
  // cell that generated it is one, so there always is a way in). Returns
  // false when the corrected f is no longer the smallest: the cell is then
  // back in the open list, to be expanded in its turn.
  bool OnPop(SearchScratch::OpenEntry& entry, OpenList& open) {
    if constexpr (!kLazy) return true;
    const uint32_t index = entry.index;
    SearchScratch::Node& node = scratch_.Raw(index);
    if (node.parent == SearchScratch::kNoParent) return true;  // the start
    const Cell at = view_.CellOf(index);
    const double segment = ProbeSegment(view_, view_.CellOf(node.parent), at);
    double g =
        segment >= 0.0 ? scratch_.Raw(node.parent).g + segment : kInfinity;
    // The assumption held: g is what the open list ordered it by.
    if (g <= node.g) return true;
    uint32_t parent = node.parent;
    const double factor = view_.Factor(index);
    view_.ForEachNeighbor(
        at.x, at.y, [&](uint32_t n, int32_t, int32_t, double move_length) {
          if (!scratch_.Seen(n) ||
              scratch_.Raw(n).open_pos != SearchScratch::kClosed) {
            return;
          }
          const double via = scratch_.Raw(n).g + move_length * factor;
          if (via < g) {
            g = via;
            parent = n;
          }
        });
    node.g = g;
    node.parent = parent;
    entry.g = g;
    const double f = g + h_(at.x, at.y);
    if (!open.empty() && OpenList::Key(f) > open.Top().f) {
      open.Push(index, f, g);
      return false;
    }
    return true;
  }

  // Caches the expanded cell's parent for the successors' path 2.
  void Prepare(uint32_t index) {
    parent_ = scratch_.Raw(index).parent;
    if (parent_ != SearchScratch::kNoParent) {
      parent_cell_ = view_.CellOf(parent_);
      parent_g_ = scratch_.Raw(parent_).g;
    }
  }

  // Offers the unexpanded neighbour n of the expanded cell s the better of
  // path 1 (s, then the move to n: `next_g`) and path 2 (s's parent, then a
  // straight segment to n); ties go to path 2, which saves a vertex.
  internal::Offer OfferTo(uint32_t index, uint32_t next, int32_t nx, int32_t ny,
                          double next_g, const SearchScratch::Node& succ) {
    internal::Offer best{next_g, index};
    if (parent_ == SearchScratch::kNoParent) return best;
    const Cell n{nx, ny};
    // The segment enters n, so it costs at least its length times n's
    // factor: a lower bound that is exact on uniform maps.
    const double bound =
        parent_g_ + SegmentLength(parent_cell_, n) * view_.Factor(next);
    if constexpr (kLazy) {
      // Assume line of sight; OnPop checks it on expansion.
      if (bound <= best.g) best = internal::Offer{bound, parent_};
    } else if (bound <= best.g && bound < succ.g) {
      // Only walk the segment when it could win.
      const double segment = ProbeSegment(view_, parent_cell_, n);
      if (segment >= 0.0 && parent_g_ + segment <= best.g) {
        best = internal::Offer{parent_g_ + segment, parent_};
      }
    }
    return best;
  }

 private:
  const GridView& view_;
  SearchScratch& scratch_;
  const EuclideanHeuristic h_;
  uint32_t parent_ = SearchScratch::kNoParent;
  Cell parent_cell_;
  double parent_g_ = 0.0;
};

// Theta* (kLazy: Lazy Theta*) from request.start to request.goal.
template <bool kLazy>
PlanResult AnyAngleSearch(const Grid& grid, const PlanRequest& request,
                          const StopCondition& stop, SearchScratch& scratch) {
  const GridView view(grid, request.cost);
  const internal::GridExpansion expansion(view);
  const EuclideanHeuristic h{request.goal};
  const internal::AStarPriority<EuclideanHeuristic> priority{h};
  scratch.BeginSearch(grid.size());
  OpenList open(scratch);
  const uint32_t goal = expansion.Id(request.goal);
  internal::PushRoot(scratch, open, expansion.Id(request.start), request.start,
                     priority);
  PlanResult result;
  result.any_angle = true;
  result.outcome = internal::WithExpansionListener(
      request.expansion_recorder, expansion, [&](auto listener) {
        return internal::BestFirstSearch(
            scratch, open, goal, stop, result.expansions, priority, expansion,
            ThetaParentUpdate<kLazy>(view, scratch, h), listener);
      });
  if (result.found()) {
    result.path = internal::TracePath(view, scratch, goal, grid.size());
    result.cost = scratch.Raw(goal).g;
    for (size_t i = 1; i < result.path.size(); ++i) {
      result.length += SegmentLength(result.path[i - 1], result.path[i]);
    }
  }
  return result;
}

template <bool kLazy>
class ThetaStarPlanner final : public GridPlanner {
 public:
  ThetaStarPlanner()
      : GridPlanner(
            kLazy ? "lazy_theta_star" : "theta_star",
            PlannerTraits{
                .any_angle = true,
                .description =
                    kLazy
                        ? "Lazy Theta*: Theta* that checks line of sight only "
                          "when it expands a cell; any-angle, never costlier "
                          "than the grid optimum"
                        : "Theta*: A* whose successors link to their parent's "
                          "parent when in line of sight; any-angle, never "
                          "costlier than the grid optimum"}) {}

 protected:
  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    return AnyAngleSearch<kLazy>(q.grid, q.request, q.stop, q.scratch);
  }
};

}  // namespace

std::unique_ptr<Planner> MakeThetaStarPlanner() {
  return std::make_unique<ThetaStarPlanner<false>>();
}
std::unique_ptr<Planner> MakeLazyThetaStarPlanner() {
  return std::make_unique<ThetaStarPlanner<true>>();
}

}  // namespace pathd
