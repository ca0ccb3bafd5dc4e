// Nav2 inflation costs (core/map/inflation_cost.h) and the shaped grid
// advanced around changed cells (AdvanceShapedGrid) against brute force:
// every cell measured against every lethal cell's centre one by one with
// Nav2's formula, and every advanced grid against ShapeGrid afresh.
#include "core/map/inflation_cost.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/map/inflation.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace pathd {
namespace {

using ::testing::HasSubstr;

// Nav2's InflationLayer::computeCost in cells, written out here.
uint8_t Nav2Cost(double d, double r, double s) {
  if (d == 0.0) return kLethalCost;
  if (d <= r) return kInscribedCost;
  return static_cast<uint8_t>(252.0 * std::exp(-s * (d - r)));
}

// Distance from `c`'s centre to the nearest lethal cell's centre
// (infinity without one).
double BruteLethal(const Grid& grid, Cell c) {
  int64_t best = std::numeric_limits<int64_t>::max();
  for (int32_t y = 0; y < grid.height(); ++y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      if (grid.cost(x, y) != kLethalCost) continue;
      const int64_t dx = x - c.x;
      const int64_t dy = y - c.y;
      best = std::min(best, dx * dx + dy * dy);
    }
  }
  return best == std::numeric_limits<int64_t>::max()
             ? std::numeric_limits<double>::infinity()
             : std::sqrt(static_cast<double>(best));
}

// Distance to the nearest cell the robot centre may not occupy, the ring
// outside the map included (the clearance's obstacles).
double BruteClearance(const Grid& grid, Cell c, bool unknown_is_free) {
  double best = std::numeric_limits<double>::infinity();
  for (int32_t y = -1; y <= grid.height(); ++y) {
    for (int32_t x = -1; x <= grid.width(); ++x) {
      const bool outside = x < 0 || y < 0 || x >= grid.width() || y >= grid.height();
      if (!outside && Traversable(grid.cost(Cell{x, y}), unknown_is_free)) continue;
      best = std::min(best, std::hypot(x - c.x, y - c.y));
    }
  }
  return best;
}

// The whole shape by brute force: the radius (inscribed unless lethal or
// unknown), Nav2's costs beyond it (unknown cells only when free; from the
// cost-only inscribed radius when it is larger, 252 up to it), then the
// clearance ramp.
Grid BruteShape(const Grid& grid, const GridShape& shape) {
  const double r = shape.robot_radius_cells;
  const double decay = std::max(r, shape.cost_inscribed_cells);
  Grid out = grid;
  for (int32_t y = 0; y < grid.height(); ++y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      const uint8_t c = grid.cost(x, y);
      const double d = BruteLethal(grid, Cell{x, y});
      if (d <= r) {
        if (c < kLethalCost) out.set_cost(x, y, kInscribedCost);
        continue;
      }
      if (!shape.has_inflation_cost() || d > shape.inflation_radius_cells) continue;
      if (c == kInscribedCost || c == kLethalCost) continue;
      if (c == kUnknownCost && !shape.unknown_is_free) continue;
      const uint8_t own = c == kUnknownCost ? 0 : c;
      const uint8_t cost =
          d <= decay ? uint8_t{252} : Nav2Cost(d, decay, shape.cost_scaling_per_cell);
      if (cost > own) out.set_cost(x, y, cost);
    }
  }
  if (shape.min_clearance_cells <= 0.0) return out;
  const double m = shape.min_clearance_cells;
  const Grid inflated = out;
  for (int32_t y = 0; y < grid.height(); ++y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      const uint8_t c = inflated.cost(x, y);
      if (!Traversable(c, shape.unknown_is_free)) continue;
      const double d = BruteClearance(inflated, Cell{x, y}, shape.unknown_is_free);
      if (!(d < m)) continue;
      const auto ramp =
          static_cast<uint8_t>(std::clamp(std::ceil(252.0 * (m - d) / m), 1.0, 252.0));
      if (ramp > (c == kUnknownCost ? 0 : c)) out.set_cost(x, y, ramp);
    }
  }
  return out;
}

// Mostly free or lethal, some of every other cost (inscribed and unknown
// included).
uint8_t RandomCost(std::mt19937& rng, double blocked) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uniform_int_distribution<int> any(0, 255);
  uint8_t c = u(rng) < blocked ? kLethalCost : kFreeCost;
  if (u(rng) < 0.15) c = static_cast<uint8_t>(any(rng));
  return c;
}

