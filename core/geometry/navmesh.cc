#include "core/geometry/navmesh.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "absl/time/clock.h"
#include "core/geometry/structure.h"
#include "core/map/cost_model.h"

namespace pathd {
namespace {

// Exact predicates suffice: every input point is an integer grid corner and
// no two constraints cross (they meet only at their ends), so CGAL never
// constructs an intersection point.
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using FaceInfo = CGAL::Triangulation_face_base_with_info_2<int32_t, Kernel>;
using FaceBase = CGAL::Constrained_triangulation_face_base_2<Kernel, FaceInfo>;
using Tds = CGAL::Triangulation_data_structure_2<
    CGAL::Triangulation_vertex_base_2<Kernel>, FaceBase>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<
    Kernel, Tds, CGAL::No_constraint_intersection_requiring_constructions_tag>;

// Cell (x, y) is blocked under the mesh's rule; outside the grid too.
class BlockedCells {
 public:
  BlockedCells(const Grid& grid, bool unknown_is_free)
      : grid_(grid), unknown_is_free_(unknown_is_free) {}
  bool operator()(int32_t x, int32_t y) const {
    return !grid_.InBounds(x, y) ||
           !Traversable(grid_.cost(x, y), unknown_is_free_);
  }
  // The cost values of traversable cells in [x0, x1) x [y0, y1), as a bit
  // set (unknown traversed as free: 0).
  std::array<uint64_t, 4> CostsIn(int32_t x0, int32_t y0, int32_t x1, int32_t y1) const {
    std::array<uint64_t, 4> bits{};
    for (int32_t y = y0; y < y1; ++y) {
      for (int32_t x = x0; x < x1; ++x) {
        uint8_t c = grid_.cost(x, y);
        if (!Traversable(c, unknown_is_free_)) continue;
        if (c == kUnknownCost) c = kFreeCost;
        bits[c >> 6] |= uint64_t{1} << (c & 63);
      }
    }
    return bits;
  }

 private:
  const Grid& grid_;
  bool unknown_is_free_;
};

// Whether boundary edges (between a blocked and a free cell) of each
// orientation end at grid corner (x, y).
struct CornerEdges {
  // On the vertical grid line x, above or below the corner.
  bool vertical = false;
  // On the horizontal grid line y, left or right of the corner.
  bool horizontal = false;
};
CornerEdges EdgesAt(const BlockedCells& blocked, int32_t x, int32_t y) {
  const bool a = blocked(x - 1, y - 1);
  const bool b = blocked(x, y - 1);
  const bool c = blocked(x - 1, y);
  const bool d = blocked(x, y);
  return CornerEdges{.vertical = a != b || c != d, .horizontal = a != c || b != d};
}

// Builds one tile. Vertices: the tile's corners; on its border, the corners
// where a boundary edge across the border line ends (a rule both tiles
// sharing the line evaluate alike); inside, the corners where boundary edges
// of both orientations meet (obstacle corners, pinches included: there the
// boundary turns, so runs between them are straight). Constraints: the
// border between consecutive border vertices, and the boundary runs inside.
class TileBuilder {
 public:
  TileBuilder(const BlockedCells& blocked, int32_t x0, int32_t y0, int32_t x1,
              int32_t y1)
      : blocked_(blocked),
        x0_(x0),
        y0_(y0),
        x1_(x1),
        y1_(y1),
        handles_(static_cast<size_t>(x1 - x0 + 1) * (y1 - y0 + 1)) {}

  std::shared_ptr<const NavTile> Build() {
    InsertVertices();
    InsertBorder();
    InsertRuns();
    auto tile = std::make_shared<NavTile>();
    tile->x0 = x0_;
    tile->y0 = y0_;
    tile->x1 = x1_;
    tile->y1 = y1_;
    tile->vertex_count = static_cast<int32_t>(cdt_.number_of_vertices());
    tile->traversable_costs = blocked_.CostsIn(x0_, y0_, x1_, y1_);
    const std::vector<Triangle> triangles = ExtractTriangles();
    tile->triangle_count = static_cast<int32_t>(triangles.size());
    const std::vector<int32_t> polygon_of = MergeTriangles(triangles, *tile);
    IndexCells(triangles, polygon_of, *tile);
    IndexBorder(*tile);
    return tile;
  }

