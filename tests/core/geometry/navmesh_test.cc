// The navigation mesh: its convex polygons tile exactly the free cells, meet
// edge to edge across tile borders, keep pinch corners closed, and an
// advanced mesh is the rebuilt one tile for tile. And the funnel, on channels whose
// shortest path is known.
#include "core/geometry/navmesh.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "core/geometry/funnel.h"
#include "core/geometry/structure.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "gtest/gtest.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

Grid RandomGrid(std::mt19937& rng, int max_side) {
  const int w = 1 + static_cast<int>(rng() % max_side);
  const int h = 1 + static_cast<int>(rng() % max_side);
  Grid grid = Grid::Create(w, h).value();
  const int density = static_cast<int>(rng() % 60);
  for (size_t i = 0; i < grid.size(); ++i) {
    const int roll = static_cast<int>(rng() % 100);
    if (roll < density) grid.mutable_cells()[i] = rng() % 4 ? kLethalCost : kUnknownCost;
  }
  return grid;
}

int64_t FreeCellCount(const Grid& grid, bool unknown_is_free) {
  int64_t n = 0;
  for (uint8_t c : grid.cells()) n += Traversable(c, unknown_is_free) ? 1 : 0;
  return n;
}

// Checks what makes the mesh a mesh of the free space.
void ExpectValidMesh(const NavMesh& mesh, const Grid& grid, bool unknown_is_free,
                     const std::string& what) {
  const FreeSpace space(grid, unknown_is_free);
  int64_t doubled_area = 0;  // 8 x area in cells
  for (int32_t ti = 0; ti < static_cast<int32_t>(mesh.tiles().size()); ++ti) {
    const NavTile& tile = mesh.tile(ti);
    for (int32_t k = 0; k < static_cast<int32_t>(tile.polygons.size()); ++k) {
      const NavPolygonView t = tile.polygon(k);
      ASSERT_GE(t.size, 3) << what;
      int64_t o = 0;
      for (int i = 0; i < t.size; ++i) {
        // Shoelace, and convex at every corner: a left turn or straight on.
        o += Orient(t.corner(0), t.corner(i), t.corner(i + 1));
        const LatticePoint prev = t.corner(i + t.size - 1);
        const LatticePoint at = t.corner(i);
        const LatticePoint next = t.corner(i + 1);
        const int64_t turn = Orient(prev, at, next);
        ASSERT_TRUE(turn > 0 || (turn == 0 && (at.x2 - prev.x2) * (next.x2 - at.x2) +
                                                      (at.y2 - prev.y2) * (next.y2 - at.y2) >
                                                  0))
            << what << " polygon not convex";
      }
      ASSERT_GT(o, 0) << what << " polygon not counter-clockwise";
      doubled_area += o;
      for (int i = 0; i < t.size; ++i) {
        const LatticePoint c = t.corner(i);
        ASSERT_TRUE(c.x2 % 2 == 0 && c.y2 % 2 == 0) << what;
        ASSERT_TRUE(c.x2 >= 2 * tile.x0 && c.x2 <= 2 * tile.x1 && c.y2 >= 2 * tile.y0 &&
                    c.y2 <= 2 * tile.y1)
            << what << " corner outside its tile";
        // Neighbours agree on their shared edge, within and across tiles.
        const NavRef other = mesh.Across(NavRef{ti, k}, i);
        if (!other.valid()) continue;
        const NavPolygonView n = mesh.polygon(other);
        bool back = false;
        for (int j = 0; j < n.size; ++j) {
          if (n.corner(j) == t.corner(i + 1) && n.corner(j + 1) == c) {
            back = mesh.Across(other, j) == (NavRef{ti, k});
          }
        }
        ASSERT_TRUE(back) << what << " neighbours disagree";
      }
    }
  }
  // Free polygons cover exactly the free cells' area (area of a unit cell
  // is 8 in doubled coordinates' cross product units)...
  EXPECT_EQ(doubled_area, 8 * FreeCellCount(grid, unknown_is_free)) << what;
  // ... and every free centre is found, no blocked one.
  for (int32_t y = 0; y < grid.height(); ++y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      const std::vector<NavRef> at = mesh.Locate({x, y});
      ASSERT_EQ(at.empty(), space.Blocked(x, y)) << what << " cell " << x << "," << y;
      for (const NavRef& r : at) {
        const NavPolygonView c = mesh.polygon(r);
        const LatticePoint p = CentreOf({x, y});
        for (int i = 0; i < c.size; ++i) {
          EXPECT_GE(Orient(c.corner(i), c.corner(i + 1), p), 0) << what;
        }
      }
    }
  }
}

TEST(NavMesh, PolygonsTileTheFreeCellsExactly) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 600; ++trial) {
    const Grid grid = RandomGrid(rng, 20);
    const bool unknown_is_free = trial % 3 == 0;
    const int tile = 1 + trial % 9;
    const auto mesh = NavMesh::Build(grid, unknown_is_free, tile);
    ExpectValidMesh(*mesh, grid, unknown_is_free,
                    "trial " + std::to_string(trial) + " tile " + std::to_string(tile));
    if (HasFatalFailure()) return;
  }
}

