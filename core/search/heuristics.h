// The heuristics of the grid searches, as functors h(x, y) -> estimated cost
// from cell (x, y) to a goal, one definition each: octile, Manhattan,
// Euclidean and zero, plus the connectivity's grid distance. Every one is
// admissible and consistent under pathd's cost model (cell factors >= 1).
#ifndef PATHD_CORE_SEARCH_HEURISTICS_H_
#define PATHD_CORE_SEARCH_HEURISTICS_H_

#include <cstdint>

#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/line_of_sight.h"

namespace pathd::internal {

// Octile distance: the cheapest 8-connected move sequence on open ground,
// straight moves 1 and diagonals sqrt(2) (OctileDistance in cost_model.h).
struct OctileHeuristic {
  Cell goal;
  double operator()(int32_t x, int32_t y) const {
    return OctileDistance(Cell{x, y}, goal);
  }
};

// Manhattan distance: the cheapest 4-connected move sequence on open ground.
struct ManhattanHeuristic {
  Cell goal;
  double operator()(int32_t x, int32_t y) const {
    return ManhattanDistance(Cell{x, y}, goal);
  }
};

// Straight-line distance between cell centres (SegmentLength): the cheapest
// any-angle segment, so the heuristic of Theta*.
struct EuclideanHeuristic {
  Cell goal;
  double operator()(int32_t x, int32_t y) const {
    return SegmentLength(Cell{x, y}, goal);
  }
};

// h = 0: Dijkstra's order, and the backward cost-to-go sweep's.
struct ZeroHeuristic {
  double operator()(int32_t, int32_t) const { return 0.0; }
};

// Octile (8-connected) or Manhattan (4-connected) distance, chosen per query.
struct GridDistanceHeuristic {
  Cell goal;
  Connectivity connectivity;
  double operator()(int32_t x, int32_t y) const {
    return connectivity == Connectivity::kFour ? ManhattanHeuristic{goal}(x, y)
                                               : OctileHeuristic{goal}(x, y);
  }
};

}  // namespace pathd::internal

#endif  // PATHD_CORE_SEARCH_HEURISTICS_H_
