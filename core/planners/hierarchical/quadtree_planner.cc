// The `quadtree` planner: A* over the leaf adjacency of the region quadtree
// (quadtree.h; lecture "Spatial Decomposition"), refined to grid moves.
// A leaf holds cells of one cost, so every cell of it is open and costs the
// same factor, and any two of its cells are joined inside it by the
// canonical move chain (diagonal steps, then straight ones; straight ones
// only when 4-connected) whose diagonal side cells lie inside it too. The
// search's node is a leaf together with the cell it was entered by: a move
// to an edge-adjacent open leaf walks inside the current leaf to a cell on
// the shared edge and steps straight across. Where on the edge is chosen
// per move (the point nearest the entry cell or nearest the goal's row or
// column, whichever looks cheaper to the goal), so the answer is not optimal
// (docs/performance.md measures it); it is complete, because grid moves
// between leaves are straight moves across a shared edge or diagonal ones
// whose side cells give two such, and the search closes each leaf once.
#include <algorithm>
#include <cstdlib>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/planners/hierarchical/quadtree.h"
#include "core/planners/planners.h"
#include "core/search/best_first.h"
#include "core/search/derived.h"
#include "core/search/grid_planner.h"
#include "core/search/heuristics.h"

namespace pathd {
namespace {

using internal::GridView;

// What `quadtree` keeps in a SearchScratch: per leaf the cells it was
// entered by and left its parent by, and without a derived store the last
// tree with a copy of its grid (as hpa_star does).
struct QuadtreeScratch final : public SearchScratch::Extension {
  std::vector<Cell> entry;
  std::vector<Cell> exit;
  // The parent-side cell of the move being offered.
  Cell pending_exit;

  bool unknown_is_free = false;
  int32_t width = 0;
  int32_t height = 0;
  std::vector<uint8_t> grid_cells;
  std::shared_ptr<const Quadtree> tree;

  size_t MemoryBytes() const override {
    return (entry.capacity() + exit.capacity()) * sizeof(Cell) + grid_cells.capacity() +
           (tree != nullptr ? tree->MemoryBytes() : 0);
  }
};

std::shared_ptr<const Quadtree> TreeFor(const Grid& grid, const PlanRequest& request,
                                        DerivedStop& stop, QuadtreeScratch& state) {
  const bool unknown_is_free = request.cost.unknown_is_free;
  if (request.derived != nullptr) {
    return GetDerived<Quadtree>(
        request.derived, grid,
        std::string("quadtree unknown_is_free=") + (unknown_is_free ? "1" : "0"),
        "the quadtree of this map version", stop,
        [unknown_is_free](const Grid& g, DerivedStop& s) {
          return Quadtree::Build(g, unknown_is_free, s);
        },
        [](const Quadtree& previous, const Grid& g, absl::Span<const Cell> changed,
           DerivedStop&) { return previous.Advance(g, changed); },
        [](const Quadtree& tree) { return tree.MemoryBytes(); });
  }
  const bool same_shape = state.tree != nullptr && state.unknown_is_free == unknown_is_free &&
                          state.width == grid.width() && state.height == grid.height();
  if (same_shape && state.grid_cells == grid.cells()) return state.tree;
  std::shared_ptr<const Quadtree> tree;
  if (same_shape) {
    std::vector<Cell> changed;
    for (size_t i = 0; i < grid.size(); ++i) {
      if (state.grid_cells[i] != grid.cells()[i]) changed.push_back(grid.CellAt(i));
    }
    tree = state.tree->Advance(grid, changed);
  } else {
    tree = Quadtree::Build(grid, unknown_is_free, stop);
  }
  if (tree == nullptr) return nullptr;
  state.unknown_is_free = unknown_is_free;
  state.width = grid.width();
  state.height = grid.height();
  state.grid_cells = grid.cells();
  state.tree = tree;
  return tree;
}

// Moves between two cells of one leaf: octile or Manhattan.
double Within(Cell a, Cell b, Connectivity connectivity) {
  return GridDistance(a, b, connectivity);
}

// The expansion policy: node ids are leaf ids, plus goal_id for the goal.
class QuadtreeExpansion {
 public:
  QuadtreeExpansion(const Quadtree& tree, const GridView& view, QuadtreeScratch& state,
                    Cell goal, Connectivity connectivity)
      : tree_(tree),
        view_(view),
        state_(state),
        goal_(goal),
        goal_id_(static_cast<uint32_t>(tree.node_slots())),
        connectivity_(connectivity) {}