TEST(NavMesh, OpenMapIsOneRectanglePerTile) {
  const Grid grid = Grid::Create(100, 70).value();
  const auto mesh = NavMesh::Build(grid, false, 64);
  EXPECT_EQ(mesh->tiles().size(), 4u);
  EXPECT_EQ(mesh->triangle_count(), 8);
  EXPECT_EQ(mesh->polygon_count(), 4);
  const auto big = NavMesh::Build(grid, false, 128);
  EXPECT_EQ(big->tiles().size(), 1u);
  EXPECT_EQ(big->polygon_count(), 1);
  EXPECT_EQ(big->polygon(NavRef{0, 0}).size, 4);
}

TEST(NavMesh, MergesTrianglesIntoFewerPolygons) {
  // A room with pillars: many triangles, far fewer convex polygons.
  Grid grid = Grid::Create(40, 40).value();
  for (int32_t y = 3; y < 40; y += 6) {
    for (int32_t x = 3; x < 40; x += 6) grid.set_cost(x, y, kLethalCost);
  }
  const auto mesh = NavMesh::Build(grid, false, 64);
  EXPECT_LT(3 * mesh->polygon_count(), 2 * mesh->triangle_count());
  ExpectValidMesh(*mesh, grid, false, "pillars");
}

TEST(NavMesh, PinchCornerJoinsNoPolygons) {
  // Cells (1, 0) and (0, 1) blocked: the free cells (0, 0) and (1, 1) touch
  // only at the pinch corner (1, 1).
  const Grid grid = MakeGrid({".#", "#."});
  const auto mesh = NavMesh::Build(grid, false);
  const std::vector<NavRef> a = mesh->Locate({0, 0});
  const std::vector<NavRef> b = mesh->Locate({1, 1});
  ASSERT_FALSE(a.empty());
  ASSERT_FALSE(b.empty());
  // Walk everything reachable from (0, 0)'s polygons.
  std::vector<NavRef> seen = a;
  for (size_t i = 0; i < seen.size(); ++i) {
    for (int e = 0; e < mesh->polygon(seen[i]).size; ++e) {
      const NavRef n = mesh->Across(seen[i], e);
      if (n.valid() && std::find(seen.begin(), seen.end(), n) == seen.end()) {
        seen.push_back(n);
      }
    }
  }
  for (const NavRef& r : b) {
    EXPECT_EQ(std::find(seen.begin(), seen.end(), r), seen.end());
  }
}

bool SameTile(const NavTile& a, const NavTile& b) {
  if (a.polygons.size() != b.polygons.size() || a.cell_polygon != b.cell_polygon ||
      a.border != b.border || a.edges != b.edges) {
    return false;
  }
  for (size_t i = 0; i < a.polygons.size(); ++i) {
    if (a.polygons[i].first != b.polygons[i].first ||
        a.polygons[i].size != b.polygons[i].size) {
      return false;
    }
  }
  return true;
}

TEST(NavMesh, AdvanceEqualsRebuildTileForTile) {
  std::mt19937 rng(5);
  for (int run = 0; run < 30; ++run) {
    Grid grid = Grid::Create(17 + run % 13, 11 + run % 7).value();
    for (size_t i = 0; i < grid.size(); ++i) {
      if (rng() % 100 < 30) grid.mutable_cells()[i] = kLethalCost;
    }
    const int tile = 2 + run % 6;
    std::shared_ptr<const NavMesh> mesh = NavMesh::Build(grid, false, tile);
    for (int step = 0; step < 15; ++step) {
      std::vector<Cell> changed;
      const int n = 1 + static_cast<int>(rng() % 4);
      for (int k = 0; k < n; ++k) {
        // Tile borders and corners are where an update reaches furthest.
        Cell c{static_cast<int32_t>(rng() % grid.width()),
               static_cast<int32_t>(rng() % grid.height())};
        if (rng() % 2) c.x = std::min<int32_t>(grid.width() - 1, (c.x / tile) * tile);
        grid.set_cost(c, grid.cost(c) == kLethalCost ? kFreeCost : kLethalCost);
        changed.push_back(c);
      }
      const std::shared_ptr<const NavMesh> previous = mesh;
      mesh = NavMesh::Advance(*previous, grid, changed);
      ASSERT_NE(mesh, nullptr);
      EXPECT_LE(mesh->rebuilt_tiles(), 4 * n);
      const auto rebuilt = NavMesh::Build(grid, false, tile);
      ASSERT_EQ(mesh->tiles().size(), rebuilt->tiles().size());
      int shared = 0;
      for (size_t t = 0; t < mesh->tiles().size(); ++t) {
        ASSERT_TRUE(SameTile(*mesh->tiles()[t], *rebuilt->tiles()[t]))
            << "run " << run << " step " << step << " tile " << t;
        shared += mesh->tiles()[t] == previous->tiles()[t] ? 1 : 0;
      }
      EXPECT_EQ(shared + mesh->rebuilt_tiles(), static_cast<int>(mesh->tiles().size()));
    }
  }
  EXPECT_EQ(NavMesh::Advance(*NavMesh::Build(Grid::Create(3, 3).value(), false),
                             Grid::Create(4, 3).value(), {}),
            nullptr);
}

