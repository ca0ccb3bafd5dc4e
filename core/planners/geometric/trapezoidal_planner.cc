// The `trapezoidal` planner (Faigl, "Path Planning", Lecture 03, "Cell
// Decomposition"): A* over the boundaries the trapezoids of
// core/geometry/trapezoidal.h share, plus the start and the goal; two
// boundary points of one trapezoid are joined by a straight segment (it is
// convex). The channel of trapezoids that path crosses is then pulled tight
// by the funnel algorithm, the shortest path inside that channel. Complete
// (the adjacency graph is connected exactly where free space is), not
// optimal: the channel is chosen by the lengths of paths through boundary
// points, not by the lengths of the pulled strings.
//
// A boundary is represented by its midpoint, the lecture's node, and by its
// two ends. With midpoints alone two channels of equal midpoint length tie
// however different their pulled lengths (around either side of a single
// blocked cell: 3.29 against 2.41 cells), and on 126,470 random maps of 2..7
// x 2..7 cells 145 paths came out longer than the 8-connected grid optimum
// (by up to 2.08 cells). The ends are the obstacle corners a pulled string
// bends at; with them 11 still do (by up to 0.29 cells). Only a node at every
// lattice point of every boundary would rule it out (a grid path crosses
// boundaries at such points), at a cost quadratic in boundary length.
#include <algorithm>
#include <cstdint>
#include <limits>
#include <memory>
#include <queue>
#include <string>
#include <vector>

#include "core/geometry/free_space.h"
#include "core/geometry/trapezoidal.h"
#include "core/map/cost_model.h"
#include "core/planners/planners.h"
#include "core/search/derived.h"
#include "core/search/grid_planner.h"

namespace pathd {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// The decomposition of `grid`; null when `stop` fired first, building it
// or waiting for another query's build.
std::shared_ptr<const TrapezoidalDecomposition> Decomposition(
    const Grid& grid, const PlanRequest& request, DerivedStop& stop) {
  const bool unknown_is_free = request.cost.unknown_is_free;
  return GetDerived<TrapezoidalDecomposition>(
      request.derived, grid,
      std::string("trapezoidal:unknown_is_free=") +
          (unknown_is_free ? "1" : "0"),
      "the trapezoidal decomposition of this map version", stop,
      [unknown_is_free](const Grid& g, DerivedStop& s) {
        return TrapezoidalDecomposition::Build(g, unknown_is_free, s);
      },
      // A change can merge or split trapezoids of any length across its
      // column; rebuilding is one sweep, O(cells).
      [](const TrapezoidalDecomposition&, const Grid&, absl::Span<const Cell>,
         DerivedStop&) -> std::shared_ptr<const TrapezoidalDecomposition> {
        return nullptr;
      },
      [](const TrapezoidalDecomposition& d) { return d.bytes(); });
}

// A* over boundary points: each portal's midpoint and its two ends. Node
// ids: kNodesPerPortal per portal, then the start, then the goal.
class BoundarySearch {
 public:
  static constexpr int32_t kNodesPerPortal = 3;

  BoundarySearch(const TrapezoidalDecomposition& d, LatticePoint start,
                 int32_t start_trapezoid, LatticePoint goal,
                 int32_t goal_trapezoid)
      : d_(d),
        start_node_(static_cast<int32_t>(d.portals().size()) * kNodesPerPortal),
        goal_node_(start_node_ + 1),
        goal_trapezoid_(goal_trapezoid),
        start_trapezoid_(start_trapezoid),
        goal_(goal),
        g_(goal_node_ + 1, kInfinity),
        parent_(goal_node_ + 1, -1),
        closed_(goal_node_ + 1, false) {
    points_.reserve(goal_node_ + 1);
    for (const CellBoundary& p : d.portals()) {
      points_.push_back(p.Midpoint());
      points_.push_back(CornerAt(p.x, p.y0));
      points_.push_back(CornerAt(p.x, p.y1));
    }
    points_.push_back(start);
    points_.push_back(goal);
  }

  // Runs to the goal or until `stop` fires.
  PlanOutcome Run(const StopCondition& stop, int64_t& expansions) {
    g_[start_node_] = 0.0;
    open_.push({Distance(points_[start_node_], goal_), start_node_});
    while (!open_.empty()) {
      const auto [f, node] = open_.top();
      open_.pop();
      if (closed_[node]) continue;
      const PlanOutcome check = stop.Check(expansions, f);
      if (check != PlanOutcome::kFound) return check;
      ++expansions;
      closed_[node] = true;
      if (node == goal_node_) return PlanOutcome::kFound;
      if (node == start_node_) {
        Relax(node, start_trapezoid_);
      } else {
        Relax(node, d_.portals()[node / kNodesPerPortal].left);
        Relax(node, d_.portals()[node / kNodesPerPortal].right);
      }
    }
    return PlanOutcome::kNoPath;
  }