  uint32_t goal_id() const { return goal_id_; }
  uint32_t Id(Cell c) const {
    return c == goal_ ? goal_id_ : static_cast<uint32_t>(tree_.Locate(c.x, c.y));
  }
  Cell CellOf(uint32_t id) const { return id == goal_id_ ? goal_ : state_.entry[id]; }

  template <typename Visit>
  void ForEachSuccessor(uint32_t id, double g, Visit&& visit) const {
    const Quadtree::Node& leaf = tree_.node(static_cast<int32_t>(id));
    const Cell p = state_.entry[id];
    const double factor = view_.Factor(view_.Index(p.x, p.y));
    const int32_t x1 = std::min(leaf.x0 + leaf.size, tree_.width());
    const int32_t y1 = std::min(leaf.y0 + leaf.size, tree_.height());
    if (goal_.x >= leaf.x0 && goal_.x < x1 && goal_.y >= leaf.y0 && goal_.y < y1) {
      state_.pending_exit = p;
      visit(goal_id_, goal_.x, goal_.y, g + Within(p, goal_, connectivity_) * factor);
    }
    // Along each side, every open leaf across it, one at a time.
    auto side = [&](bool vertical, int32_t across, int32_t inside, int32_t from, int32_t to) {
      for (int32_t t = from; t < to;) {
        const Cell probe = vertical ? Cell{across, t} : Cell{t, across};
        const int32_t m = tree_.Locate(probe.x, probe.y);
        const Quadtree::Node& next = tree_.node(m);
        const int32_t next_from = vertical ? next.y0 : next.x0;
        const int32_t lo = std::max(from, next_from);
        const int32_t hi = std::min(to, next_from + next.size);
        if (next.open()) Cross(vertical, across, inside, lo, hi, p, factor, m, g, visit);
        t = hi;
      }
    };
    if (x1 < tree_.width()) side(true, x1, x1 - 1, leaf.y0, y1);
    if (leaf.x0 > 0) side(true, leaf.x0 - 1, leaf.x0, leaf.y0, y1);
    if (y1 < tree_.height()) side(false, y1, y1 - 1, leaf.x0, x1);
    if (leaf.y0 > 0) side(false, leaf.y0 - 1, leaf.y0, leaf.x0, x1);
  }

 private:
  // Offers leaf m across a shared edge: positions [lo, hi) along it, the
  // line `inside` in this leaf and `across` in m.
  template <typename Visit>
  void Cross(bool vertical, int32_t across, int32_t inside, int32_t lo, int32_t hi, Cell p,
             double factor, int32_t m, double g, Visit& visit) const {
    auto at = [&](int32_t t, int32_t line) { return vertical ? Cell{line, t} : Cell{t, line}; };
    const double next_factor = view_.Factor(view_.Index(at(lo, across).x, at(lo, across).y));
    const int32_t candidates[2] = {std::clamp(vertical ? p.y : p.x, lo, hi - 1),
                                   std::clamp(vertical ? goal_.y : goal_.x, lo, hi - 1)};
    double best = -1;
    int32_t chosen = candidates[0];
    for (const int32_t t : candidates) {
      const double estimate = Within(p, at(t, inside), connectivity_) * factor +
                              Within(at(t, across), goal_, connectivity_);
      if (best < 0 || estimate < best) {
        best = estimate;
        chosen = t;
      }
    }
    const Cell a = at(chosen, inside);
    const Cell b = at(chosen, across);
    state_.pending_exit = a;
    visit(static_cast<uint32_t>(m), b.x, b.y,
          g + Within(p, a, connectivity_) * factor + next_factor);
  }