TEST(NavMesh, DescribedAsMesh) {
  const Grid grid = MakeGrid({"....", ".##.", "...."});
  auto s = DescribeStructure("mesh", grid, false);
  ASSERT_TRUE(s.ok()) << s.status();
  EXPECT_EQ(s->kind, "mesh");
  ASSERT_EQ(s->counts.size(), 4u);
  EXPECT_EQ(s->counts[0].first, "tiles");
  EXPECT_EQ(s->counts[0].second, 1);
  EXPECT_EQ(s->counts[2].first, "triangles");
  EXPECT_EQ(s->counts[3].first, "polygons");
  const auto mesh = NavMesh::Build(grid, false);
  EXPECT_EQ(s->counts[2].second, mesh->triangle_count());
  EXPECT_EQ(s->counts[3].second, mesh->polygon_count());
  // Each polygon edge once, shared ones drawn once.
  int64_t edges = 0;
  int64_t walls = 0;
  for (int32_t k = 0; k < mesh->polygon_count(); ++k) {
    const int32_t size = mesh->polygon(NavRef{0, k}).size;
    edges += size;
    for (int e = 0; e < size; ++e) walls += mesh->Across(NavRef{0, k}, e).valid() ? 0 : 1;
  }
  EXPECT_EQ(static_cast<int64_t>(s->segments.size()), (edges + walls) / 2);
  EXPECT_GT(s->bytes, 0u);
}

// ---- funnel ----

double Length(const std::vector<CellPoint>& path) {
  double l = 0;
  for (size_t i = 1; i < path.size(); ++i) {
    l += std::hypot(path[i].x - path[i - 1].x, path[i].y - path[i - 1].y);
  }
  return l;
}

TEST(Funnel, StraightCorridorIsOneSegment) {
  // Walking +x: left is +y (positive cross product).
  std::vector<Portal> portals;
  for (int x = 1; x < 10; ++x) portals.push_back({{double(x), 1.0}, {double(x), 0.0}});
  const auto path = FunnelPath({0.5, 0.5}, portals, {9.5, 0.5});
  ASSERT_EQ(path.size(), 2u);
  EXPECT_EQ(path[1].x, 9.5);
}

TEST(Funnel, BendsAtTheInnerCornerOfAnL) {
  // A corridor along +x (y in [0, 1]) then up +y (x in [4, 5]); the path
  // bends at the inner corner (4, 1).
  const std::vector<Portal> portals = {
      {{1, 1}, {1, 0}}, {{2, 1}, {2, 0}}, {{3, 1}, {3, 0}}, {{4, 1}, {4, 0}},
      // Into the corner cell, then up: walking +y, left is -x.
      {{4, 1}, {5, 1}}, {{4, 2}, {5, 2}}, {{4, 3}, {5, 3}}};
  const auto path = FunnelPath({0.5, 0.5}, portals, {4.5, 3.5});
  ASSERT_EQ(path.size(), 3u);
  EXPECT_EQ(path[1].x, 4.0);
  EXPECT_EQ(path[1].y, 1.0);
  EXPECT_NEAR(Length(path), std::hypot(3.5, 0.5) + std::hypot(0.5, 2.5), 1e-12);
}

TEST(Funnel, ZigZagBendsOnBothSides) {
  // Walking +x: the first portal (x = 2) is open above y = 2, the second
  // (x = 4) below y = 1, so the path bends at the first's right end (2, 2)
  // and the second's left end (4, 1).
  const std::vector<Portal> portals = {{{2, 4}, {2, 2}}, {{4, 1}, {4, 0}}};
  const auto path = FunnelPath({0, 0}, portals, {6, 4});
  ASSERT_EQ(path.size(), 4u);
  EXPECT_EQ(path[1].x, 2.0);
  EXPECT_EQ(path[1].y, 2.0);
  EXPECT_EQ(path[2].x, 4.0);
  EXPECT_EQ(path[2].y, 1.0);
  // Where the line already passes, no bend.
  const std::vector<Portal> wide = {{{2, 4}, {2, 1}}, {{4, 3}, {4, 0}}};
  EXPECT_EQ(FunnelPath({0, 0}, wide, {6, 4}).size(), 2u);
}

TEST(Funnel, NoPortalsIsTheSegment) {
  const auto path = FunnelPath({0, 0}, {}, {3, 4});
  ASSERT_EQ(path.size(), 2u);
  EXPECT_EQ(Length(path), 5.0);
}

}  // namespace
}  // namespace pathd
