// Isochrones: a budgeted Dijkstra search, then the region's boundary rings
// grouped into polygons.
#include "core/fleet/isochrone.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <optional>

#include <boost/geometry.hpp>
#include <boost/geometry/geometries/point_xy.hpp>
#include <boost/geometry/geometries/ring.hpp>

#include "core/fleet/table.h"
#include "core/geometry/free_space.h"

namespace pathd {
namespace {

namespace bg = boost::geometry;
using BgPoint = bg::model::d2::point_xy<double>;
using BgRing = bg::model::ring<BgPoint, /*ClockWise=*/false, /*Closed=*/false>;

BgRing ToRing(const std::vector<GridCorner>& vertices) {
  BgRing ring;
  for (const GridCorner& v : vertices) ring.push_back(BgPoint(v.x, v.y));
  bg::correct(ring);
  return ring;
}

// The centre of a cell outside the region that `hole` bounds: one of the two
// cells beside its first unit of boundary, the one not in the region.
std::optional<BgPoint> PointInHole(const std::vector<GridCorner>& hole, int32_t width,
                                   int32_t height, const std::vector<uint8_t>& inside) {
  if (hole.size() < 2) return std::nullopt;
  const GridCorner a = hole[0];
  const GridCorner b = hole[1];
  const int dx = (b.x > a.x) - (b.x < a.x);
  const int dy = (b.y > a.y) - (b.y < a.y);
  // The unit edge from a towards b separates two cells.
  int32_t c1x, c1y, c2x, c2y;
  if (dx != 0) {  // horizontal edge at y = a.y
    c1x = c2x = std::min(a.x, a.x + dx);
    c1y = a.y - 1;
    c2y = a.y;
  } else {  // vertical edge at x = a.x
    c1y = c2y = std::min(a.y, a.y + dy);
    c1x = a.x - 1;
    c2x = a.x;
  }
  const auto in = [&](int32_t x, int32_t y) {
    return x >= 0 && y >= 0 && x < width && y < height &&
           inside[static_cast<size_t>(y) * width + x] != 0;
  };
  if (!in(c1x, c1y)) return BgPoint(c1x + 0.5, c1y + 0.5);
  if (!in(c2x, c2y)) return BgPoint(c2x + 0.5, c2y + 0.5);
  return std::nullopt;
}

// Twice the signed area (shoelace), positive counter-clockwise.
int64_t TwiceArea(const std::vector<GridCorner>& ring) {
  int64_t sum = 0;
  for (size_t i = 0; i < ring.size(); ++i) {
    const GridCorner& a = ring[i];
    const GridCorner& b = ring[(i + 1) % ring.size()];
    sum += int64_t{a.x} * b.y - int64_t{b.x} * a.y;
  }
  return sum;
}

// A boundary ring that passes a corner twice (cells of one region meeting
// diagonally there) split into simple rings at that corner, so each is a
// valid OGC ring: a loop's sign says whether it is an exterior or a hole
// (a hole may touch its exterior at that corner, which OGC allows).
std::vector<std::vector<GridCorner>> SimpleRings(const std::vector<GridCorner>& ring) {
  std::vector<std::vector<GridCorner>> out;
  std::vector<GridCorner> stack;
  std::map<GridCorner, size_t> at;  // vertex -> its index in `stack`
  for (const GridCorner& v : ring) {
    if (const auto it = at.find(v); it != at.end()) {
      // stack[it->second..] closes a loop at v; v stays for the rest.
      std::vector<GridCorner> loop(stack.begin() + static_cast<std::ptrdiff_t>(it->second),
                                   stack.end());
      for (size_t k = it->second + 1; k < stack.size(); ++k) at.erase(stack[k]);
      stack.resize(it->second + 1);
      out.push_back(std::move(loop));
      continue;
    }
    at[v] = stack.size();
    stack.push_back(v);
  }
  out.push_back(std::move(stack));
  return out;
}

}  // namespace

Isochrone ComputeIsochrone(const Grid& grid, const CostParams& cost, Cell start,
                           double budget, const StopCondition& stop) {
  Isochrone out;
  CostField field = DijkstraFrom(grid, cost, start, {}, budget, stop);
  out.expansions = field.expansions;
  if (field.outcome != PlanOutcome::kFound) {
    out.outcome = field.outcome;
    return out;
  }
  out.reachable.assign(grid.size(), 0);
  for (size_t i = 0; i < grid.size(); ++i) {
    if (field.cost[i] <= budget) {
      out.reachable[i] = 1;
      ++out.reachable_cells;
    }
  }
  out.polygons = RegionPolygons(grid.width(), grid.height(), out.reachable);
  return out;
}

std::vector<CellPolygon> RegionPolygons(int32_t width, int32_t height,
                                        const std::vector<uint8_t>& inside) {
  // The region as the free space of a grid: free where inside.
  Grid mask = *Grid::Create(width, height, kLethalCost);
  for (size_t i = 0; i < inside.size(); ++i) {
    if (inside[i] != 0) mask.mutable_cells()[i] = 0;
  }
  const FreeSpace space(mask, /*unknown_is_free=*/false);
  const std::shared_ptr<const ObstaclePolygons> rings = ObstaclePolygons::Build(space);
  std::vector<std::vector<GridCorner>> holes;
  std::vector<CellPolygon> polygons;
  std::vector<BgRing> exteriors;
  std::vector<double> areas;
  for (const BoundaryRing& ring : rings->rings()) {
    for (std::vector<GridCorner>& simple : SimpleRings(ring.vertices)) {
      if (simple.size() < 3) continue;
      const int64_t twice_area = TwiceArea(simple);
      if (twice_area < 0) {
        holes.push_back(std::move(simple));
        continue;
      }
      exteriors.push_back(ToRing(simple));
      areas.push_back(static_cast<double>(twice_area) / 2.0);
      polygons.push_back(CellPolygon{std::move(simple), {}});
    }
  }
  for (std::vector<GridCorner>& hole : holes) {
    const std::optional<BgPoint> point = PointInHole(hole, width, height, inside);
    if (!point.has_value()) continue;
    // The innermost exterior around the hole: nested regions (an island in
    // a lake in a region) have exteriors inside one another.
    int best = -1;
    for (size_t k = 0; k < exteriors.size(); ++k) {
      if (best >= 0 && areas[k] >= areas[best]) continue;
      if (bg::within(*point, exteriors[k])) best = static_cast<int>(k);
    }
    if (best >= 0) polygons[best].holes.push_back(std::move(hole));
  }
  return polygons;
}

}  // namespace pathd