  const Quadtree& tree_;
  const GridView& view_;
  QuadtreeScratch& state_;
  const Cell goal_;
  const uint32_t goal_id_;
  const Connectivity connectivity_;
};

// The plain parent update, also recording the cells a leaf is entered and
// left by when its offer is taken (the loop takes an offer exactly when its
// g is below the node's).
struct EntryParentUpdate {
  QuadtreeScratch& state;
  bool OnPop(SearchScratch::OpenEntry&, internal::OpenList&) { return true; }
  void Prepare(uint32_t) {}
  internal::Offer OfferTo(uint32_t id, uint32_t next, int32_t nx, int32_t ny, double next_g,
                          const SearchScratch::Node& node) {
    if (next_g < node.g) {
      state.entry[next] = Cell{nx, ny};
      state.exit[next] = state.pending_exit;
    }
    return internal::Offer{next_g, id};
  }
};

// Appends the canonical move chain from `from` (already in `path`) to `to`.
void Walk(Cell from, Cell to, Connectivity connectivity, std::vector<Cell>& path) {
  Cell at = from;
  while (!(at == to)) {
    const int32_t sx = (to.x > at.x) - (to.x < at.x);
    const int32_t sy = (to.y > at.y) - (to.y < at.y);
    if (connectivity == Connectivity::kEight || sx == 0 || sy == 0) {
      at = Cell{at.x + sx, at.y + sy};
    } else {
      at = Cell{at.x + sx, at.y};
    }
    path.push_back(at);
  }
}

class QuadtreePlanner final : public GridPlanner {
 public:
  QuadtreePlanner()
      : GridPlanner("quadtree",
                    PlannerTraits{
                        .description =
                            "A* over the leaves of a region quadtree of the map (kept "
                            "per map version, updated around changed cells), refined to "
                            "grid moves; complete, not optimal"}) {}

 protected:
  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    const Grid& grid = q.grid;
    const PlanRequest& request = q.request;
    const StopCondition& stop = q.stop;
    PlanResult result;
    result.outcome = stop.Check(0);
    if (result.outcome != PlanOutcome::kFound) return result;
    if (request.start == request.goal) {
      result.path = {request.start};
      return result;
    }
    QuadtreeScratch& state = q.scratch.extension<QuadtreeScratch>();
    DerivedStop derived_stop(stop);
    const std::shared_ptr<const Quadtree> tree = TreeFor(grid, request, derived_stop, state);
    if (tree == nullptr) return StoppedWhileDeriving(derived_stop);

    const GridView view(grid, request.cost);
    const Connectivity connectivity = request.cost.connectivity;
    SearchScratch& scratch = q.scratch;
    scratch.BeginSearch(tree->node_slots() + 1);
    state.entry.resize(tree->node_slots() + 1);
    state.exit.resize(tree->node_slots() + 1);
    const QuadtreeExpansion expansion(*tree, view, state, request.goal, connectivity);
    const uint32_t start = static_cast<uint32_t>(tree->Locate(request.start.x, request.start.y));
    state.entry[start] = request.start;
    const internal::AStarPriority<internal::GridDistanceHeuristic> priority{
        {request.goal, connectivity}};
    internal::OpenList open(scratch);
    internal::PushRoot(scratch, open, start, request.start, priority);
    const uint32_t goal = expansion.goal_id();
    result.outcome = internal::WithExpansionListener(
        request.expansion_recorder, expansion, [&](auto listener) {
          return internal::BestFirstSearch(scratch, open, goal, stop, result.expansions,
                                           priority, expansion, EntryParentUpdate{state},
                                           listener);
        });
    if (!result.found()) return result;
    // Leaves from the start's to the goal's; each later one was entered
    // from the one before it.
    std::vector<uint32_t> chain;
    for (uint32_t at = scratch.Raw(goal).parent; at != SearchScratch::kNoParent;
         at = scratch.Raw(at).parent) {
      chain.push_back(at);
      if (chain.size() > tree->node_slots()) return absl::InternalError("quadtree: parent loop");
    }
    std::reverse(chain.begin(), chain.end());
    std::vector<Cell> path{request.start};
    for (size_t i = 1; i < chain.size(); ++i) {
      Walk(path.back(), state.exit[chain[i]], connectivity, path);
      path.push_back(state.entry[chain[i]]);
    }
    Walk(path.back(), request.goal, connectivity, path);
    internal::SetMeasuredPath(grid, request.cost, std::move(path), &result);
    return result;
  }
};

}  // namespace

std::unique_ptr<Planner> MakeQuadtreePlanner() { return std::make_unique<QuadtreePlanner>(); }

}  // namespace pathd