 private:
  bool IsVertex(int32_t x, int32_t y) const {
    const bool on_x_border = x == x0_ || x == x1_;
    const bool on_y_border = y == y0_ || y == y1_;
    if (on_x_border && on_y_border) return true;
    const CornerEdges e = EdgesAt(blocked_, x, y);
    if (on_x_border) return e.horizontal;
    if (on_y_border) return e.vertical;
    return e.vertical && e.horizontal;
  }
  Cdt::Vertex_handle& Handle(int32_t x, int32_t y) {
    return handles_[static_cast<size_t>(y - y0_) * (x1_ - x0_ + 1) + (x - x0_)];
  }

  void InsertVertices() {
    Cdt::Face_handle hint;
    for (int32_t y = y0_; y <= y1_; ++y) {
      for (int32_t x = x0_; x <= x1_; ++x) {
        if (!IsVertex(x, y)) continue;
        Cdt::Vertex_handle v = cdt_.insert(Cdt::Point(x, y), hint);
        hint = v->face();
        Handle(x, y) = v;
      }
    }
  }

  void Constrain(int32_t xa, int32_t ya, int32_t xb, int32_t yb) {
    cdt_.insert_constraint(Handle(xa, ya), Handle(xb, yb));
  }

  void InsertBorder() {
    for (const int32_t y : {y0_, y1_}) {
      int32_t last = x0_;
      for (int32_t x = x0_ + 1; x <= x1_; ++x) {
        if (Handle(x, y) == Cdt::Vertex_handle()) continue;
        Constrain(last, y, x, y);
        last = x;
      }
    }
    for (const int32_t x : {x0_, x1_}) {
      int32_t last = y0_;
      for (int32_t y = y0_ + 1; y <= y1_; ++y) {
        if (Handle(x, y) == Cdt::Vertex_handle()) continue;
        Constrain(x, last, x, y);
        last = y;
      }
    }
  }

  // Maximal runs of boundary edges on the grid lines strictly inside the
  // tile, cut at vertices. A run starts and ends at vertices: a corner with
  // a boundary edge on one side only has one of the other orientation too
  // (the edges around a corner come in pairs).
  void InsertRuns() {
    for (int32_t y = y0_ + 1; y < y1_; ++y) {
      int32_t start = -1;
      for (int32_t x = x0_; x <= x1_; ++x) {
        const bool edge = x < x1_ && blocked_(x, y - 1) != blocked_(x, y);
        if (start >= 0 && (!edge || Handle(x, y) != Cdt::Vertex_handle())) {
          Constrain(start, y, x, y);
          start = -1;
        }
        if (edge && start < 0) start = x;
      }
    }
    for (int32_t x = x0_ + 1; x < x1_; ++x) {
      int32_t start = -1;
      for (int32_t y = y0_; y <= y1_; ++y) {
        const bool edge = y < y1_ && blocked_(x - 1, y) != blocked_(x, y);
        if (start >= 0 && (!edge || Handle(x, y) != Cdt::Vertex_handle())) {
          Constrain(x, start, x, y);
          start = -1;
        }
        if (edge && start < 0) start = y;
      }
    }
  }

  bool OnBorder(LatticePoint a, LatticePoint b) const {
    return (a.x2 == b.x2 && (a.x2 == 2 * x0_ || a.x2 == 2 * x1_)) ||
           (a.y2 == b.y2 && (a.y2 == 2 * y0_ || a.y2 == 2 * y1_));
  }

