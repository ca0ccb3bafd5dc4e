// The dynamic brushfire field of core/geometry/voronoi.h: a fresh build
// against brute force (every obstacle tried for every cell, the diagram rule
// evaluated from those answers), and random update sequences against a fresh
// build of the same map, cell by cell.
#include "core/geometry/voronoi.h"

#include <atomic>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "core/geometry/structure.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/stop_condition.h"
#include "absl/time/clock.h"
#include "gtest/gtest.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

std::string At(Cell c) {
  return "(" + std::to_string(c.x) + ", " + std::to_string(c.y) + ")";
}

bool BlockedOrOutside(const Grid& grid, int x, int y, bool unknown_is_free) {
  return !grid.InBounds(x, y) || !Traversable(grid.cost(x, y), unknown_is_free);
}

// For every cell: the nearest obstacle (cells of the grid that are blocked
// and the ring around it) by octile distance, ties to the first in row-major
// order from (-1, -1).
std::vector<Cell> BruteNearest(const Grid& grid, bool unknown_is_free) {
  std::vector<Cell> obstacles;
  for (int y = -1; y <= grid.height(); ++y) {
    for (int x = -1; x <= grid.width(); ++x) {
      if (BlockedOrOutside(grid, x, y, unknown_is_free))
        obstacles.push_back({x, y});
    }
  }
  std::vector<Cell> nearest(grid.size());
  for (int y = 0; y < grid.height(); ++y) {
    for (int x = 0; x < grid.width(); ++x) {
      Cell best = obstacles[0];
      for (const Cell& o : obstacles) {
        if (Compare(OctileLength::Between(x - o.x, y - o.y),
                    OctileLength::Between(x - best.x, y - best.y)) < 0) {
          best = o;
        }
      }
      nearest[grid.Index(x, y)] = best;
    }
  }
  return nearest;
}

OctileLength Oct(Cell a, Cell b) {
  return OctileLength::Between(a.x - b.x, a.y - b.y);
}

// The diagram rule, from brute-force nearest obstacles.
bool BruteOnDiagram(const Grid& grid, const std::vector<Cell>& nearest, Cell c,
                    bool unknown_is_free) {
  if (BlockedOrOutside(grid, c.x, c.y, unknown_is_free)) return false;
  const Cell s = nearest[grid.Index(c)];
  for (const Cell n : {Cell{c.x + 1, c.y}, Cell{c.x - 1, c.y},
                       Cell{c.x, c.y + 1}, Cell{c.x, c.y - 1}}) {
    if (BlockedOrOutside(grid, n.x, n.y, unknown_is_free)) continue;
    const Cell t = nearest[grid.Index(n)];
    if (std::abs(s.x - t.x) <= 1 && std::abs(s.y - t.y) <= 1) continue;
    // d(c,t) - d(c,s) <= d(n,s) - d(n,t), in doubles with a margin far
    // below the smallest nonzero difference of such sums.
    const double lhs = Oct(c, t).value() - Oct(c, s).value();
    const double rhs = Oct(n, s).value() - Oct(n, t).value();
    if (lhs <= rhs + 1e-9) return true;
  }
  return false;
}

Grid RandomGrid(std::mt19937& rng, int w, int h, int obstacle_pct) {
  Grid grid = Grid::Create(w, h).value();
  for (uint8_t& v : grid.mutable_cells()) {
    const int roll = static_cast<int>(rng() % 100);
    v = roll < obstacle_pct ? (rng() % 4 == 0 ? kUnknownCost : kLethalCost)
                            : kFreeCost;
  }
  return grid;
}

void ExpectSameField(const VoronoiField& a, const VoronoiField& b,
                     const std::string& where) {
  for (int32_t y = 0; y < a.height(); ++y) {
    for (int32_t x = 0; x < a.width(); ++x) {
      const Cell c{x, y};
      ASSERT_EQ(a.Blocked(c), b.Blocked(c)) << where << " " << At(c);
      ASSERT_EQ(a.NearestObstacle(c), b.NearestObstacle(c))
          << where << " " << At(c);
      ASSERT_EQ(a.OnDiagram(c), b.OnDiagram(c)) << where << " " << At(c);
    }
  }
}

