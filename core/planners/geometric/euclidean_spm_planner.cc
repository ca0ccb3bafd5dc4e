// euclidean_spm: exact Euclidean shortest paths answered from the goal's
// shortest path map (core/geometry/euclidean_spm.h). The map is a derived
// value per (map version, goal, unknown_is_free), so the server builds it
// once per goal and every later start costs one table read plus one step per
// bend of its path.
#include <cstdint>
#include <memory>
#include <vector>

#include "core/geometry/euclidean_spm.h"
#include "core/geometry/free_space.h"
#include "core/geometry/visibility_graph.h"
#include "core/map/cost_model.h"
#include "core/planners/planners.h"
#include "core/search/derived.h"
#include "core/search/grid_planner.h"

namespace pathd {
namespace {

class EuclideanSpmPlanner final : public GridPlanner {
 public:
  EuclideanSpmPlanner()
      : GridPlanner("euclidean_spm", [] {
          PlannerTraits t;
          t.optimal = true;
          t.geometric = true;
          t.needs_uniform_cost = true;
          t.needs_eight_connected = true;
          t.description =
              "Euclidean shortest path map of the goal over the visibility "
              "graph, kept per (map version, goal): any start answered by "
              "point location and following roots; exact";
          return t;
        }()) {}

 protected:
  // result.expansions counts the roots followed from the start to the goal
  // (the map itself is built, or taken from the store, before).
  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    const PlanRequest& request = q.request;
    DerivedStop stop(q.stop);
    const std::shared_ptr<const EuclideanSpm> spm = GetEuclideanSpm(
        request.derived, q.grid, request.goal, request.cost.unknown_is_free, stop);
    if (spm == nullptr) return StoppedWhileDeriving(stop);
    const FreeSpace& space = spm->graph().space();
    PlanResult result;
    std::vector<LatticePoint> polyline = {CentreOf(request.start)};
    uint32_t root = spm->RootOf(request.start);
    if (root == EuclideanSpm::kNoRoot) {
      result.outcome = PlanOutcome::kNoPath;
      return result;
    }
    // The start's own root is the goal when start == goal.
    while (root != EuclideanSpm::kNoRoot) {
      const PlanOutcome stop = q.stop.Check(result.expansions, spm->RootDistance(root));
      if (stop != PlanOutcome::kFound) {
        result.outcome = stop;
        return result;
      }
      ++result.expansions;
      if (!(spm->RootPoint(root) == polyline.back())) {
        polyline.push_back(spm->RootPoint(root));
      }
      root = spm->NextRoot(root);
    }
    FillPolylineResult(space, polyline,
                       CellFactor(q.grid.cost(request.start), request.cost.cost_weight),
                       result);
    return result;
  }
};

}  // namespace

std::unique_ptr<Planner> MakeEuclideanSpmPlanner() {
  return std::make_unique<EuclideanSpmPlanner>();
}

}  // namespace pathd
