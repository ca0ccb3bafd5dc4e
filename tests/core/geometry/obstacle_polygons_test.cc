// The polygonal model: rings on hand-made maps, and rings advanced through
// random update sequences equal to rings built from scratch.
#include "core/geometry/obstacle_polygons.h"

#include <random>
#include <string>
#include <vector>

#include "core/geometry/structure.h"
#include "gtest/gtest.h"

namespace pathd {
namespace {

Grid GridFrom(const std::vector<std::string>& rows) {
  Grid grid = *Grid::Create(static_cast<int32_t>(rows[0].size()),
                            static_cast<int32_t>(rows.size()));
  for (size_t y = 0; y < rows.size(); ++y) {
    for (size_t x = 0; x < rows[y].size(); ++x) {
      grid.set_cost(static_cast<int32_t>(x), static_cast<int32_t>(y),
                    rows[y][x] == '#' ? kLethalCost : kFreeCost);
    }
  }
  return grid;
}

std::shared_ptr<const ObstaclePolygons> Build(const Grid& grid) {
  return ObstaclePolygons::Build(FreeSpace(grid, false));
}

TEST(ObstaclePolygonsTest, AnOpenMapIsOneCounterClockwiseRing) {
  auto p = Build(GridFrom({"...", "...", "..."}));
  ASSERT_EQ(p->rings().size(), 1u);
  const BoundaryRing& ring = p->rings()[0];
  EXPECT_EQ(ring.twice_area, 2 * 3 * 3);
  EXPECT_EQ(ring.vertices.size(), 4u);
  EXPECT_EQ(p->hole_count(), 0);
}

TEST(ObstaclePolygonsTest, AnObstacleIsAClockwiseHole) {
  auto p = Build(GridFrom({"....", ".##.", "...."}));
  ASSERT_EQ(p->rings().size(), 2u);
  EXPECT_EQ(p->hole_count(), 1);
  for (const BoundaryRing& ring : p->rings()) {
    if (ring.is_hole()) {
      EXPECT_EQ(ring.twice_area, -2 * 2);
      EXPECT_EQ(ring.vertices.size(), 4u);  // collinear runs merged
    } else {
      EXPECT_EQ(ring.twice_area, 2 * 12);
    }
  }
}

TEST(ObstaclePolygonsTest, ObstaclesTouchingAtAPinchShareOneRingThatTouchesItTwice) {
  auto p = Build(GridFrom({"....", ".#..", "..#.", "...."}));
  ASSERT_EQ(p->rings().size(), 2u);
  for (const BoundaryRing& ring : p->rings()) {
    if (!ring.is_hole()) continue;
    EXPECT_EQ(ring.twice_area, -2 * 2);
    int at_pinch = 0;
    for (const GridCorner& v : ring.vertices) at_pinch += v == GridCorner{2, 2} ? 1 : 0;
    EXPECT_EQ(at_pinch, 2);
  }
}

TEST(ObstaclePolygonsTest, AWallAcrossTheMapMakesTwoRegions) {
  auto p = Build(GridFrom({"..#..", "..#..", "..#.."}));
  ASSERT_EQ(p->rings().size(), 2u);
  EXPECT_EQ(p->hole_count(), 0);
}

TEST(ObstaclePolygonsTest, TheDescriptionCountsRegionsHolesAndVertices) {
  const absl::StatusOr<GeometricStructure> s =
      DescribeStructure("polygons", GridFrom({"....", ".##.", "...."}), false);
  ASSERT_TRUE(s.ok()) << s.status();
  ASSERT_EQ(s->counts.size(), 3u);
  EXPECT_EQ(s->counts[0].second, 1);
  EXPECT_EQ(s->counts[1].second, 1);
  EXPECT_EQ(s->counts[2].second, 8);
  EXPECT_EQ(s->segments.size(), 8u);
  EXPECT_FALSE(DescribeStructure("no_such", GridFrom({"."}), false).ok());
}

// Random maps, random batches of changed cells: the advanced rings equal a
// fresh build's after every batch.
TEST(ObstaclePolygonsTest, AdvancedRingsEqualRebuiltRings) {
  std::mt19937 rng(20261201);
  for (int trial = 0; trial < 300; ++trial) {
    const int w = 1 + static_cast<int>(rng() % 24);
    const int h = 1 + static_cast<int>(rng() % 24);
    Grid grid = *Grid::Create(w, h);
    const int density = static_cast<int>(rng() % 50);
    for (uint8_t& v : grid.mutable_cells()) {
      v = static_cast<int>(rng() % 100) < density ? kLethalCost : kFreeCost;
    }
    FreeSpace space(grid, false);
    std::shared_ptr<const ObstaclePolygons> rings = ObstaclePolygons::Build(space);
    for (int step = 0; step < 8; ++step) {
      std::vector<Cell> changed;
      const int n = 1 + static_cast<int>(rng() % 6);
      for (int i = 0; i < n; ++i) {
        const Cell c{static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h)};
        const uint8_t v = rng() % 2 ? kLethalCost : kFreeCost;
        if (grid.cost(c) == v) continue;
        if (std::find(changed.begin(), changed.end(), c) != changed.end()) continue;
        grid.set_cost(c, v);
        changed.push_back(c);
      }
      space.Update(grid, changed);
      rings = ObstaclePolygons::Advance(*rings, space, changed);
      ASSERT_EQ(rings->Canonical(), ObstaclePolygons::Build(space)->Canonical())
          << "trial " << trial << " step " << step;
    }
  }
}

}  // namespace
}  // namespace pathd