TEST(OctileLength, ComparesExactly) {
  EXPECT_EQ(Compare(OctileLength::Between(3, 4), OctileLength::Between(4, 3)),
            0);
  // 1 + 3 sqrt2 = 5.243 vs 5 + 0: longer.
  EXPECT_EQ(Compare(OctileLength::Between(3, 4), OctileLength::Between(5, 0)),
            1);
  // 7 sqrt2 = 9.8995 vs 10: shorter; 12 sqrt2 = 16.97 vs 17.
  EXPECT_EQ(Compare(OctileLength::Between(7, 7), OctileLength::Between(10, 0)),
            -1);
  EXPECT_EQ(
      Compare(OctileLength::Between(12, 12), OctileLength::Between(17, 0)), -1);
  // 70 sqrt2 = 98.995: between 98 and 99.
  EXPECT_EQ(Compare(OctileLength{0, 70}, OctileLength{99, 0}), -1);
  EXPECT_EQ(Compare(OctileLength{0, 70}, OctileLength{98, 0}), 1);
  EXPECT_DOUBLE_EQ(OctileLength::Between(-2, 5).value(), 3 + 2 * kSqrt2);
}

TEST(VoronoiField, CorridorCentreIsTheDiagram) {
  // A corridor three cells high between two walls: its middle row is the
  // diagram, at clearance 2 from each wall.
  const Grid grid = MakeGrid(
      {"##########", "..........", "..........", "..........", "##########"});
  const VoronoiField field(grid, false);
  for (int x = 2; x < 8; ++x) {
    EXPECT_TRUE(field.OnDiagram({x, 2})) << x;
    EXPECT_FALSE(field.OnDiagram({x, 1})) << x;
    EXPECT_DOUBLE_EQ(field.Clearance({x, 2}), 2.0);
  }
  EXPECT_DOUBLE_EQ(field.Clearance({0, 2}), 1.0);  // the map's edge is a wall
  EXPECT_EQ(field.NearestObstacle({0, 2}), (Cell{-1, 2}));
  EXPECT_EQ(field.Clearance({3, 0}), 0.0);
}

TEST(VoronoiField, DescribesItsDiagramAsPoints) {
  const Grid grid = MakeGrid(
      {"##########", "..........", "..........", "..........", "##########"});
  const auto s = DescribeStructure("voronoi", grid, false);
  ASSERT_TRUE(s.ok()) << s.status();
  const VoronoiField field(grid, false);
  ASSERT_EQ(s->counts.size(), 1u);
  EXPECT_EQ(s->counts[0].second, field.DiagramCells());
  EXPECT_EQ(static_cast<int64_t>(s->points.size()), field.DiagramCells());
  EXPECT_EQ(s->bytes, field.bytes());
}

TEST(VoronoiField, FreshBuildMatchesBruteForce) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 1500; ++trial) {
    const int w = 1 + static_cast<int>(rng() % 14);
    const int h = 1 + static_cast<int>(rng() % 14);
    const Grid grid = RandomGrid(rng, w, h, static_cast<int>(rng() % 50));
    const bool unknown_is_free = trial % 3 == 0;
    const VoronoiField field(grid, unknown_is_free);
    const std::vector<Cell> nearest = BruteNearest(grid, unknown_is_free);
    int64_t diagram = 0;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const Cell c{x, y};
        ASSERT_EQ(field.Blocked(c),
                  BlockedOrOutside(grid, x, y, unknown_is_free));
        ASSERT_EQ(field.NearestObstacle(c), nearest[grid.Index(c)])
            << "trial " << trial << " " << At(c);
        EXPECT_EQ(Compare(field.Distance(c), Oct(c, nearest[grid.Index(c)])),
                  0);
        const bool on = BruteOnDiagram(grid, nearest, c, unknown_is_free);
        ASSERT_EQ(field.OnDiagram(c), on) << "trial " << trial << " " << At(c);
        diagram += on ? 1 : 0;
      }
    }
    EXPECT_EQ(field.DiagramCells(), diagram);
  }
}

