// A navigation mesh of a grid's free space: a constrained Delaunay
// triangulation (CGAL) of every tile, free triangles only, merged into
// convex polygons, with the lookups Polyanya
// (core/planners/geometric/polyanya.h) and the funnel need.
// Derived per (map version, unknown_is_free) and advanced tile by tile: an
// update re-triangulates only the tiles its cells touch and shares the rest
// with the previous version.
//
// The constraints are the obstacle boundary of core/geometry/free_space.h
// (grid edges between a blocked and a free cell, the map border) in maximal
// collinear runs, split wherever boundary edges of the other orientation
// meet them, plus each tile's border, split at the same points on both of
// its sides, so neighbouring tiles meet edge to edge. Every mesh vertex is a
// grid corner: the input is integers and no constraints cross, so the
// triangulation needs exact predicates only. A pinch corner (two diagonally
// opposite blocked cells) is a vertex whose two free fans share no edge, so
// no walk from triangle to triangle passes it.
#ifndef PATHD_CORE_GEOMETRY_NAVMESH_H_
#define PATHD_CORE_GEOMETRY_NAVMESH_H_

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "absl/time/time.h"
#include "absl/types/span.h"
#include "core/geometry/free_space.h"
#include "core/map/grid.h"

namespace pathd {

// A free convex polygon of one tile, as a range of the tile's edge array:
// corners counter-clockwise (y down is still "counter-clockwise" in the
// sense of a positive cross product), edge i running from corner i to
// corner i + 1 (mod size). Corners may be collinear (an angle of exactly
// 180 degrees) but never coincide.
struct NavPolygon {
  int32_t first = 0;
  uint16_t size = 0;
  // Edges with no wall across (another polygon or the tile border): a
  // polygon with one is a dead end.
  uint16_t open = 0;
};

// A polygon edge: its first corner, in doubled cell coordinates (a
// LatticePoint in half the bytes), and what lies across it: another
// polygon of the tile (>= 0), NavTile::kWall or NavTile::kTileBorder. One
// record, because the search reads both of an edge together and far more
// often than anything else.
struct NavEdge {
  int32_t x2 = 0;
  int32_t y2 = 0;
  int32_t across = 0;
  friend bool operator==(const NavEdge&, const NavEdge&) = default;
};

// One polygon's edges, read through the tile that stores them.
struct NavPolygonView {
  const NavEdge* edges = nullptr;
  int32_t size = 0;
  int32_t open = 0;
  // Corner i, for any i in [0, 2 * size).
  LatticePoint corner(int32_t i) const {
    const NavEdge& e = edges[i < size ? i : i - size];
    return LatticePoint{e.x2, e.y2};
  }
  // What lies across edge i, for i in [0, size).
  int32_t across(int32_t i) const { return edges[i].across; }
};

// The mesh of one tile: cells [x0, x1) x [y0, y1). Immutable once built.
// The tile's constrained Delaunay triangles are merged into maximal convex
// polygons (Hertel & Mehlhorn, "Fast triangulation of simple polygons",
// 1983: drop a non-constraint diagonal while both angles it ends in stay
// convex), because Polyanya splits an interval at every vertex it sees:
// fewer, larger polygons mean fewer search nodes.
struct NavTile {
  // Across an edge: another polygon of the tile (>= 0), an obstacle or the
  // map's outside, or the tile's border (the neighbour tile decides).
  static constexpr int32_t kWall = -1;
  static constexpr int32_t kTileBorder = -2;
  int32_t x0 = 0;
  int32_t y0 = 0;
  int32_t x1 = 0;
  int32_t y1 = 0;
  std::vector<NavPolygon> polygons;
  // Per polygon edge, indexed by NavPolygon::first + i.
  std::vector<NavEdge> edges;
  // Row-major over the tile's cells: the polygon containing the cell's
  // centre, kNoPolygon for blocked cells.
  static constexpr uint16_t kNoPolygon = 0xffff;
  std::vector<uint16_t> cell_polygon;
  // Edges on the tile's border, per side (0: y = y0, 1: x = x1, 2: y = y1,
  // 3: x = x0), sorted by their lower coordinate along the side: (lower
  // coordinate, polygon).
  std::array<std::vector<std::pair<int32_t, int32_t>>, 4> border;
  // Mesh vertices of the tile (grid corners), for descriptions.
  int32_t vertex_count = 0;
  // Triangles of the tile before merging, for descriptions.
  int32_t triangle_count = 0;
  // Bit v set when a traversable cell of the tile costs v (unknown cells
  // traversed as free count as 0), so planners that need uniform cost can
  // check a whole map in a few words per tile.
  std::array<uint64_t, 4> traversable_costs{};