  // The portals the path crosses, start to goal, each with the direction it
  // is crossed in. Consecutive nodes on one portal (a path may run along it
  // between them) cross it at most once: whether it does follows from the
  // trapezoid the next node or the goal lies in.
  std::vector<Gate> Channel() const {
    std::vector<int32_t> portals;
    for (int32_t n = parent_[goal_node_]; n != start_node_; n = parent_[n]) {
      const int32_t p = n / kNodesPerPortal;
      if (portals.empty() || portals.back() != p) portals.push_back(p);
    }
    std::reverse(portals.begin(), portals.end());
    std::vector<Gate> gates;
    int32_t at = start_trapezoid_;
    for (size_t i = 0; i < portals.size(); ++i) {
      const CellBoundary& p = d_.portals()[portals[i]];
      const int32_t other = p.left == at ? p.right : p.left;
      const bool next_beyond =
          i + 1 < portals.size()
              ? d_.portals()[portals[i + 1]].left == other ||
                    d_.portals()[portals[i + 1]].right == other
              : other == goal_trapezoid_;
      if (!next_beyond) continue;  // touched, not crossed
      gates.push_back(GateOf(p, p.left == at));
      at = other;
    }
    return gates;
  }

 private:
  // Offers every other boundary point of trapezoid t to `from`.
  void Relax(int32_t from, int32_t t) {
    for (int32_t p : d_.PortalsOf(t)) {
      for (int32_t k = 0; k < kNodesPerPortal; ++k)
        Offer(from, p * kNodesPerPortal + k);
    }
    if (t == goal_trapezoid_) Offer(from, goal_node_);
  }
  void Offer(int32_t from, int32_t to) {
    if (closed_[to]) return;
    const double g = g_[from] + Distance(points_[from], points_[to]);
    if (g >= g_[to]) return;
    g_[to] = g;
    parent_[to] = from;
    open_.push({g + Distance(points_[to], goal_), to});
  }

  using Entry = std::pair<double, int32_t>;
  const TrapezoidalDecomposition& d_;
  const int32_t start_node_;
  const int32_t goal_node_;
  const int32_t goal_trapezoid_;
  const int32_t start_trapezoid_;
  const LatticePoint goal_;
  std::vector<LatticePoint> points_;
  std::vector<double> g_;
  std::vector<int32_t> parent_;
  std::vector<bool> closed_;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open_;
};

class TrapezoidalPlanner final : public GridPlanner {
 public:
  TrapezoidalPlanner()
      : GridPlanner(
            "trapezoidal",
            PlannerTraits{
                .needs_uniform_cost = true,
                .needs_eight_connected = true,
                .geometric = true,
                .description =
                    "vertical trapezoidal cell decomposition: A* over the "
                    "midpoints and ends of shared cell boundaries, then the "
                    "funnel pulls the path tight in its channel; complete, "
                    "not optimal"}) {}

 protected:
  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    const Grid& grid = q.grid;
    const PlanRequest& request = q.request;
    PlanResult result;
    // Polled before the decomposition is fetched, so an expired request
    // costs no build.
    result.outcome = q.stop.Check(0);
    if (result.outcome != PlanOutcome::kFound) return result;
    DerivedStop stop(q.stop);
    const std::shared_ptr<const TrapezoidalDecomposition> d =
        Decomposition(grid, request, stop);
    if (d == nullptr) return StoppedWhileDeriving(stop);
    const LatticePoint start = CentreOf(request.start);
    const LatticePoint goal = CentreOf(request.goal);
    const int32_t start_trapezoid = d->TrapezoidOf(request.start);
    const int32_t goal_trapezoid = d->TrapezoidOf(request.goal);
    std::vector<LatticePoint> polyline{start, goal};
    if (start_trapezoid != goal_trapezoid) {
      BoundarySearch search(*d, start, start_trapezoid, goal, goal_trapezoid);
      result.outcome = search.Run(q.stop, result.expansions);
      if (result.outcome != PlanOutcome::kFound) return result;
      polyline = PullString(start, goal, search.Channel());
    } else if (start == goal) {
      polyline.pop_back();
    }
    // The map is uniform (needs_uniform_cost): every cell costs the start's.
    FillPolylineResult(d->space(), polyline,
                       CellFactor(grid.cost(request.start), request.cost.cost_weight),
                       result);
    return result;
  }
};

}  // namespace

std::unique_ptr<Planner> MakeTrapezoidalPlanner() {
  return std::make_unique<TrapezoidalPlanner>();
}

}  // namespace pathd