// Random batches of changes (single cells, rectangles, unknown cells flipping
// with the option, cells listed that did not change, the same cell twice)
// applied by Update must leave exactly the field a fresh build gives.
TEST(VoronoiField, UpdatesEqualAFreshBuild) {
  std::mt19937 rng(2013);
  int updates = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int w = 1 + static_cast<int>(rng() % 24);
    const int h = 1 + static_cast<int>(rng() % 24);
    Grid grid = RandomGrid(rng, w, h, static_cast<int>(rng() % 45));
    const bool unknown_is_free = trial % 4 == 0;
    VoronoiField field(grid, unknown_is_free);
    for (int step = 0; step < 12; ++step) {
      std::vector<Cell> changed;
      const int kind = static_cast<int>(rng() % 3);
      const int count = kind == 0 ? 1 : 1 + static_cast<int>(rng() % 8);
      for (int k = 0; k < count; ++k) {
        const Cell c{static_cast<int32_t>(rng() % w),
                     static_cast<int32_t>(rng() % h)};
        if (kind == 2) {
          // A rectangle set to one value.
          const int rw = 1 + static_cast<int>(rng() % 4);
          const int rh = 1 + static_cast<int>(rng() % 4);
          const uint8_t v = rng() % 2 ? kLethalCost : kFreeCost;
          for (int y = c.y; y < std::min(h, c.y + rh); ++y) {
            for (int x = c.x; x < std::min(w, c.x + rw); ++x) {
              grid.set_cost(x, y, v);
              changed.push_back({x, y});
            }
          }
          break;
        }
        const int roll = static_cast<int>(rng() % 10);
        grid.set_cost(c, roll < 4   ? kLethalCost
                         : roll < 5 ? kUnknownCost
                                    : kFreeCost);
        changed.push_back(c);
        if (rng() % 5 == 0) changed.push_back(c);
      }
      if (rng() % 6 == 0) changed.push_back({0, 0});  // listed, maybe unchanged
      field.Update(grid, changed);
      ++updates;
      ExpectSameField(
          field, VoronoiField(grid, unknown_is_free),
          "trial " + std::to_string(trial) + " step " + std::to_string(step));
      if (HasFatalFailure()) return;
    }
  }
  EXPECT_EQ(updates, 400 * 12);
}

TEST(VoronoiField, OpeningAWallLetsTheFarSideIn) {
  // Removing a whole wall: every cell that was nearest to it must move on.
  Grid grid = MakeGrid(
      {"........", "........", "########", "........", "........", "........"});
  VoronoiField field(grid, false);
  std::vector<Cell> changed;
  for (int x = 0; x < 8; ++x) {
    grid.set_cost(x, 2, kFreeCost);
    changed.push_back({x, 2});
  }
  field.Update(grid, changed);
  EXPECT_DOUBLE_EQ(field.Clearance({3, 2}), 3.0);  // the top edge, 3 rows up
  ExpectSameField(field, VoronoiField(grid, false), "opened");
}

TEST(VoronoiField, ABuildUnderAStopThatFiredReturnsNothing) {
  std::mt19937 rng(17);
  const Grid grid = RandomGrid(rng, 300, 300, 20);
  const StopCondition expired(absl::Now() - absl::Seconds(1), nullptr, 0);
  DerivedStop stop(expired);
  EXPECT_EQ(VoronoiField::Build(grid, false, stop), nullptr);
  EXPECT_EQ(stop.stopped_while(),
            "building the Voronoi field of this map version (300 x 300 cells)");
  std::atomic<bool> cancelled{true};
  const StopCondition cancel(absl::InfiniteFuture(), &cancelled, 0);
  DerivedStop cancelled_stop(cancel);
  EXPECT_EQ(VoronoiField::Build(grid, false, cancelled_stop), nullptr);
  EXPECT_EQ(cancelled_stop.Outcome(), PlanOutcome::kCancelled);
  // Not stopped, it is the field the constructor builds.
  DerivedStop never;
  const auto built = VoronoiField::Build(grid, false, never);
  ASSERT_NE(built, nullptr);
  ExpectSameField(*built, VoronoiField(grid, false), "under a stop");
}

}  // namespace
}  // namespace pathd
