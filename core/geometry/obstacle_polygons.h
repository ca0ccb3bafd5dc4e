// The polygonal model of a map: the boundary of free space (core/geometry/
// free_space.h) as closed rings on cell edges. Each ring keeps free space on
// its left, so in the x-right, y-up cell frame the outer boundary of a free
// region runs counter-clockwise and the boundary of an obstacle inside it
// (a hole of the region's polygon) clockwise. Collinear runs are merged:
// ring vertices are exactly the corners where the boundary turns.
//
// Where two obstacles touch at a pinch corner, the rings of the free cells
// on either side touch there without joining, so a region's polygon never
// connects through a pinch: the no-corner-cutting rule of the planners.
//
// Built from scratch in O(cells), or advanced from the previous version's
// rings in O(rings touching the changed cells): only the rings passing
// through a corner of a changed cell are traced again.
#ifndef PATHD_CORE_GEOMETRY_OBSTACLE_POLYGONS_H_
#define PATHD_CORE_GEOMETRY_OBSTACLE_POLYGONS_H_

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "absl/types/span.h"
#include "core/geometry/free_space.h"
#include "core/map/grid.h"

namespace pathd {

// A grid corner: the point (x, y) in cell coordinates.
struct GridCorner {
  int32_t x = 0;
  int32_t y = 0;
  friend bool operator==(const GridCorner&, const GridCorner&) = default;
  friend auto operator<=>(const GridCorner&, const GridCorner&) = default;
};

// One closed boundary ring; the last vertex connects back to the first.
struct BoundaryRing {
  std::vector<GridCorner> vertices;
  // Twice the signed area (shoelace): positive for a free region's outer
  // boundary, negative for a hole.
  int64_t twice_area = 0;
  // Bounding box of the vertices, for the advance's filter.
  GridCorner min;
  GridCorner max;
  bool is_hole() const { return twice_area < 0; }
};

class ObstaclePolygons {
 public:
  // The rings of `space`'s free space.
  static std::shared_ptr<const ObstaclePolygons> Build(const FreeSpace& space);
  // The rings of `space` (the new version), from `previous` (the rings of a
  // version whose cells differ from it exactly in `changed`).
  static std::shared_ptr<const ObstaclePolygons> Advance(
      const ObstaclePolygons& previous, const FreeSpace& space,
      absl::Span<const Cell> changed);

  const std::vector<BoundaryRing>& rings() const { return rings_; }
  int64_t vertex_count() const;
  int64_t hole_count() const;
  size_t bytes() const;

  // The same rings, each rotated to start at its smallest vertex, sorted:
  // equal for equal free spaces however they were made.
  std::vector<std::vector<GridCorner>> Canonical() const;

 private:
  std::vector<BoundaryRing> rings_;
};

}  // namespace pathd

#endif  // PATHD_CORE_GEOMETRY_OBSTACLE_POLYGONS_H_