Grid RandomGrid(std::mt19937& rng, int32_t w, int32_t h, double blocked) {
  Grid grid = Grid::Create(w, h).value();
  for (uint8_t& c : grid.mutable_cells()) c = RandomCost(rng, blocked);
  return grid;
}

// A random shape: a robot radius or none, inflation costs (radius at least
// the robot's) or none, a clearance or none, unknown cells free or not.
GridShape RandomShape(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  // Whole radii half the time: the cells exactly that far away count.
  const bool whole = u(rng) < 0.5;
  auto length = [&](double most) {
    return whole ? std::round(most * u(rng)) : most * u(rng);
  };
  const double r = u(rng) < 0.25 ? 0.0 : length(4.0);
  const double big = u(rng) < 0.6 ? r + length(8.0) : 0.0;
  const double s = 0.1 + 2.0 * u(rng);
  const double m = u(rng) < 0.5 ? 0.5 + length(4.0) : 0.0;
  // A kinematic planner's footprint: costs decaying from its inscribed
  // radius (up to the inflation radius, GridShape::Of) with nothing blocked.
  const double inscribed = u(rng) < 0.4 ? r + length(6.0) : 0.0;
  return GridShape::Of(r, big, s, m, u(rng) < 0.5, inscribed);
}

TEST(InflationCost, FollowsNav2ComputeCost) {
  // Nav2's defaults at 5 cm per cell: 0.55 m (11 cells), 10 per metre (0.5
  // per cell), a 0.2 m (4 cell) robot: 0.25 m away is 252 * e^-0.5 = 152.9.
  EXPECT_EQ(InflationCost(5.0, 4.0, 0.5), 152);
  EXPECT_EQ(InflationCost(11.0, 4.0, 0.5), 7);  // 252 * e^-3.5 = 7.6
  EXPECT_EQ(InflationCost(4.0, 4.0, 0.5), kInscribedCost);
  EXPECT_EQ(InflationCost(0.0, 4.0, 0.5), kLethalCost);
  EXPECT_EQ(InflationCost(1.0, 0.0, 0.5), 152);
  // Truncated, never rounded up: just past the radius is 251, not 252.
  EXPECT_EQ(InflationCost(4.0001, 4.0, 0.5), 251);
  EXPECT_EQ(InflationCost(100.0, 4.0, 0.5), 0);
}

// Every cell of ~200 random maps with random radii and factors against the
// brute force above.
TEST(InflationCost, ShapeMatchesBruteForceOnRandomMaps) {
  std::mt19937 rng(29);
  std::uniform_int_distribution<int> size(1, 22);
  int costed = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Grid grid = RandomGrid(rng, size(rng), size(rng), trial % 3 == 0 ? 0.03 : 0.15);
    GridShape shape = RandomShape(rng);
    // Mostly without the clearance, which has its own test.
    if (trial % 3 != 0) shape.min_clearance_cells = 0.0;
    const absl::StatusOr<Grid> got = ShapeGrid(grid, shape);
    ASSERT_TRUE(got.ok()) << got.status();
    const Grid want = BruteShape(grid, shape);
    for (int32_t y = 0; y < grid.height(); ++y) {
      for (int32_t x = 0; x < grid.width(); ++x) {
        ASSERT_EQ(got->cost(x, y), want.cost(x, y))
            << "trial " << trial << " cell (" << x << ", " << y << ") stored "
            << int{grid.cost(x, y)} << " r " << shape.robot_radius_cells << " R "
            << shape.inflation_radius_cells << " s " << shape.cost_scaling_per_cell
            << " m " << shape.min_clearance_cells << " unknown_is_free "
            << shape.unknown_is_free << " inscribed " << shape.cost_inscribed_cells;
        const uint8_t c = got->cost(x, y);
        costed += c > 0 && c < kInscribedCost && c != grid.cost(x, y);
      }
    }
  }
  // The costs were there to compare.
  EXPECT_GT(costed, 2000);
}