  // A free triangle before merging: corners counter-clockwise, across edge
  // i (corner i to i + 1) another triangle, NavTile::kWall or kTileBorder.
  struct Triangle {
    std::array<LatticePoint, 3> corners;
    std::array<int32_t, 3> across;
  };

  // Keeps the free faces: no constraint crosses a face, so its interior
  // lies in one cell class, read at its centroid (inside the face, hence
  // not on a boundary edge, so either cell beside a grid line it may lie on
  // has the face's class).
  std::vector<Triangle> ExtractTriangles() {
    int32_t next = 0;
    for (Cdt::Face_handle f : cdt_.finite_face_handles()) {
      int64_t sx = 0;
      int64_t sy = 0;
      for (int i = 0; i < 3; ++i) {
        sx += static_cast<int64_t>(f->vertex(i)->point().x());
        sy += static_cast<int64_t>(f->vertex(i)->point().y());
      }
      const bool free = !blocked_(static_cast<int32_t>(sx / 3),
                                  static_cast<int32_t>(sy / 3));
      f->info() = free ? next++ : -1;
    }
    std::vector<Triangle> triangles(static_cast<size_t>(next));
    for (Cdt::Face_handle f : cdt_.finite_face_handles()) {
      if (f->info() < 0) continue;
      Triangle& t = triangles[static_cast<size_t>(f->info())];
      for (int i = 0; i < 3; ++i) {
        const Cdt::Point& p = f->vertex(i)->point();
        t.corners[i] = CornerAt(static_cast<int64_t>(p.x()), static_cast<int64_t>(p.y()));
      }
      for (int i = 0; i < 3; ++i) {
        // CGAL's neighbour i is opposite vertex i: across edge (i+1, i+2).
        const Cdt::Face_handle n = f->neighbor((i + 2) % 3);
        if (!cdt_.is_infinite(n) && n->info() >= 0) {
          t.across[i] = n->info();
        } else if (OnBorder(t.corners[i], t.corners[(i + 1) % 3])) {
          t.across[i] = NavTile::kTileBorder;
        } else {
          t.across[i] = NavTile::kWall;
        }
      }
    }
    return triangles;
  }

  // Grid corner `p` is a bend corner: exactly one of its four cells is
  // blocked (free_space.h), the only kind of point a shortest path turns at.
  bool IsBend(LatticePoint p) const {
    const int32_t x = static_cast<int32_t>(p.x2 / 2);
    const int32_t y = static_cast<int32_t>(p.y2 / 2);
    return blocked_(x - 1, y - 1) + blocked_(x, y - 1) + blocked_(x - 1, y) +
               blocked_(x, y) ==
           1;
  }

  // The corner `at` of a merged polygon may join `prev` to `next`: a convex
  // turn, or straight on (collinear but not doubling back, which two
  // polygons sharing two collinear edges would otherwise produce) where no
  // path turns. A straight angle at a bend corner would hide it: a root on
  // the polygon's side sees the edge beyond the corner edge-on, so no
  // interval would end there and the path could not turn round it.
  bool ConvexAt(LatticePoint prev, LatticePoint at, LatticePoint next) const {
    const int64_t o = Orient(prev, at, next);
    if (o != 0) return o > 0;
    return (at.x2 - prev.x2) * (next.x2 - at.x2) + (at.y2 - prev.y2) * (next.y2 - at.y2) > 0 &&
           !IsBend(at);
  }

