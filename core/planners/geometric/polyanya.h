// Polyanya (Cui, Harabor & Grastien, "Compromise-free Pathfinding on a
// Navigation Mesh", IJCAI 2017): optimal any-angle search on a navigation
// mesh (core/geometry/navmesh.h). A search node is an interval of a mesh
// edge and a root from which every point of the interval is visible; its
// successors project the interval through the next polygon, keeping the
// root (observable) or turning at an obstacle corner at one of its ends
// (non-observable). The answer is a Euclidean shortest path in the free
// space of core/geometry/free_space.h.
#ifndef PATHD_CORE_PLANNERS_GEOMETRIC_POLYANYA_H_
#define PATHD_CORE_PLANNERS_GEOMETRIC_POLYANYA_H_

#include <cstdint>
#include <vector>

#include "core/geometry/free_space.h"
#include "core/geometry/navmesh.h"
#include "core/map/grid.h"
#include "core/search/plan_types.h"
#include "core/search/search_scratch.h"
#include "core/search/stop_condition.h"

namespace pathd {

struct PolyanyaPath {
  // kFound, kNoPath, or why the stop condition ended the search.
  PlanOutcome outcome = PlanOutcome::kNoPath;
  // Start cell centre, the obstacle corners it bends at, goal cell centre;
  // one point when start == goal; empty unless found.
  std::vector<LatticePoint> polyline;
  // Search nodes taken from the open list.
  int64_t expansions = 0;
};

// The shortest path from the centre of `start` to the centre of `goal`
// through `mesh`, which must be the mesh of `grid` (same cells, its
// unknown_is_free). Preconditions: both cells on the grid and free. Polls
// `stop` before the first expansion and every StopCondition::kPollInterval
// expansions. Keeps its buffers in `scratch`.
PolyanyaPath PolyanyaSearch(const NavMesh& mesh, const Grid& grid, Cell start,
                            Cell goal, const StopCondition& stop,
                            SearchScratch& scratch);

}  // namespace pathd

#endif  // PATHD_CORE_PLANNERS_GEOMETRIC_POLYANYA_H_