// ApplyInflationCost alone is the same step: the radius's cells left to the
// radius.
TEST(InflationCost, ApplyLeavesTheRadiusToInflation) {
  Grid grid = Grid::Create(15, 1).value();
  grid.set_cost(0, 0, kLethalCost);
  grid.set_cost(3, 0, 40);
  grid.set_cost(6, 0, kUnknownCost);
  Grid costed = grid;
  ASSERT_TRUE(ApplyInflationCost(2.0, 9.0, 0.5, false, &costed).ok());
  EXPECT_EQ(costed.cost(0, 0), kLethalCost);
  EXPECT_EQ(costed.cost(1, 0), 0);  // within the radius: not this step's
  EXPECT_EQ(costed.cost(2, 0), 0);
  EXPECT_EQ(costed.cost(3, 0), 152);  // 252 * e^-0.5, above its own 40
  EXPECT_EQ(costed.cost(6, 0), kUnknownCost);
  EXPECT_EQ(costed.cost(9, 0), 7);   // 252 * e^-3.5
  EXPECT_EQ(costed.cost(10, 0), 0);  // beyond the inflation radius
  Grid free_unknown = grid;
  ASSERT_TRUE(ApplyInflationCost(2.0, 9.0, 0.5, true, &free_unknown).ok());
  EXPECT_EQ(free_unknown.cost(6, 0), 34);  // 252 * e^-2
}