  // Hertel-Mehlhorn: each diagonal between two free triangles (never a
  // constraint: those have a wall or the tile border on one side) is
  // dropped when both corners it ends in stay convex, longest diagonals
  // first so that merged polygons come out fat rather than long slivers.
  // Deterministic in the triangles, so a re-built tile equals the tile an
  // advance builds. Fills the tile's polygons and returns, per triangle,
  // its polygon.
  std::vector<int32_t> MergeTriangles(const std::vector<Triangle>& triangles,
                                      NavTile& tile) const {
    // Every polygon is a ring of the triangles' edges, linked both ways in
    // flat arrays (edge 3t + i is edge i of triangle t), so a merge relinks
    // four edges and allocates nothing.
    const size_t n = triangles.size();
    std::vector<int32_t> next(3 * n);
    std::vector<int32_t> prev(3 * n);
    std::vector<int32_t> parent(n);
    std::vector<int32_t> head(n);  // an edge of the ring, for roots
    std::vector<int32_t> size(n, 3);
    for (size_t t = 0; t < n; ++t) {
      parent[t] = static_cast<int32_t>(t);
      head[t] = static_cast<int32_t>(3 * t);
      for (int i = 0; i < 3; ++i) {
        next[3 * t + i] = static_cast<int32_t>(3 * t + (i + 1) % 3);
        prev[3 * t + i] = static_cast<int32_t>(3 * t + (i + 2) % 3);
      }
    }
    auto corner = [&](int32_t e) { return triangles[e / 3].corners[e % 3]; };
    auto find = [&](int32_t t) {
      while (parent[t] != t) {
        parent[t] = parent[parent[t]];
        t = parent[t];
      }
      return t;
    };
    struct Diagonal {
      int64_t length2;
      int32_t t;
      int32_t i;
    };
    std::vector<Diagonal> diagonals;
    for (size_t t = 0; t < n; ++t) {
      for (int i = 0; i < 3; ++i) {
        const int32_t other = triangles[t].across[i];
        if (other <= static_cast<int32_t>(t)) continue;  // each once; no walls
        const LatticePoint a = triangles[t].corners[i];
        const LatticePoint b = triangles[t].corners[(i + 1) % 3];
        const int64_t dx = b.x2 - a.x2;
        const int64_t dy = b.y2 - a.y2;
        diagonals.push_back(Diagonal{dx * dx + dy * dy, static_cast<int32_t>(t), i});
      }
    }
    std::sort(diagonals.begin(), diagonals.end(), [](const Diagonal& x, const Diagonal& y) {
      if (x.length2 != y.length2) return x.length2 > y.length2;
      return x.t != y.t ? x.t < y.t : x.i < y.i;
    });
    for (const Diagonal& d : diagonals) {
      // Edge i runs u -> v in p's ring, its twin j v -> u in q's.
      const int32_t i = 3 * d.t + d.i;
      const int32_t other = triangles[d.t].across[d.i];
      const LatticePoint u = corner(i);
      int32_t j = 3 * other;
      while (!(corner(j) == corner(next[i]) && corner(next[j]) == u)) ++j;
      const int32_t p = find(d.t);
      const int32_t q = find(other);
      if (p == q) continue;
      const LatticePoint v = corner(next[i]);
      if (!ConvexAt(corner(prev[i]), u, corner(next[next[j]])) ||
          !ConvexAt(corner(prev[j]), v, corner(next[next[i]]))) {
        continue;
      }
      // p's edges from v round to u, then q's from u round to v.
      next[prev[i]] = next[j];
      prev[next[j]] = prev[i];
      next[prev[j]] = next[i];
      prev[next[i]] = prev[j];
      head[p] = next[i];
      size[p] += size[q] - 2;
      parent[q] = p;
    }
    // The polygons' rings, as (corner, what lies across) from their heads.
    struct Edge {
      LatticePoint corner;
      int32_t across;  // a triangle, kWall or kTileBorder
    };
    std::vector<std::vector<Edge>> rings(n);
    for (size_t t = 0; t < n; ++t) {
      if (find(static_cast<int32_t>(t)) != static_cast<int32_t>(t)) continue;
      rings[t].reserve(static_cast<size_t>(size[t]));
      int32_t e = head[t];
      do {
        rings[t].push_back(Edge{corner(e), triangles[e / 3].across[e % 3]});
        e = next[e];
      } while (e != head[t]);
    }
    // Number the polygons row by row (by their top-left corner, then their
    // first triangle), so that neighbours tend to lie close in memory.
    struct Order {
      int64_t y2;
      int64_t x2;
      int32_t t;
    };
    std::vector<Order> order;
    for (size_t t = 0; t < n; ++t) {
      if (find(static_cast<int32_t>(t)) != static_cast<int32_t>(t)) continue;
      Order o{INT64_MAX, INT64_MAX, static_cast<int32_t>(t)};
      for (const Edge& e : rings[t]) {
        if (e.corner.y2 < o.y2 || (e.corner.y2 == o.y2 && e.corner.x2 < o.x2)) {
          o.y2 = e.corner.y2;
          o.x2 = e.corner.x2;
        }
      }
      order.push_back(o);
    }
    std::sort(order.begin(), order.end(), [](const Order& a, const Order& b) {
      if (a.y2 != b.y2) return a.y2 < b.y2;
      return a.x2 != b.x2 ? a.x2 < b.x2 : a.t < b.t;
    });
    std::vector<int32_t> id(n, -1);
    for (size_t k = 0; k < order.size(); ++k) id[order[k].t] = static_cast<int32_t>(k);
    std::vector<int32_t> polygon_of(n);
    for (size_t t = 0; t < n; ++t) polygon_of[t] = id[find(static_cast<int32_t>(t))];
    tile.polygons.reserve(order.size());
    for (const Order& o : order) {
      const std::vector<Edge>& ring = rings[o.t];
      NavPolygon polygon{static_cast<int32_t>(tile.edges.size()),
                         static_cast<uint16_t>(ring.size()), 0};
      for (const Edge& e : ring) {
        tile.edges.push_back(NavEdge{static_cast<int32_t>(e.corner.x2),
                                     static_cast<int32_t>(e.corner.y2),
                                     e.across >= 0 ? polygon_of[e.across] : e.across});
        if (e.across != NavTile::kWall) ++polygon.open;
      }
      tile.polygons.push_back(polygon);
    }
    tile.edges.shrink_to_fit();
    return polygon_of;
  }

