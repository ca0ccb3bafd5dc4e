// The two derived values a kinematic search reads from a map version: the
// obstacle distance field (for FootprintChecker's shortcuts) and the
// holonomic-with-obstacles heuristic of Dolgov et al. ("Path Planning for
// Autonomous Vehicles in Unknown Semi-structured Environments", 2010): the
// cost to the goal of a robot that may move in any direction, ignoring its
// heading but not the obstacles, by Dijkstra's algorithm (with Dial's
// buckets) from the goal cell over the 8-connected grid. Both come from the query's DerivedStore when it has one
// (the server's per-version cache: a replan towards the same goal on the same
// map version reuses the field) and are built for the query otherwise.
#ifndef PATHD_CORE_KINEMATICS_OBSTACLE_HEURISTIC_H_
#define PATHD_CORE_KINEMATICS_OBSTACLE_HEURISTIC_H_

#include <cstddef>
#include <memory>
#include <vector>

#include "core/map/grid.h"
#include "core/search/derived.h"

namespace pathd {

// ObstacleDistanceField (core/kinematics/footprint.h) of a map version, from
// the store under "obstacle_distance unknown_is_free=<0|1>". Never null: the
// transform is O(cells) and does not poll.
std::shared_ptr<const std::vector<float>> GetObstacleDistance(DerivedStore* store,
                                                              const Grid& grid,
                                                              bool unknown_is_free);

// What the heuristic field depends on besides the map version.
struct ObstacleHeuristicParams {
  Cell goal;
  bool unknown_is_free = false;
  // Entering a cell of cost c costs the move's length x (1 + cost_penalty *
  // c / 252), as the kinematic planners price their motions.
  double cost_penalty = 0.0;
  // Cells whose centre is nearer than this (cells) to an obstacle's centre
  // are blocked too: no pose in them is free for a footprint whose inscribed
  // radius is this + sqrt(2)/2 (FootprintChecker's "nearer than the
  // inscribed radius" shortcut). <= 0: only obstacle cells are blocked.
  double blocked_within = 0.0;
};

// The cost-to-go of every cell to the goal cell, from cell centre to cell
// centre, under ObstacleHeuristicParams: Dijkstra over the 8 moves (1 or
// sqrt(2) long), a diagonal allowed when at least one of the two cells beside
// it is open (a continuous path passes there; the grid planners' stricter
// rule would overestimate). +inf where the goal cannot be reached. Immutable.
//
// As a heuristic for a robot's motions it is "admissible-ish": an 8-connected
// path is up to 8.2% longer than the straight line (22.5 degrees), and the
// field measures between cell centres, so it can exceed the true cost by
// that ratio plus about a cell; Nav2's Smac planners accept the same.
struct ObstacleHeuristic {
  Cell goal;
  int32_t width = 0;
  std::vector<float> cost;

  // The field at a cell on the grid.
  double At(Cell c) const {
    return cost[static_cast<size_t>(c.y) * static_cast<size_t>(width) +
                static_cast<size_t>(c.x)];
  }
  size_t bytes() const { return sizeof(*this) + cost.capacity() * sizeof(float); }
};

// The field for `params` on `grid`, built polling `stop` (null when it fired;
// `stop` then says what was running). `distance` must be
// ObstacleDistanceField(grid, params.unknown_is_free) when
// params.blocked_within > 0 (may be null otherwise). O(cells): every move
// costs at least 1, so buckets of width 1 replace the heap exactly.
std::shared_ptr<const ObstacleHeuristic> BuildObstacleHeuristic(
    const Grid& grid, const ObstacleHeuristicParams& params, const float* distance,
    DerivedStop& stop);

// The field from the store, keyed by goal cell and every parameter (a new map
// version rebuilds it), or built now without a store; null when `stop` fired.
std::shared_ptr<const ObstacleHeuristic> GetObstacleHeuristic(
    DerivedStore* store, const Grid& grid, const ObstacleHeuristicParams& params,
    DerivedStop& stop);

}  // namespace pathd

#endif  // PATHD_CORE_KINEMATICS_OBSTACLE_HEURISTIC_H_
