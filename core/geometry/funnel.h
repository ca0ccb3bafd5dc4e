// String pulling ("path refinement" in the lecture notes): the shortest path
// through a channel of convex cells, given as the sequence of portals (the
// edges shared by consecutive cells) from the start's cell to the goal's, by
// the funnel algorithm (Lee & Preparata, "Euclidean shortest paths in the
// presence of rectilinear barriers", Networks 1984; in the "simple stupid
// funnel" form of Mononen, 2010). Reusable by any planner whose search
// yields a channel (navigation mesh, trapezoidal decomposition).
#ifndef PATHD_CORE_GEOMETRY_FUNNEL_H_
#define PATHD_CORE_GEOMETRY_FUNNEL_H_

#include <vector>

#include "absl/types/span.h"
#include "core/map/grid.h"

namespace pathd {

// A segment the path crosses, with its ends named as seen walking from the
// start to the goal: `left` is on the side where the cross product of the
// walking direction with (point - position) is positive.
struct Portal {
  CellPoint left;
  CellPoint right;
};

// The shortest polyline from `start` to `goal` that crosses every portal in
// order: start, the portal ends it bends at (copied exactly), goal.
// Preconditions: start lies in the cell before the first portal, goal in
// the cell after the last, and consecutive portals bound a convex cell.
std::vector<CellPoint> FunnelPath(CellPoint start, absl::Span<const Portal> portals,
                                  CellPoint goal);

}  // namespace pathd

#endif  // PATHD_CORE_GEOMETRY_FUNNEL_H_