  // For each triangle, the cell centres it holds, row by row: the x range
  // from its edges in floating point, widened by a cell, then each
  // candidate tested exactly. Recorded as the triangle's polygon.
  void IndexCells(const std::vector<Triangle>& triangles,
                  const std::vector<int32_t>& polygon_of, NavTile& tile) const {
    const int32_t w = x1_ - x0_;
    tile.cell_polygon.assign(static_cast<size_t>(w) * (y1_ - y0_), NavTile::kNoPolygon);
    for (size_t ti = 0; ti < triangles.size(); ++ti) {
      const auto& c = triangles[ti].corners;
      const int64_t ymin = std::min({c[0].y2, c[1].y2, c[2].y2});
      const int64_t ymax = std::max({c[0].y2, c[1].y2, c[2].y2});
      for (int64_t row = ymin / 2; 2 * row + 1 < ymax; ++row) {
        const double yc = static_cast<double>(2 * row + 1);
        double lo = INFINITY;
        double hi = -INFINITY;
        for (int i = 0; i < 3; ++i) {
          const LatticePoint a = c[i];
          const LatticePoint b = c[(i + 1) % 3];
          if ((a.y2 < yc) == (b.y2 < yc)) continue;
          const double x = static_cast<double>(a.x2) +
                           static_cast<double>(b.x2 - a.x2) * (yc - static_cast<double>(a.y2)) /
                               static_cast<double>(b.y2 - a.y2);
          lo = std::min(lo, x);
          hi = std::max(hi, x);
        }
        if (lo > hi) continue;
        const int32_t first = std::max<int32_t>(x0_, static_cast<int32_t>(std::floor((lo - 1) / 2)) - 1);
        const int32_t last = std::min<int32_t>(x1_ - 1, static_cast<int32_t>(std::ceil((hi - 1) / 2)) + 1);
        for (int32_t x = first; x <= last; ++x) {
          const LatticePoint p = CentreOf(Cell{x, static_cast<int32_t>(row)});
          if (Orient(c[0], c[1], p) < 0 || Orient(c[1], c[2], p) < 0 ||
              Orient(c[2], c[0], p) < 0) {
            continue;
          }
          uint16_t& slot = tile.cell_polygon[static_cast<size_t>(row - y0_) * w + (x - x0_)];
          if (slot == NavTile::kNoPolygon) slot = static_cast<uint16_t>(polygon_of[ti]);
        }
      }
    }
  }

