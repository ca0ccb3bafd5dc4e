// The `voronoi` planner: a Voronoi roadmap "maximizes clearance" (Faigl,
// "Path Planning", Lecture 03, "Voronoi Graph") on the dynamic brushfire
// distance map and GVD of core/geometry/voronoi.h (Lau, Sprunk & Burgard,
// RAS 2013), answering with a legal 8-connected cell path.
//
// The objective is lexicographic: first the largest achievable clearance
// bottleneck B* (the smallest distance-map value over the path's cells), then
// the shortest way along the diagram. Searching the GVD cells alone cannot
// promise B*: the discrete diagram can break (a corridor of even width has a
// ridge two cells wide, diagonal ridges are staircases that a pinch may cut),
// and climbing from the start onto it may have to cross lower ground than the
// best route. So:
//  1. B* comes from a widest-path search over all free cells (Dijkstra on
//     the bottleneck, which is isotone), with labels capped at
//     min(d(start), d(goal)), a bound no path can beat; among equal labels
//     the search is A* on the octile length, so wide-open maps cost A*'s work.
//  2. The path is the cheapest one over cells with clearance >= B*, where a
//     step onto a GVD cell costs its length and a step onto any other cell
//     kOffDiagramFactor times its length. It climbs to the diagram, follows
//     it and descends to the goal, leaving it only where it is broken or dips
//     below B*. (Maximising the bottleneck and then minimising length in one
//     Dijkstra is not sound: a label with the better bottleneck may lose it
//     later and then be longer; two phases are.)
// min_clearance is B*, the distance map's value (octile distance from a cell
// centre to the nearest obstacle cell's centre or the map's outside) at the
// path's lowest cell.
#include <algorithm>
#include <cstdint>
#include <limits>
#include <memory>
#include <queue>
#include <string>
#include <tuple>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "core/geometry/voronoi.h"
#include "core/map/cost_model.h"
#include "core/planners/planners.h"
#include "core/search/derived.h"
#include "core/search/grid_planner.h"
#include "core/search/grid_view.h"
#include "core/status_macros.h"

namespace pathd {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
// What a step off the diagram costs per cell of length. 4 keeps the path on
// the diagram unless leaving it saves three quarters of the way; larger
// factors make detours along long GVD branches worth little shortcuts.
constexpr double kOffDiagramFactor = 4.0;

// The field of `grid`; null when `stop` fired first, building it or
// waiting for another query's build. An advance (O(cells whose nearest
// obstacle changed)) does not poll.
std::shared_ptr<const VoronoiField> Field(const Grid& grid, const PlanRequest& request,
                                          DerivedStop& stop) {
  const bool unknown_is_free = request.cost.unknown_is_free;
  return GetDerived<VoronoiField>(
      request.derived, grid,
      std::string("voronoi:unknown_is_free=") + (unknown_is_free ? "1" : "0"),
      "the Voronoi field of this map version", stop,
      [unknown_is_free](const Grid& g, DerivedStop& s) {
        return VoronoiField::Build(g, unknown_is_free, s);
      },
      [](const VoronoiField& previous, const Grid& g,
         absl::Span<const Cell> changed, DerivedStop&)
          -> std::shared_ptr<const VoronoiField> {
        auto next = std::make_shared<VoronoiField>(previous);
        next->Update(g, changed);
        return next;
      },
      [](const VoronoiField& f) { return f.bytes(); });
}

// The 8-connected moves without corner cutting over a field's free cells.
template <typename Visit>
void ForEachMove(const VoronoiField& field, Cell c, Visit&& visit) {
  auto free = [&](int32_t x, int32_t y) {
    return x >= 0 && y >= 0 && x < field.width() && y < field.height() &&
           !field.Blocked(Cell{x, y});
  };
  for (const Move& m : kMoves) {
    const Cell n{c.x + m.dx, c.y + m.dy};
    if (!free(n.x, n.y)) continue;
    if (m.dx != 0 && m.dy != 0 &&
        (!free(c.x + m.dx, c.y) || !free(c.x, c.y + m.dy))) {
      continue;
    }
    visit(n, m.length);
  }
}

double Octile(Cell a, Cell b) {
  return OctileLength::Between(a.x - b.x, a.y - b.y).value();
}

class VoronoiSearch {
 public:
  VoronoiSearch(const VoronoiField& field, const PlanRequest& request,
                const StopCondition& stop)
      : field_(field),
        request_(request),
        stop_(stop),
        size_(static_cast<size_t>(field.width()) * field.height()),
        g_(size_, kInfinity),
        closed_(size_, false) {}

  // Phase 1: the best bottleneck B* into `bottleneck`, or why not.
  PlanOutcome WidestBottleneck(double& bottleneck) {
    const double cap = std::min(field_.Clearance(request_.start),
                                field_.Clearance(request_.goal));
    std::vector<double> best(size_, -kInfinity);
    // (bottleneck, -f, -g, index): the widest first, then the A* order.
    using Entry = std::tuple<double, double, double, size_t>;
    std::priority_queue<Entry> open;
    const size_t start = Index(request_.start);
    best[start] = cap;
    g_[start] = 0.0;
    open.emplace(cap, -Octile(request_.start, request_.goal), 0.0, start);
    while (!open.empty()) {
      // Named copies, not a structured binding: clang 14 (the thread-safety
      // check) cannot capture bindings in the lambda below.
      const double b = std::get<0>(open.top());
      const double neg_f = std::get<1>(open.top());
      const double neg_g = std::get<2>(open.top());
      const size_t i = std::get<3>(open.top());
      open.pop();
      if (closed_[i]) continue;
      if (const PlanOutcome o = Expand(i, -neg_f); o != PlanOutcome::kFound)
        return o;
      const Cell c = CellAt(i);
      if (c == request_.goal) {
        bottleneck = b;
        return PlanOutcome::kFound;
      }
      ForEachMove(field_, c, [&](Cell n, double step) {
        const size_t j = Index(n);
        if (closed_[j]) return;
        const double nb = std::min(b, field_.Clearance(n));
        const double ng = -neg_g + step;
        if (nb < best[j] || (nb == best[j] && ng >= g_[j])) return;
        best[j] = nb;
        g_[j] = ng;
        open.emplace(nb, -(ng + Octile(n, request_.goal)), -ng, j);
      });
    }
    return PlanOutcome::kNoPath;
  }

