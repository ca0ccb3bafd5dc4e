// What a geometric planner builds from a map, described for people: the
// sizes and build time `pathctl maps stats` prints and the segments `pathctl
// render --overlay` draws under a plan, so a person can see what the planner
// saw. Each kind is built by the same code the planner uses.
#ifndef PATHD_CORE_GEOMETRY_STRUCTURE_H_
#define PATHD_CORE_GEOMETRY_STRUCTURE_H_

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "core/map/grid.h"

namespace pathd {

struct GeometricStructure {
  // "polygons", "visibility", "mesh", "decomposition", "voronoi".
  std::string kind;
  // Named sizes in the order to print, e.g. {"vertices", 1204}.
  std::vector<std::pair<std::string, int64_t>> counts;
  // Memory the structure holds.
  size_t bytes = 0;
  absl::Duration build_time;
  // What to draw, in cell coordinates: line segments and points.
  std::vector<std::array<CellPoint, 2>> segments;
  std::vector<CellPoint> points;
};

// The kinds DescribeStructure knows, in listing order.
const std::vector<std::string_view>& StructureKinds();

// Builds `kind` for `grid` (cells blocked or free under unknown_is_free) and
// describes it; INVALID_ARGUMENT naming the known kinds for an unknown one.
absl::StatusOr<GeometricStructure> DescribeStructure(std::string_view kind,
                                                     const Grid& grid,
                                                     bool unknown_is_free);

// One per kind, each next to the structure it describes.
GeometricStructure DescribeObstaclePolygons(const Grid& grid, bool unknown_is_free);
GeometricStructure DescribeVisibilityGraph(const Grid& grid, bool unknown_is_free);
GeometricStructure DescribeNavMesh(const Grid& grid, bool unknown_is_free);
GeometricStructure DescribeDecomposition(const Grid& grid, bool unknown_is_free);
GeometricStructure DescribeVoronoi(const Grid& grid, bool unknown_is_free);

}  // namespace pathd

#endif  // PATHD_CORE_GEOMETRY_STRUCTURE_H_