  void IndexBorder(NavTile& tile) const {
    for (size_t pi = 0; pi < tile.polygons.size(); ++pi) {
      const NavPolygonView p = tile.polygon(static_cast<int32_t>(pi));
      for (int32_t i = 0; i < p.size; ++i) {
        if (p.across(i) != NavTile::kTileBorder) continue;
        const LatticePoint a = p.corner(i);
        const LatticePoint b = p.corner(i + 1);
        int side;
        int64_t lo;
        if (a.y2 == b.y2) {
          side = a.y2 == 2 * y0_ ? 0 : 2;
          lo = std::min(a.x2, b.x2) / 2;
        } else {
          side = a.x2 == 2 * x1_ ? 1 : 3;
          lo = std::min(a.y2, b.y2) / 2;
        }
        tile.border[side].emplace_back(static_cast<int32_t>(lo), static_cast<int32_t>(pi));
      }
    }
    for (auto& side : tile.border) std::sort(side.begin(), side.end());
  }

  const BlockedCells& blocked_;
  const int32_t x0_, y0_, x1_, y1_;
  std::vector<Cdt::Vertex_handle> handles_;
  Cdt cdt_;
};

std::shared_ptr<const NavTile> BuildTile(const BlockedCells& blocked,
                                         int32_t tile_size, int32_t tx,
                                         int32_t ty, int32_t width,
                                         int32_t height) {
  const int32_t t = tile_size;
  return TileBuilder(blocked, tx * t, ty * t, std::min(width, (tx + 1) * t),
                     std::min(height, (ty + 1) * t))
      .Build();
}

// The tiles whose closed extent holds grid line `line`: one, or two on a
// border between tiles.
std::pair<int32_t, int32_t> TilesAtLine(int32_t line, int32_t tile_size,
                                        int32_t count) {
  const int32_t lo = line > 0 ? (line - 1) / tile_size : 0;
  return {std::min(lo, count - 1), std::min(count - 1, line / tile_size)};
}

}  // namespace

size_t NavTile::bytes() const {
  size_t b = sizeof(NavTile) + polygons.capacity() * sizeof(NavPolygon) +
             edges.capacity() * sizeof(NavEdge) +
             cell_polygon.capacity() * sizeof(uint16_t);
  for (const auto& side : border) b += side.capacity() * sizeof(side[0]);
  return b;
}

std::shared_ptr<const NavMesh> NavMesh::Build(const Grid& grid,
                                              bool unknown_is_free,
                                              int32_t tile_size) {
  const absl::Time started = absl::Now();
  std::shared_ptr<NavMesh> mesh(new NavMesh());
  mesh->width_ = grid.width();
  mesh->height_ = grid.height();
  mesh->unknown_is_free_ = unknown_is_free;
  mesh->tile_size_ = std::clamp(tile_size, 1, kMaxTileSize);
  mesh->tiles_x_ = (grid.width() + mesh->tile_size_ - 1) / mesh->tile_size_;
  mesh->tiles_y_ = (grid.height() + mesh->tile_size_ - 1) / mesh->tile_size_;
  const BlockedCells blocked(grid, unknown_is_free);
  mesh->tiles_.reserve(static_cast<size_t>(mesh->tiles_x_) * mesh->tiles_y_);
  for (int32_t ty = 0; ty < mesh->tiles_y_; ++ty) {
    for (int32_t tx = 0; tx < mesh->tiles_x_; ++tx) {
      mesh->tiles_.push_back(BuildTile(blocked, mesh->tile_size_, tx, ty,
                                       grid.width(), grid.height()));
    }
  }
  mesh->rebuilt_tiles_ = static_cast<int32_t>(mesh->tiles_.size());
  mesh->build_time_ = absl::Now() - started;
  return mesh;
}

std::shared_ptr<const NavMesh> NavMesh::Advance(const NavMesh& previous,
                                                const Grid& grid,
                                                absl::Span<const Cell> changed) {
  if (grid.width() != previous.width_ || grid.height() != previous.height_) {
    return nullptr;
  }
  const absl::Time started = absl::Now();
  std::shared_ptr<NavMesh> mesh(new NavMesh(previous));
  // A cell decides the vertices at its four corners and the class of the
  // faces over it: every tile whose closed extent holds one of its corners
  // may change.
  std::vector<bool> dirty(mesh->tiles_.size(), false);
  for (const Cell& c : changed) {
    if (!grid.InBounds(c)) continue;
    const auto [tx0, tx1] = TilesAtLine(c.x, mesh->tile_size_, mesh->tiles_x_);
    const auto [tx2, tx3] = TilesAtLine(c.x + 1, mesh->tile_size_, mesh->tiles_x_);
    const auto [ty0, ty1] = TilesAtLine(c.y, mesh->tile_size_, mesh->tiles_y_);
    const auto [ty2, ty3] = TilesAtLine(c.y + 1, mesh->tile_size_, mesh->tiles_y_);
    for (int32_t ty = std::min(ty0, ty2); ty <= std::max(ty1, ty3); ++ty) {
      for (int32_t tx = std::min(tx0, tx2); tx <= std::max(tx1, tx3); ++tx) {
        dirty[static_cast<size_t>(ty) * mesh->tiles_x_ + tx] = true;
      }
    }
  }
  const BlockedCells blocked(grid, mesh->unknown_is_free_);
  mesh->rebuilt_tiles_ = 0;
  for (int32_t ty = 0; ty < mesh->tiles_y_; ++ty) {
    for (int32_t tx = 0; tx < mesh->tiles_x_; ++tx) {
      const size_t i = static_cast<size_t>(ty) * mesh->tiles_x_ + tx;
      if (!dirty[i]) continue;
      mesh->tiles_[i] = BuildTile(blocked, mesh->tile_size_, tx, ty,
                                  grid.width(), grid.height());
      ++mesh->rebuilt_tiles_;
    }
  }
  mesh->build_time_ = absl::Now() - started;
  return mesh;
}

NavRef NavMesh::AcrossBorder(NavRef ref, int edge) const {
  const NavTile& tile = *tiles_[ref.tile];
  const NavPolygonView p = tile.polygon(ref.polygon);
  const LatticePoint a = p.corner(edge);
  const LatticePoint b = p.corner(edge + 1);
  const int32_t tx = ref.tile % tiles_x_;
  const int32_t ty = ref.tile / tiles_x_;
  int32_t ntx = tx;
  int32_t nty = ty;
  int side;  // the neighbour's side
  int64_t lo;
  if (a.y2 == b.y2) {
    nty += a.y2 == 2 * tile.y0 ? -1 : 1;
    side = a.y2 == 2 * tile.y0 ? 2 : 0;
    lo = std::min(a.x2, b.x2) / 2;
  } else {
    ntx += a.x2 == 2 * tile.x1 ? 1 : -1;
    side = a.x2 == 2 * tile.x1 ? 3 : 1;
    lo = std::min(a.y2, b.y2) / 2;
  }
  if (ntx < 0 || nty < 0 || ntx >= tiles_x_ || nty >= tiles_y_) return NavRef{};
  const int32_t n = nty * tiles_x_ + ntx;
  const auto& entries = tiles_[n]->border[side];
  const auto it = std::lower_bound(
      entries.begin(), entries.end(), std::make_pair(static_cast<int32_t>(lo), INT32_MIN));
  if (it == entries.end() || it->first != lo) return NavRef{};
  return NavRef{n, it->second};
}

std::vector<NavRef> NavMesh::Locate(Cell cell) const {
  std::vector<NavRef> found;
  if (cell.x < 0 || cell.y < 0 || cell.x >= width_ || cell.y >= height_) return found;
  const int32_t tx = cell.x / tile_size_;
  const int32_t ty = cell.y / tile_size_;
  const int32_t ti = ty * tiles_x_ + tx;
  const NavTile& tile = *tiles_[ti];
  const uint16_t local =
      tile.cell_polygon[static_cast<size_t>(cell.y - tile.y0) * (tile.x1 - tile.x0) +
                        (cell.x - tile.x0)];
  if (local == NavTile::kNoPolygon) return found;
  const NavRef ref{ti, local};
  found.push_back(ref);
  const LatticePoint c = CentreOf(cell);
  const NavPolygonView p = tile.polygon(local);
  for (int32_t i = 0; i < p.size; ++i) {
    // On the edge, not merely on its line (a polygon's side may be several
    // collinear edges).
    const LatticePoint a = p.corner(i);
    const LatticePoint b = p.corner(i + 1);
    if (Orient(a, b, c) != 0 ||
        (c.x2 - a.x2) * (c.x2 - b.x2) + (c.y2 - a.y2) * (c.y2 - b.y2) > 0) {
      continue;
    }
    const NavRef other = Across(ref, i);
    if (other.valid()) found.push_back(other);
  }
  return found;
}

bool NavMesh::UniformCost() const {
  std::array<uint64_t, 4> all{};
  for (const auto& t : tiles_) {
    for (int i = 0; i < 4; ++i) all[i] |= t->traversable_costs[i];
  }
  int values = 0;
  for (const uint64_t w : all) values += std::popcount(w);
  return values <= 1;
}

int64_t NavMesh::polygon_count() const {
  int64_t n = 0;
  for (const auto& t : tiles_) n += static_cast<int64_t>(t->polygons.size());
  return n;
}

int64_t NavMesh::triangle_count() const {
  int64_t n = 0;
  for (const auto& t : tiles_) n += t->triangle_count;
  return n;
}

int64_t NavMesh::vertex_count() const {
  int64_t n = 0;
  for (const auto& t : tiles_) n += t->vertex_count;
  return n;
}

size_t NavMesh::bytes() const {
  size_t b = sizeof(NavMesh) + tiles_.capacity() * sizeof(tiles_[0]);
  for (const auto& t : tiles_) b += t->bytes();
  return b;
}

GeometricStructure DescribeNavMesh(const Grid& grid, bool unknown_is_free) {
  const std::shared_ptr<const NavMesh> mesh = NavMesh::Build(grid, unknown_is_free);
  GeometricStructure s;
  s.kind = "mesh";
  s.counts = {{"tiles", static_cast<int64_t>(mesh->tiles().size())},
              {"vertices", mesh->vertex_count()},
              {"triangles", mesh->triangle_count()},
              {"polygons", mesh->polygon_count()}};
  s.bytes = mesh->bytes();
  s.build_time = mesh->build_time();
  for (int32_t ti = 0; ti < static_cast<int32_t>(mesh->tiles().size()); ++ti) {
    const NavTile& tile = mesh->tile(ti);
    for (int32_t k = 0; k < static_cast<int32_t>(tile.polygons.size()); ++k) {
      const NavPolygonView p = tile.polygon(k);
      for (int32_t i = 0; i < p.size; ++i) {
        // Each edge once: from the polygon with the smaller reference.
        const NavRef other = mesh->Across(NavRef{ti, k}, i);
        if (other.valid() && (other.tile < ti || (other.tile == ti && other.polygon < k))) {
          continue;
        }
        s.segments.push_back({ToCellPoint(p.corner(i)), ToCellPoint(p.corner(i + 1))});
      }
    }
  }
  return s;
}

}  // namespace pathd
