#include "core/geometry/funnel.h"

#include <vector>

namespace pathd {
namespace {

// > 0 when c is left of a -> b.
double Side(CellPoint a, CellPoint b, CellPoint c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}
bool Same(CellPoint a, CellPoint b) { return a.x == b.x && a.y == b.y; }

}  // namespace

std::vector<CellPoint> FunnelPath(CellPoint start, absl::Span<const Portal> portals,
                                  CellPoint goal) {
  // The goal closes the channel as a last, zero-width portal.
  std::vector<Portal> all(portals.begin(), portals.end());
  all.push_back(Portal{goal, goal});
  std::vector<CellPoint> path{start};
  // The funnel: apex, and the left and right ends it is narrowed to, with
  // the portal index each end came from (to restart after a bend).
  CellPoint apex = start;
  CellPoint left = start;
  CellPoint right = start;
  size_t left_index = 0;
  size_t right_index = 0;
  for (size_t i = 0; i < all.size(); ++i) {
    const CellPoint l = all[i].left;
    const CellPoint r = all[i].right;
    // The right side moves in (or stays) ...
    if (Side(apex, right, r) >= 0) {
      // ... and, unless it crosses the left side, narrows the funnel.
      if (Same(apex, right) || Side(apex, left, r) < 0) {
        right = r;
        right_index = i;
      } else {
        // The path bends at the left end: restart the funnel from there.
        path.push_back(left);
        apex = left;
        right = apex;
        i = left_index;
        right_index = left_index;
        continue;
      }
    }
    if (Side(apex, left, l) <= 0) {
      if (Same(apex, left) || Side(apex, right, l) > 0) {
        left = l;
        left_index = i;
      } else {
        path.push_back(right);
        apex = right;
        left = apex;
        i = right_index;
        left_index = right_index;
        continue;
      }
    }
  }
  if (!Same(path.back(), goal)) path.push_back(goal);
  return path;
}

}  // namespace pathd