// Bad parameters are refused, naming the value.
TEST(InflationCost, RefusesBadParameters) {
  Grid grid = Grid::Create(4, 4).value();
  auto message = [&](const GridShape& shape) {
    const absl::StatusOr<Grid> shaped = ShapeGrid(grid, shape);
    EXPECT_EQ(shaped.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(CheckGridShape(shape).code(), absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(AdvanceShapedGrid(grid, grid, {}, shape).status().code(),
              absl::StatusCode::kInvalidArgument);
    return std::string(shaped.status().message());
  };
  EXPECT_THAT(message(GridShape::Of(0, -1.0, 0.5, 0, false)),
              HasSubstr("inflation radius"));
  EXPECT_THAT(message(GridShape::Of(0, std::nan(""), 0.5, 0, false)),
              HasSubstr("inflation radius"));
  EXPECT_THAT(message(GridShape::Of(0, INFINITY, 0.5, 0, false)),
              HasSubstr("inflation radius"));
  EXPECT_THAT(message(GridShape::Of(3.0, 2.0, 0.5, 0, false)),
              HasSubstr("smaller than the robot radius"));
  EXPECT_THAT(message(GridShape::Of(1.0, 2.0, 0.0, 0, false)), HasSubstr("cost scaling"));
  EXPECT_THAT(message(GridShape::Of(1.0, 2.0, -0.5, 0, false)),
              HasSubstr("cost scaling"));
  EXPECT_THAT(message(GridShape::Of(1.0, 2.0, std::nan(""), 0, false)),
              HasSubstr("cost scaling"));
  EXPECT_THAT(message(GridShape::Of(-1.0, 2.0, 0.5, 0, false)),
              HasSubstr("robot radius"));
  EXPECT_EQ(ApplyInflationCost(1.0, 0.5, 0.5, false, &grid).code(),
            absl::StatusCode::kInvalidArgument);
  // Equal radii are fine (no costs beyond the inscribed cells).
  EXPECT_TRUE(ShapeGrid(grid, GridShape::Of(2.0, 2.0, 0.5, 0, false)).ok());
}

// The shape's identity: fields that do not apply are cleared.
TEST(GridShape, OfClearsWhatDoesNotApply) {
  EXPECT_FALSE(GridShape::Of(0, 0, 0.5, 0, true).shaped());
  EXPECT_EQ(GridShape::Of(1.0, 0, 0.5, 0, true), GridShape::Of(1.0, 0, 0.9, 0, false));
  EXPECT_TRUE(GridShape::Of(0, 3.0, 0.5, 0, false).shaped());
  EXPECT_NE(GridShape::Of(0, 3.0, 0.5, 0, true), GridShape::Of(0, 3.0, 0.5, 0, false));
  EXPECT_NE(GridShape::Of(0, 3.0, 0.5, 0, false), GridShape::Of(0, 3.0, 0.6, 0, false));
  // The cost-only inscribed radius: only with inflation costs, only above
  // the robot radius, at most the inflation radius.
  EXPECT_EQ(GridShape::Of(0, 0, 0.5, 2.0, false, 1.5).cost_inscribed_cells, 0.0);
  EXPECT_EQ(GridShape::Of(2.0, 5.0, 0.5, 0, false, 1.5).cost_inscribed_cells, 0.0);
  EXPECT_EQ(GridShape::Of(0, 5.0, 0.5, 0, false, 1.5).cost_inscribed_cells, 1.5);
  EXPECT_EQ(GridShape::Of(0, 5.0, 0.5, 0, false, 7.0).cost_inscribed_cells, 5.0);
  EXPECT_NE(GridShape::Of(0, 5.0, 0.5, 0, false, 1.5), GridShape::Of(0, 5.0, 0.5, 0, false));
}

// Nav2's numbers for a footprint: costs decay from its inscribed radius and
// nothing is blocked (a kinematic planner checks the footprint itself).
TEST(GridShape, CostOnlyInscribedRadiusDecaysAsNav2AndBlocksNothing) {
  Grid grid = Grid::Create(41, 41).value();
  grid.set_cost(20, 20, kLethalCost);
  // 5 cm cells: inflation 0.55 m, 10 per metre, a footprint 0.2 m inscribed.
  const Grid shaped = ShapeGrid(grid, GridShape::Of(0.0, 11.0, 0.5, 0.0, false, 4.0)).value();
  EXPECT_EQ(shaped.cost(20, 20), kLethalCost);
  EXPECT_EQ(shaped.cost(21, 20), 252);  // inside the inscribed radius: not blocked
  EXPECT_EQ(shaped.cost(24, 20), 252);
  EXPECT_EQ(shaped.cost(25, 20), InflationCost(5.0, 4.0, 0.5));  // 152, Nav2's
  EXPECT_EQ(shaped.cost(31, 20), InflationCost(11.0, 4.0, 0.5));
  EXPECT_EQ(shaped.cost(32, 20), kFreeCost);
  for (const uint8_t c : shaped.cells()) EXPECT_NE(c, kInscribedCost);
}

// A random change of an update: a single cell or a rectangle, to a random
// cost (lethal, free and everything else, so cells are blocked and freed).
void RandomUpdate(std::mt19937& rng, Grid* grid, std::vector<Cell>* changed) {
  std::uniform_int_distribution<int> count(1, 30);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<uint8_t> before = grid->cells();
  const int n = count(rng);
  int written = 0;
  while (written < n) {
    std::uniform_int_distribution<int> px(0, grid->width() - 1),
        py(0, grid->height() - 1);
    const Cell at{px(rng), py(rng)};
    const uint8_t cost = u(rng) < 0.4 ? kFreeCost : RandomCost(rng, 0.7);
    if (u(rng) < 0.25) {
      // A rectangle of up to 5 x 6 cells.
      std::uniform_int_distribution<int> side(1, 6);
      const int32_t x1 = std::min(at.x + side(rng) - 1, grid->width() - 1);
      const int32_t y1 = std::min(at.y + side(rng) - 1, grid->height() - 1);
      for (int32_t y = at.y; y <= y1; ++y) {
        for (int32_t x = at.x; x <= x1; ++x) grid->set_cost(x, y, cost);
      }
      written += (x1 - at.x + 1) * (y1 - at.y + 1);
    } else {
      grid->set_cost(at, cost);
      ++written;
    }
  }
  // As the map store records them: the cells whose cost differs, row-major.
  changed->clear();
  for (size_t i = 0; i < before.size(); ++i) {
    if (before[i] != grid->cells()[i]) changed->push_back(grid->CellAt(i));
  }
}

// Random maps and shapes (robot radius, inflation costs, clearance, unknown
// as free), 24 updates of 1-30 cells each: after every update the advanced
// grid equals ShapeGrid of the new map byte for byte.
TEST(AdvanceShapedGrid, EqualsShapingAfreshAfterRandomUpdates) {
  std::mt19937 rng(41);
  std::uniform_int_distribution<int> size(40, 140);
  int advanced = 0;
  int steps = 0;
  for (int trial = 0; trial < 40; ++trial) {
    Grid stored = RandomGrid(rng, size(rng), size(rng), trial % 2 == 0 ? 0.02 : 0.12);
    const GridShape shape = RandomShape(rng);
    Grid shaped = ShapeGrid(stored, shape).value();
    std::vector<Cell> changed;
    for (int update = 0; update < 24; ++update) {
      RandomUpdate(rng, &stored, &changed);
      absl::StatusOr<ShapedGridAdvance> next =
          AdvanceShapedGrid(shaped, stored, changed, shape);
      ASSERT_TRUE(next.ok()) << next.status();
      const Grid fresh = ShapeGrid(stored, shape).value();
      ASSERT_EQ(next->grid.cells(), fresh.cells())
          << "trial " << trial << " update " << update << " r "
          << shape.robot_radius_cells << " R " << shape.inflation_radius_cells << " s "
          << shape.cost_scaling_per_cell << " m " << shape.min_clearance_cells
          << " unknown_is_free " << shape.unknown_is_free << " " << stored.width() << "x"
          << stored.height() << " changed " << changed.size();
      advanced += next->advanced;
      ++steps;
      if (next->advanced) {
        EXPECT_LT(next->window_cells, static_cast<int64_t>(stored.size()));
      }
      shaped = std::move(next->grid);
    }
  }
  // Most steps took the windowed path being tested, not the fallback.
  EXPECT_GT(advanced, steps * 3 / 4) << advanced << " of " << steps;
}

// The farthest reaches of one new lethal cell, for each step: the robot
// radius's inscribed cells, the inflation costs' radius, and the clearance
// measured from the inscribed cells (radius + clearance away), on integer
// radii where the cells at exactly that distance count.
TEST(AdvanceShapedGrid, ReachesAsFarAsEachStepDoes) {
  const GridShape shapes[] = {
      GridShape::Of(3.0, 0.0, 0.0, 0.0, false), GridShape::Of(0.0, 6.0, 0.1, 0.0, false),
      GridShape::Of(2.0, 7.0, 0.1, 0.0, false), GridShape::Of(3.0, 0.0, 0.0, 4.0, false),
      GridShape::Of(0.0, 0.0, 0.0, 5.0, false), GridShape::Of(3.0, 5.0, 0.1, 4.0, true)};
  for (const GridShape& shape : shapes) {
    Grid stored = Grid::Create(81, 81).value();
    const Grid shaped = ShapeGrid(stored, shape).value();
    for (const uint8_t cost : {kLethalCost, kFreeCost}) {
      Grid changed = stored;
      changed.set_cost(40, 40, kLethalCost);
      const Grid before = ShapeGrid(changed, shape).value();
      // Blocking, then freeing it again.
      const Grid& from = cost == kLethalCost ? shaped : before;
      Grid to = cost == kLethalCost ? changed : stored;
      absl::StatusOr<ShapedGridAdvance> next =
          AdvanceShapedGrid(from, to, {Cell{40, 40}}, shape);
      ASSERT_TRUE(next.ok());
      EXPECT_TRUE(next->advanced);
      EXPECT_EQ(next->grid.cells(), ShapeGrid(to, shape)->cells())
          << "r " << shape.robot_radius_cells << " R " << shape.inflation_radius_cells
          << " m " << shape.min_clearance_cells << " cost " << int{cost};
    }
  }
}

// No changes: the previous grid as it was. Changes off the map, or another
// map's size: shaped in full, still right.
TEST(AdvanceShapedGrid, FallsBackWhereWindowsCannotHelp) {
  std::mt19937 rng(8);
  const GridShape shape = GridShape::Of(1.5, 5.0, 0.7, 2.0, false);
  const Grid stored = RandomGrid(rng, 60, 50, 0.05);
  const Grid shaped = ShapeGrid(stored, shape).value();
  absl::StatusOr<ShapedGridAdvance> same = AdvanceShapedGrid(shaped, stored, {}, shape);
  ASSERT_TRUE(same.ok());
  EXPECT_TRUE(same->advanced);
  EXPECT_EQ(same->window_cells, 0);
  EXPECT_EQ(same->grid.cells(), shaped.cells());

  absl::StatusOr<ShapedGridAdvance> off =
      AdvanceShapedGrid(shaped, stored, {Cell{60, 0}}, shape);
  ASSERT_TRUE(off.ok());
  EXPECT_FALSE(off->advanced);
  EXPECT_EQ(off->grid.cells(), shaped.cells());

  const Grid other = RandomGrid(rng, 30, 20, 0.05);
  absl::StatusOr<ShapedGridAdvance> resized = AdvanceShapedGrid(shaped, other, {}, shape);
  ASSERT_TRUE(resized.ok());
  EXPECT_FALSE(resized->advanced);
  EXPECT_EQ(resized->grid.cells(), ShapeGrid(other, shape)->cells());

  // Every cell changed: more than half the map would be shaped again.
  Grid cleared = Grid::Create(60, 50).value();
  std::vector<Cell> all;
  for (size_t i = 0; i < cleared.size(); ++i) all.push_back(cleared.CellAt(i));
  absl::StatusOr<ShapedGridAdvance> everything =
      AdvanceShapedGrid(shaped, cleared, all, shape);
  ASSERT_TRUE(everything.ok());
  EXPECT_FALSE(everything->advanced);
  EXPECT_EQ(everything->grid.cells(), ShapeGrid(cleared, shape)->cells());
}

}  // namespace
}  // namespace pathd
