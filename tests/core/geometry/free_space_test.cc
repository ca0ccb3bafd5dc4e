// The free-space rule of the geometric planners on hand-made cases; the
// randomised comparison with an independent checker is in
// geometric_planners_test.
#include "core/geometry/free_space.h"

#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

TEST(FreeSpaceTest, OpenGridAndItsBorder) {
  const FreeSpace space(MakeGrid({"...", "...", "..."}), false);
  EXPECT_TRUE(space.SegmentClear(CentreOf({0, 0}), CentreOf({2, 2})));
  // Along the map border: the outside is blocked, the inside free.
  EXPECT_TRUE(space.SegmentClear(CornerAt(0, 0), CornerAt(3, 0)));
  EXPECT_TRUE(space.SegmentClear(CornerAt(3, 0), CornerAt(3, 3)));
  // Outside the map.
  EXPECT_FALSE(space.SegmentClear(CornerAt(0, 0), CornerAt(-1, 0)));
  EXPECT_FALSE(space.PointFree(CornerAt(4, 1)));
  // Map corners are enclosed on three sides: not bend corners.
  EXPECT_TRUE(space.BendCorners().empty());
}

TEST(FreeSpaceTest, OneBlockedCellIsTouchedNotCrossed) {
  const FreeSpace space(MakeGrid({"...", ".#.", "..."}), false);
  EXPECT_FALSE(space.SegmentClear(CentreOf({0, 0}), CentreOf({2, 2})));
  EXPECT_FALSE(space.SegmentClear(CornerAt(1, 1), CornerAt(2, 2)));
  // Along its edges and through its corners.
  EXPECT_TRUE(space.SegmentClear(CornerAt(1, 1), CornerAt(2, 1)));
  EXPECT_TRUE(space.SegmentClear(CentreOf({0, 0}), CornerAt(1, 1)));
  EXPECT_TRUE(space.SegmentClear(CentreOf({0, 1}), CentreOf({1, 0})));
  EXPECT_TRUE(space.SegmentClear(CentreOf({0, 0}), CentreOf({2, 0})));
  // (0.5, 0.5) -> (2.5, 1.5) crosses the blocked cell's interior.
  EXPECT_FALSE(space.SegmentClear(CentreOf({0, 0}), CentreOf({2, 1})));
  std::vector<LatticePoint> bends = space.BendCorners();
  ASSERT_EQ(bends.size(), 4u);
  EXPECT_EQ(bends[0], CornerAt(1, 1));
  EXPECT_EQ(bends[3], CornerAt(2, 2));
}

TEST(FreeSpaceTest, PinchesAreClosed) {
  // (0, 0) and (1, 1) blocked: they touch at corner (1, 1).
  const FreeSpace space(MakeGrid({"#..", ".#.", "..."}), false);
  EXPECT_FALSE(space.PointFree(CornerAt(1, 1)));
  EXPECT_FALSE(space.SegmentClear(CentreOf({1, 0}), CentreOf({0, 1})));
  EXPECT_FALSE(space.IsBendCorner(1, 1));
  // Past the pinch on the free side of both cells.
  EXPECT_TRUE(space.SegmentClear(CentreOf({2, 0}), CornerAt(2, 1)));
}

TEST(FreeSpaceTest, WallsAreClosedBetweenTheirCells) {
  const FreeSpace space(MakeGrid({"....", ".##.", "...."}), false);
  // The edge between the two wall cells.
  EXPECT_FALSE(space.SegmentClear(CornerAt(2, 1), CornerAt(2, 2)));
  EXPECT_FALSE(space.SegmentClear(CornerAt(2, 0), CornerAt(2, 3)));
  // Along the wall's top side, corner to corner.
  EXPECT_TRUE(space.SegmentClear(CornerAt(0, 1), CornerAt(4, 1)));
  EXPECT_FALSE(space.SegmentClear(CornerAt(1, 1), CornerAt(3, 2)));
  // A map corner is on the boundary of its cell.
  EXPECT_TRUE(space.PointFree(CornerAt(0, 0)));
}

TEST(FreeSpaceTest, CellsAlongPolylineFollowTheSegments) {
  const FreeSpace space(MakeGrid({"...", ".#.", "..."}), false);
  // Round the blocked cell's left side.
  const std::vector<LatticePoint> polyline = {CentreOf({0, 0}), CornerAt(1, 1),
                                              CornerAt(1, 2), CentreOf({1, 2})};
  ASSERT_TRUE(space.PolylineClear(polyline));
  EXPECT_DOUBLE_EQ(PolylineLength(polyline), 2.0 * std::sqrt(0.5) + 1.0);
  // Straight into the blocked cell from its corner.
  EXPECT_FALSE(space.SegmentClear(CornerAt(1, 1), CentreOf({1, 2})));
  const std::vector<Cell> cells = CellsAlongPolyline(space, polyline);
  ASSERT_FALSE(cells.empty());
  EXPECT_EQ(cells.front(), (Cell{0, 0}));
  EXPECT_EQ(cells.back(), (Cell{1, 2}));
  for (const Cell& c : cells) EXPECT_FALSE(space.Blocked(c.x, c.y));
}

TEST(FreeSpaceTest, UpdateReadsChangedCells) {
  Grid grid = MakeGrid({"...", "...", "..."});
  FreeSpace space(grid, false);
  grid.set_cost(1, 1, kLethalCost);
  space.Update(grid, std::vector<Cell>{{1, 1}});
  EXPECT_TRUE(space.Blocked(1, 1));
  EXPECT_EQ(space.BendCorners().size(), 4u);
}

}  // namespace
}  // namespace pathd