  NavPolygonView polygon(int32_t index) const {
    const NavPolygon& p = polygons[static_cast<size_t>(index)];
    return NavPolygonView{edges.data() + p.first, p.size, p.open};
  }
  size_t bytes() const;
};

// A polygon of the mesh: tile index and polygon within the tile.
struct NavRef {
  int32_t tile = -1;
  int32_t polygon = -1;
  bool valid() const { return tile >= 0; }
  friend bool operator==(const NavRef&, const NavRef&) = default;
};

// The navigation mesh of one map version. Immutable and thread-safe once
// built; versions share unchanged tiles.
class NavMesh {
 public:
  // Tile side in cells. An update re-meshes every tile a changed cell
  // touches, so 100 scattered cells on a 1024^2 map touch ~120 of 4096
  // tiles at 16 (re-meshed ~20x cheaper than a rebuild) but ~105 of 1024
  // at 32 (under 10x whatever a tile costs). With convex polygons, 16 costs
  // 6-9% more search nodes than 32 where obstacles are dense (random,
  // maze512-1) and up to 3x on open maps (maze512-32, 32room), which stay
  // 9-28x faster than A* there. navmesh_bench --tile_size measures the
  // trade.
  static constexpr int32_t kDefaultTileSize = 16;
  // A tile's polygons are numbered in 16 bits: at most 2 (s + 1)^2.
  static constexpr int32_t kMaxTileSize = 128;

  // The mesh of `grid`'s free space (cells Traversable under
  // unknown_is_free), in tiles of tile_size x tile_size cells (small tiles
  // let tests cross many tile borders on small maps). The grid must not be
  // empty; tile_size is clamped to 1..kMaxTileSize.
  static std::shared_ptr<const NavMesh> Build(const Grid& grid,
                                              bool unknown_is_free,
                                              int32_t tile_size = kDefaultTileSize);
  // The mesh of `grid`, whose cells differ from the grid `previous` was
  // built from exactly in `changed`: the tiles those cells touch are
  // triangulated again, the others shared. Null when the grid's size
  // differs (the caller rebuilds).
  static std::shared_ptr<const NavMesh> Advance(const NavMesh& previous,
                                                const Grid& grid,
                                                absl::Span<const Cell> changed);

  int32_t width() const { return width_; }
  int32_t height() const { return height_; }
  bool unknown_is_free() const { return unknown_is_free_; }
  int32_t tile_size() const { return tile_size_; }
  int32_t tiles_x() const { return tiles_x_; }
  int32_t tiles_y() const { return tiles_y_; }
  const std::vector<std::shared_ptr<const NavTile>>& tiles() const { return tiles_; }
  const NavTile& tile(int32_t index) const { return *tiles_[index]; }
  NavPolygonView polygon(NavRef ref) const {
    return tiles_[ref.tile]->polygon(ref.polygon);
  }

  // The polygon across edge `edge` of `ref`; invalid when an obstacle or
  // the map's outside is there. Inline for the search's inner loop; a tile
  // border is looked up in the neighbour tile.
  NavRef Across(NavRef ref, int edge) const {
    const NavTile& tile = *tiles_[ref.tile];
    const int32_t across = tile.edges[tile.polygons[ref.polygon].first + edge].across;
    if (across >= 0) return NavRef{ref.tile, across};
    if (across == NavTile::kWall) return NavRef{};
    return AcrossBorder(ref, edge);
  }
  // The free polygons whose closure holds the centre of `cell` (one, or
  // two when it lies on their shared edge); empty for a blocked cell.
  std::vector<NavRef> Locate(Cell cell) const;

  // Every traversable cell costs the same (at most one cost value over all
  // tiles). O(tiles).
  bool UniformCost() const;

  // Totals over the tiles (triangles: before merging into polygons).
  int64_t polygon_count() const;
  int64_t triangle_count() const;
  int64_t vertex_count() const;
  size_t bytes() const;
  // How long Build or Advance took.
  absl::Duration build_time() const { return build_time_; }
  // Tiles Advance triangulated again (all of them for Build).
  int32_t rebuilt_tiles() const { return rebuilt_tiles_; }

 private:
  NavMesh() = default;
  NavRef AcrossBorder(NavRef ref, int edge) const;

  int32_t width_ = 0;
  int32_t height_ = 0;
  bool unknown_is_free_ = false;
  int32_t tile_size_ = kDefaultTileSize;
  int32_t tiles_x_ = 0;
  int32_t tiles_y_ = 0;
  std::vector<std::shared_ptr<const NavTile>> tiles_;
  absl::Duration build_time_;
  int32_t rebuilt_tiles_ = 0;
};

// Twice the signed area of triangle a, b, c: > 0 counter-clockwise (c left
// of a -> b), 0 collinear. Exact for lattice points.
inline int64_t Orient(LatticePoint a, LatticePoint b, LatticePoint c) {
  return (b.x2 - a.x2) * (c.y2 - a.y2) - (b.y2 - a.y2) * (c.x2 - a.x2);
}

}  // namespace pathd

#endif  // PATHD_CORE_GEOMETRY_NAVMESH_H_
