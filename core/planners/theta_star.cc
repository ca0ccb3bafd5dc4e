// Theta* (Nash, Daniel, Koenig & Felner, AAAI 2007; Daniel, Nash, Koenig &
// Felner, JAIR 39, 2010) and Lazy Theta* (Nash, Koenig & Tovey, AAAI 2010):
// any-angle search as a parent-update policy on the A* loop and open list of
// best_first.h. A successor may link straight to its parent's parent when the
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
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>

#include "absl/time/clock.h"
#include "core/search/path_measure.h"
#include "core/search/endpoints.h"
#include "core/search/line_of_sight.h"
#include "core/search/best_first.h"
#include "core/planners/planners.h"
#include "core/search/grid_view.h"
#include "core/status_macros.h"

namespace pathd {
namespace {

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

// Straight-line distance to the goal: admissible and consistent because every
// segment costs at least its length (cell factors are >= 1).
struct EuclideanHeuristic {
  Cell goal;
  double operator()(Cell c) const {
    const double dx = static_cast<double>(c.x) - goal.x;
    const double dy = static_cast<double>(c.y) - goal.y;
    return std::sqrt(dx * dx + dy * dy);
  }
};

// One Theta* (kLazy: Lazy Theta*) query over the caller's SearchScratch.
// Single use; not thread-safe.
template <bool kLazy>
class AnyAngleSearch {
 public:
  AnyAngleSearch(const Grid& grid, const PlanRequest& request,
                 SearchScratch& scratch)
      : grid_(grid),
        recorder_(request.expansion_recorder),
        view_(grid, request.cost),
        scratch_(scratch),
        open_(scratch),
        h_{request.goal},
        start_(view_.Index(request.start.x, request.start.y)),
        goal_(view_.Index(request.goal.x, request.goal.y)) {}

  PlanResult Run(const StopCondition& stop) {
    PlanResult result;
    result.any_angle = true;
    result.outcome = PlanOutcome::kNoPath;
    scratch_.BeginSearch(grid_.size());
    scratch_.At(start_).g = 0.0;
    open_.Push(start_, h_(view_.CellOf(start_)), 0.0);
    int64_t expansions = 0;
    while (!open_.empty()) {
      if (const PlanOutcome why = stop.Check(expansions, open_.Top().f);
          why != PlanOutcome::kFound) {
        result.outcome = why;
        break;
      }
      const uint32_t index = open_.Pop().index;
      if constexpr (kLazy) {
        if (!SetVertex(index)) continue;
      }
      ++expansions;
      if (recorder_ != nullptr) recorder_->Record(view_.CellOf(index));
      if (index == goal_) {
        result.outcome = PlanOutcome::kFound;
        break;
      }
      Expand(index);
    }
    result.expansions = expansions;
    if (result.found()) {
      result.path = internal::TracePath(view_, scratch_, goal_, grid_.size());
      result.cost = scratch_.Raw(goal_).g;
      for (size_t i = 1; i < result.path.size(); ++i) {
        result.length += SegmentLength(result.path[i - 1], result.path[i]);
      }
    }
    return result;
  }

 private:
  // Offers every unexpanded neighbour n of the expanded cell s the better of
  // path 1 (s, then the move to n) and path 2 (s's parent, then a straight
  // segment to n); ties go to path 2, which saves a vertex.
  void Expand(uint32_t index) {
    const SearchScratch::Node& node = scratch_.Raw(index);
    const double g = node.g;
    const uint32_t parent = node.parent;
    const Cell parent_cell =
        parent == SearchScratch::kNoParent ? Cell{} : view_.CellOf(parent);
    const double parent_g =
        parent == SearchScratch::kNoParent ? 0.0 : scratch_.Raw(parent).g;
    const Cell at = view_.CellOf(index);
    view_.ForEachNeighbor(
        at.x, at.y,
        [&](uint32_t next, int32_t nx, int32_t ny, double move_length) {
          SearchScratch::Node& succ = scratch_.At(next);
          if (succ.open_pos == SearchScratch::kClosed) return;
          const double factor = view_.Factor(next);
          double best_g = g + move_length * factor;
          uint32_t best_parent = index;
          if (parent != SearchScratch::kNoParent) {
            const Cell n{nx, ny};
            // The segment enters n, so it costs at least its length times n's
            // factor: a lower bound that is exact on uniform maps.
            const double bound =
                parent_g + SegmentLength(parent_cell, n) * factor;
            if constexpr (kLazy) {
              // Assume line of sight; SetVertex checks it on expansion.
              if (bound <= best_g) {
                best_g = bound;
                best_parent = parent;
              }
            } else if (bound <= best_g && bound < succ.g) {
              // Only walk the segment when it could win.
              const double segment = ProbeSegment(view_, parent_cell, n);
              if (segment >= 0.0 && parent_g + segment <= best_g) {
                best_g = parent_g + segment;
                best_parent = parent;
              }
            }
          }
          if (best_g < succ.g) {
            succ.g = best_g;
            succ.parent = best_parent;
            open_.Push(next, best_g + h_(Cell{nx, ny}), best_g);
          }
        });
  }

  // Lazy Theta*'s SetVertex for a cell just taken off the open list: checks
  // the assumed segment from its parent and, when it is blocked or dearer than
  // assumed, takes the best path 1 through an expanded neighbour instead (the
  // cell that generated it is one, so there always is a way in). Returns
  // false when the corrected f is no longer the smallest: the cell is then
  // back in the open list, to be expanded in its turn.
  bool SetVertex(uint32_t index) {
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
    const double f = g + h_(at);
    if (!open_.empty() && f > open_.Top().f) {
      open_.Push(index, f, g);
      return false;
    }
    return true;
  }

  const Grid& grid_;
  ExpansionRecorder* const recorder_;
  const GridView view_;
  SearchScratch& scratch_;
  OpenList open_;
  const EuclideanHeuristic h_;
  const uint32_t start_;
  const uint32_t goal_;
};

template <bool kLazy>
class ThetaStarPlanner final : public Planner {
 public:
  std::string_view name() const override {
    return kLazy ? "lazy_theta_star" : "theta_star";
  }
  const PlannerTraits& traits() const override {
    static const PlannerTraits kTraits{
        .any_angle = true,
        .description =
            kLazy
                ? "Lazy Theta*: Theta* that checks line of sight only when it "
                  "expands a cell; any-angle, never costlier than the grid "
                  "optimum"
                : "Theta*: A* whose successors link to their parent's parent "
                  "when in line of sight; any-angle, never costlier than the "
                  "grid optimum"};
    return kTraits;
  }

  absl::StatusOr<PlanResult> Plan(const Grid& grid, const PlanRequest& request,
                                  const StopCondition& stop,
                                  SearchScratch& scratch) const override {
    PATHD_RETURN_IF_ERROR(ValidateRequest(grid, request, name(), traits()));
    const absl::Time started = absl::Now();
    AnyAngleSearch<kLazy> search(grid, request, scratch);
    PlanResult result = search.Run(stop);
    result.planning_time = absl::Now() - started;
    return result;
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