  // Phase 2: the cheapest path over cells of clearance >= `bottleneck`, GVD
  // steps cheap. Precondition: WidestBottleneck found `bottleneck`.
  PlanOutcome AlongDiagram(double bottleneck, std::vector<Cell>& path) {
    std::fill(g_.begin(), g_.end(), kInfinity);
    std::fill(closed_.begin(), closed_.end(), false);
    std::vector<size_t> parent(size_, size_);
    using Entry = std::pair<double, size_t>;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
    const size_t start = Index(request_.start);
    g_[start] = 0.0;
    open.emplace(Octile(request_.start, request_.goal), start);
    while (!open.empty()) {
      const double f = open.top().first;
      const size_t i = open.top().second;
      open.pop();
      if (closed_[i]) continue;
      if (const PlanOutcome o = Expand(i, f); o != PlanOutcome::kFound)
        return o;
      const Cell c = CellAt(i);
      if (c == request_.goal) {
        for (size_t k = i; k != size_; k = parent[k]) path.push_back(CellAt(k));
        std::reverse(path.begin(), path.end());
        return PlanOutcome::kFound;
      }
      ForEachMove(field_, c, [&](Cell n, double step) {
        const size_t j = Index(n);
        if (closed_[j] || field_.Clearance(n) < bottleneck) return;
        const double g =
            g_[i] + step * (field_.OnDiagram(n) ? 1.0 : kOffDiagramFactor);
        if (g >= g_[j]) return;
        g_[j] = g;
        parent[j] = i;
        open.emplace(g + Octile(n, request_.goal), j);
      });
    }
    return PlanOutcome::kNoPath;  // unreachable: phase 1 found a way
  }

  int64_t expansions() const { return expansions_; }

 private:
  size_t Index(Cell c) const {
    return static_cast<size_t>(c.y) * field_.width() + c.x;
  }
  Cell CellAt(size_t i) const {
    return Cell{static_cast<int32_t>(i % field_.width()),
                static_cast<int32_t>(i / field_.width())};
  }
  // Polls the stop condition, then closes and records cell i.
  PlanOutcome Expand(size_t i, double f) {
    const PlanOutcome o = stop_.Check(expansions_, f);
    if (o != PlanOutcome::kFound) return o;
    ++expansions_;
    closed_[i] = true;
    if (request_.expansion_recorder != nullptr) {
      request_.expansion_recorder->Record(CellAt(i));
    }
    return PlanOutcome::kFound;
  }

  const VoronoiField& field_;
  const PlanRequest& request_;
  const StopCondition& stop_;
  const size_t size_;
  std::vector<double> g_;
  std::vector<bool> closed_;
  int64_t expansions_ = 0;
};

class VoronoiPlanner final : public GridPlanner {
 public:
  VoronoiPlanner()
      : GridPlanner(
            "voronoi",
            // Cell costs do not steer it (clearance does); they are charged
            // on the path it returns, as BFS does.
            PlannerTraits{
                .needs_eight_connected = true,
                .description =
                    "Voronoi roadmap on a dynamic brushfire distance map: the "
                    "largest achievable clearance, then the shortest way along "
                    "the Voronoi diagram; complete, not shortest"}) {}

 protected:
  absl::Status Validate(const Grid& grid,
                        const PlanRequest& request) const override {
    PATHD_RETURN_IF_ERROR(GridPlanner::Validate(grid, request));
    if (!VoronoiField::Fits(grid)) {
      return absl::FailedPreconditionError(
          absl::StrFormat("planner voronoi supports maps of up to 2^31 cells; "
                          "this one is %d x %d",
                          grid.width(), grid.height()));
    }
    return absl::OkStatus();
  }

  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    const Grid& grid = q.grid;
    const PlanRequest& request = q.request;
    PlanResult result;
    // Polled before the field is fetched, so an expired request costs no
    // build.
    result.outcome = q.stop.Check(0);
    if (result.outcome != PlanOutcome::kFound) return result;
    DerivedStop stop(q.stop);
    const std::shared_ptr<const VoronoiField> field = Field(grid, request, stop);
    if (field == nullptr) return StoppedWhileDeriving(stop);
    VoronoiSearch search(*field, request, q.stop);
    double bottleneck = 0.0;
    result.outcome = search.WidestBottleneck(bottleneck);
    std::vector<Cell> path;
    if (result.found()) result.outcome = search.AlongDiagram(bottleneck, path);
    result.expansions = search.expansions();
    if (!result.found()) return result;
    result.min_clearance = bottleneck;
    internal::SetMeasuredPath(grid, request.cost, std::move(path), &result);
    return result;
  }
};

}  // namespace

std::unique_ptr<Planner> MakeVoronoiPlanner() {
  return std::make_unique<VoronoiPlanner>();
}

}  // namespace pathd
