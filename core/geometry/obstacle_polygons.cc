#include "core/geometry/obstacle_polygons.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "absl/container/flat_hash_set.h"
#include "absl/time/clock.h"
#include "core/geometry/structure.h"

namespace pathd {
namespace {

// Directions: 0 +x, 1 +y, 2 -x, 3 -y; a left turn is +1.
constexpr std::array<int32_t, 4> kDx = {1, 0, -1, 0};
constexpr std::array<int32_t, 4> kDy = {0, 1, 0, -1};

// The cells left and right of the unit edge leaving corner (x, y) in
// direction d.
Cell LeftOf(int32_t x, int32_t y, int d) {
  switch (d) {
    case 0: return Cell{x, y};
    case 1: return Cell{x - 1, y};
    case 2: return Cell{x - 1, y - 1};
    default: return Cell{x, y - 1};
  }
}
Cell RightOf(int32_t x, int32_t y, int d) {
  switch (d) {
    case 0: return Cell{x, y - 1};
    case 1: return Cell{x, y};
    case 2: return Cell{x - 1, y};
    default: return Cell{x - 1, y - 1};
  }
}

// The unit edge from corner (x, y) in direction d is on the boundary with
// free space on its left.
bool BoundaryEdge(const FreeSpace& space, int32_t x, int32_t y, int d) {
  const Cell left = LeftOf(x, y, d);
  const Cell right = RightOf(x, y, d);
  return !space.Blocked(left.x, left.y) && space.Blocked(right.x, right.y);
}

// Follows the boundary from the edge leaving (x, y) in direction d until it
// returns, turning left before going straight before turning right, so that
// at a pinch the ring stays with the free cell it borders. `visit` sees each
// unit edge (corner, direction) once.
template <typename Visit>
BoundaryRing TraceRing(const FreeSpace& space, int32_t x0, int32_t y0, int d0,
                       Visit&& visit) {
  BoundaryRing ring;
  int32_t x = x0;
  int32_t y = y0;
  int d = d0;
  do {
    visit(x, y, d);
    x += kDx[d];
    y += kDy[d];
    int next = d;
    for (int turn : {1, 0, 3}) {
      next = (d + turn) % 4;
      if (BoundaryEdge(space, x, y, next)) break;
    }
    if (next != d) ring.vertices.push_back(GridCorner{x, y});
    d = next;
  } while (!(x == x0 && y == y0 && d == d0));
  ring.min = ring.max = ring.vertices.front();
  const size_t n = ring.vertices.size();
  for (size_t i = 0; i < n; ++i) {
    const GridCorner& a = ring.vertices[i];
    const GridCorner& b = ring.vertices[(i + 1) % n];
    ring.twice_area += static_cast<int64_t>(a.x) * b.y - static_cast<int64_t>(b.x) * a.y;
    ring.min = GridCorner{std::min(ring.min.x, a.x), std::min(ring.min.y, a.y)};
    ring.max = GridCorner{std::max(ring.max.x, a.x), std::max(ring.max.y, a.y)};
  }
  return ring;
}

uint64_t EdgeKey(int32_t x, int32_t y, int d) {
  return (static_cast<uint64_t>(static_cast<uint32_t>(x)) << 34) |
         (static_cast<uint64_t>(static_cast<uint32_t>(y)) << 2) |
         static_cast<uint64_t>(d);
}

// Some corner of `corners` lies on the ring (a vertex or inside one of its
// axis-parallel runs).
bool RingTouches(const BoundaryRing& ring,
                 const absl::flat_hash_set<uint64_t>& corners,
                 const std::vector<GridCorner>& corner_list) {
  const size_t n = ring.vertices.size();
  for (size_t i = 0; i < n; ++i) {
    const GridCorner& a = ring.vertices[i];
    const GridCorner& b = ring.vertices[(i + 1) % n];
    const int64_t run = std::abs(static_cast<int64_t>(b.x) - a.x) +
                        std::abs(static_cast<int64_t>(b.y) - a.y);
    if (run < static_cast<int64_t>(corner_list.size())) {
      const int32_t sx = b.x > a.x ? 1 : (b.x < a.x ? -1 : 0);
      const int32_t sy = b.y > a.y ? 1 : (b.y < a.y ? -1 : 0);
      for (int64_t k = 0; k <= run; ++k) {
        const int32_t x = a.x + static_cast<int32_t>(k) * sx;
        const int32_t y = a.y + static_cast<int32_t>(k) * sy;
        if (corners.contains(EdgeKey(x, y, 0))) return true;
      }
    } else {
      for (const GridCorner& c : corner_list) {
        if (c.x >= std::min(a.x, b.x) && c.x <= std::max(a.x, b.x) &&
            c.y >= std::min(a.y, b.y) && c.y <= std::max(a.y, b.y)) {
          return true;
        }
      }
    }
  }
  return false;
}

}  // namespace

std::shared_ptr<const ObstaclePolygons> ObstaclePolygons::Build(const FreeSpace& space) {
  auto polygons = std::make_shared<ObstaclePolygons>();
  const int32_t w = space.width();
  const int32_t h = space.height();
  // One bit per (corner, direction).
  std::vector<uint8_t> visited(static_cast<size_t>(w + 1) * static_cast<size_t>(h + 1), 0);
  auto index = [w](int32_t x, int32_t y) {
    return static_cast<size_t>(y) * static_cast<size_t>(w + 1) + static_cast<size_t>(x);
  };
  for (int32_t y = 0; y <= h; ++y) {
    for (int32_t x = 0; x <= w; ++x) {
      for (int d = 0; d < 4; ++d) {
        if ((visited[index(x, y)] >> d & 1) != 0 || !BoundaryEdge(space, x, y, d)) continue;
        polygons->rings_.push_back(TraceRing(space, x, y, d, [&](int32_t cx, int32_t cy, int cd) {
          visited[index(cx, cy)] |= static_cast<uint8_t>(1 << cd);
        }));
      }
    }
  }
  return polygons;
}

std::shared_ptr<const ObstaclePolygons> ObstaclePolygons::Advance(
    const ObstaclePolygons& previous, const FreeSpace& space,
    absl::Span<const Cell> changed) {
  // A unit edge's boundary state depends on its two cells and a corner's
  // turn on its four, so only rings through a corner of a changed cell can
  // differ.
  absl::flat_hash_set<uint64_t> corners;
  std::vector<GridCorner> corner_list;
  GridCorner lo{INT32_MAX, INT32_MAX};
  GridCorner hi{INT32_MIN, INT32_MIN};
  for (const Cell& c : changed) {
    for (int32_t dy = 0; dy <= 1; ++dy) {
      for (int32_t dx = 0; dx <= 1; ++dx) {
        const GridCorner corner{c.x + dx, c.y + dy};
        if (corners.insert(EdgeKey(corner.x, corner.y, 0)).second) {
          corner_list.push_back(corner);
          lo = GridCorner{std::min(lo.x, corner.x), std::min(lo.y, corner.y)};
          hi = GridCorner{std::max(hi.x, corner.x), std::max(hi.y, corner.y)};
        }
      }
    }
  }
  auto polygons = std::make_shared<ObstaclePolygons>();
  for (const BoundaryRing& ring : previous.rings_) {
    const bool may_touch = !corner_list.empty() && ring.max.x >= lo.x &&
                           ring.min.x <= hi.x && ring.max.y >= lo.y &&
                           ring.min.y <= hi.y;
    if (!may_touch || !RingTouches(ring, corners, corner_list)) {
      polygons->rings_.push_back(ring);
    }
  }
  absl::flat_hash_set<uint64_t> traced;
  for (const GridCorner& c : corner_list) {
    for (int d = 0; d < 4; ++d) {
      if (traced.contains(EdgeKey(c.x, c.y, d)) || !BoundaryEdge(space, c.x, c.y, d)) {
        continue;
      }
      polygons->rings_.push_back(TraceRing(space, c.x, c.y, d, [&](int32_t x, int32_t y, int cd) {
        traced.insert(EdgeKey(x, y, cd));
      }));
    }
  }
  return polygons;
}

int64_t ObstaclePolygons::vertex_count() const {
  int64_t n = 0;
  for (const BoundaryRing& ring : rings_) n += static_cast<int64_t>(ring.vertices.size());
  return n;
}

int64_t ObstaclePolygons::hole_count() const {
  return std::count_if(rings_.begin(), rings_.end(),
                       [](const BoundaryRing& r) { return r.is_hole(); });
}

size_t ObstaclePolygons::bytes() const {
  size_t bytes = sizeof(*this) + rings_.capacity() * sizeof(BoundaryRing);
  for (const BoundaryRing& ring : rings_) {
    bytes += ring.vertices.capacity() * sizeof(GridCorner);
  }
  return bytes;
}

std::vector<std::vector<GridCorner>> ObstaclePolygons::Canonical() const {
  std::vector<std::vector<GridCorner>> rings;
  rings.reserve(rings_.size());
  for (const BoundaryRing& ring : rings_) {
    std::vector<GridCorner> v = ring.vertices;
    std::rotate(v.begin(), std::min_element(v.begin(), v.end()), v.end());
    rings.push_back(std::move(v));
  }
  std::sort(rings.begin(), rings.end());
  return rings;
}

GeometricStructure DescribeObstaclePolygons(const Grid& grid, bool unknown_is_free) {
  const absl::Time start = absl::Now();
  const FreeSpace space(grid, unknown_is_free);
  const std::shared_ptr<const ObstaclePolygons> polygons = ObstaclePolygons::Build(space);
  GeometricStructure s;
  s.kind = "polygons";
  s.build_time = absl::Now() - start;
  const int64_t holes = polygons->hole_count();
  s.counts = {{"regions", static_cast<int64_t>(polygons->rings().size()) - holes},
              {"holes", holes},
              {"vertices", polygons->vertex_count()}};
  s.bytes = polygons->bytes() + space.bytes();
  for (const BoundaryRing& ring : polygons->rings()) {
    const size_t n = ring.vertices.size();
    for (size_t i = 0; i < n; ++i) {
      const GridCorner& a = ring.vertices[i];
      const GridCorner& b = ring.vertices[(i + 1) % n];
      s.segments.push_back({CellPoint{static_cast<double>(a.x), static_cast<double>(a.y)},
                            CellPoint{static_cast<double>(b.x), static_cast<double>(b.y)}});
    }
  }
  return s;
}

}  // namespace pathd
