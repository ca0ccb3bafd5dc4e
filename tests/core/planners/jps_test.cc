// Jump Point Search: hand-made maps whose optimal cost is worked out by hand
// and checked in all eight orientations (so every scan direction and forced-
// neighbour rule runs), its preconditions and stop outcomes, a map edited in
// place between queries, and random grids against Dijkstra. Also the bit
// packing it reads the map through.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "core/search/registry.h"
#include "core/search/path_measure.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/planner.h"
#include "core/planners/jps/bit_grid.h"
#include "gtest/gtest.h"
#include "tests/testing/advancing_store.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

// One of the eight symmetries of the square: bit 0 mirrors x, bit 1 mirrors
// y, bit 2 swaps the axes (applied last).
struct Orientation {
  int code;
  int32_t w;
  int32_t h;
  Cell Map(Cell c) const {
    if (code & 1) c.x = w - 1 - c.x;
    if (code & 2) c.y = h - 1 - c.y;
    if (code & 4) std::swap(c.x, c.y);
    return c;
  }
};

Grid Orient(const Grid& grid, const Orientation& o) {
  const bool swap = (o.code & 4) != 0;
  Grid out = Grid::Create(swap ? grid.height() : grid.width(),
                          swap ? grid.width() : grid.height())
                 .value();
  for (int32_t y = 0; y < grid.height(); ++y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      out.set_cost(o.Map({x, y}), grid.cost(x, y));
    }
  }
  return out;
}

class JpsTest : public ::testing::Test {
 protected:
  const Planner& jps() const { return *PlannerRegistry::Default().Get("jps"); }
  const Planner& dijkstra() const {
    return *PlannerRegistry::Default().Get("dijkstra");
  }

  absl::StatusOr<PlanResult> Plan(const Grid& grid, Cell s, Cell g,
                                  CostParams params = {},
                                  StopCondition stop = StopCondition::None()) {
    return jps().Plan(grid, PlanRequest::Between(s, g, params), stop, scratch_);
  }

  // Plans s -> g on `rows` in all eight orientations and expects `cost` each
  // time, a legal path between the endpoints whose measure matches the
  // reported cost and length, and Dijkstra's cost.
  void ExpectCostInEveryOrientation(const std::vector<std::string>& rows,
                                    Cell s, Cell g, double cost) {
    const Grid base = MakeGrid(rows);
    for (int code = 0; code < 8; ++code) {
      SCOPED_TRACE("orientation " + std::to_string(code));
      const Orientation o{code, base.width(), base.height()};
      const Grid grid = Orient(base, o);
      auto r = Plan(grid, o.Map(s), o.Map(g));
      ASSERT_TRUE(r.ok()) << r.status();
      ASSERT_TRUE(r->found());
      EXPECT_NEAR(r->cost, cost, 1e-9);
      ASSERT_EQ(r->path.front(), o.Map(s));
      ASSERT_EQ(r->path.back(), o.Map(g));
      const PathMeasure m = MeasurePath(grid, r->path, {});
      ASSERT_TRUE(m.valid) << "step " << m.first_invalid;
      EXPECT_DOUBLE_EQ(m.cost, r->cost);
      EXPECT_DOUBLE_EQ(m.length, r->length);
      auto d = dijkstra().Plan(grid, PlanRequest::Between(o.Map(s), o.Map(g)),
                               StopCondition::None(), scratch_);
      ASSERT_TRUE(d.ok() && d->found());
      EXPECT_NEAR(d->cost, cost, 1e-9);
    }
  }

  SearchScratch scratch_;
};

TEST_F(JpsTest, IsRegisteredWithItsPreconditions) {
  const PlannerTraits& traits = jps().traits();
  EXPECT_EQ(jps().name(), "jps");
  EXPECT_TRUE(traits.optimal);
  EXPECT_TRUE(traits.complete);
  EXPECT_TRUE(traits.needs_uniform_cost);
  EXPECT_TRUE(traits.needs_eight_connected);
  EXPECT_FALSE(traits.any_angle);
}

TEST_F(JpsTest, StartEqualsGoalIsOneCell) {
  Grid grid = MakeGrid({"...", "...", "..."});
  auto r = Plan(grid, {1, 1}, {1, 1});
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_TRUE(r->found());
  EXPECT_EQ(r->path, (std::vector<Cell>{{1, 1}}));
  EXPECT_EQ(r->cost, 0.0);
  EXPECT_EQ(r->length, 0.0);
  EXPECT_EQ(r->expansions, 1);
}

TEST_F(JpsTest, UnreachableGoalIsNoPath) {
  Grid grid = MakeGrid({
      "....#...",
      "....#...",
      "....#.#.",
      "....#..#",
  });
  auto r = Plan(grid, {0, 0}, {6, 3});
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->outcome, PlanOutcome::kNoPath);
  EXPECT_TRUE(r->path.empty());
  EXPECT_GE(r->expansions, 1);
}

TEST_F(JpsTest, OpenDiagonalIsTwoExpansions) {
  // The start's diagonal scan reaches the goal: expansions count jump points
  // taken from the open list (start and goal), not cells passed.
  Grid grid = Grid::Create(10, 10).value();
  auto r = Plan(grid, {0, 0}, {9, 9});
  ASSERT_TRUE(r.ok() && r->found());
  EXPECT_EQ(r->path.size(), 10u);
  EXPECT_NEAR(r->cost, 9 * kSqrt2, 1e-12);
  EXPECT_EQ(r->expansions, 2);
}

TEST_F(JpsTest, DiagonalBlockedByOneSideCell) {
  ExpectCostInEveryOrientation({"S#", ".G"}, {0, 0}, {1, 1}, 2.0);
  ExpectCostInEveryOrientation({"..", ".."}, {0, 0}, {1, 1}, kSqrt2);
  // Two blocked corners: no way through at all.
  Grid grid = MakeGrid({".#", "#."});
  auto r = Plan(grid, {0, 0}, {1, 1});
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kNoPath);
}

TEST_F(JpsTest, ForcedNeighbourPastTheEndOfAWall) {
  // Moving east under the wall, the first cell whose north side opens is a
  // jump point; the path turns diagonally there: 5 + 2 sqrt 2 + 3.
  ExpectCostInEveryOrientation(
      {
          "..........G",
          "#####......",
          "S..........",
      },
      {0, 2}, {10, 0}, 8 + 2 * kSqrt2);
}

TEST_F(JpsTest, ForcedNeighbourOnBothSides) {
  // Walls end on both sides of the row at once; the goals above and below
  // need the turn at x = 4 either way.
  const std::vector<std::string> rows = {
      ".........", "####.....", "S........", "####.....", ".........",
  };
  ExpectCostInEveryOrientation(rows, {0, 2}, {8, 0}, 6 + 2 * kSqrt2);
  ExpectCostInEveryOrientation(rows, {0, 2}, {8, 4}, 6 + 2 * kSqrt2);
  // Back along the far side of the wall: round its end, where both diagonals
  // would cut its corner, so 4 + 2 + 4 straight moves.
  ExpectCostInEveryOrientation(rows, {0, 2}, {0, 0}, 10.0);
}

TEST_F(JpsTest, GapInAWall) {
  // The only way through is the gap at (5, 3), entered and left straight
  // because the diagonals into it cut the wall's corners:
  // (0,0) -> (4,3): 1 + 3 sqrt 2; -> (6,3): 2; -> (9,5): 1 + 2 sqrt 2.
  ExpectCostInEveryOrientation(
      {
          ".....#....",
          ".....#....",
          ".....#....",
          "..........",
          ".....#....",
          ".....#....",
      },
      {0, 0}, {9, 5}, 4 + 5 * kSqrt2);
}

TEST_F(JpsTest, WindingCorridor) {
  // One cell wide with square corners, so no diagonal move is legal: 22
  // straight moves.
  ExpectCostInEveryOrientation(
      {
          ".#.....",
          ".#.###.",
          ".#.#.#.",
          ".#.#.#.",
          "...#...",
      },
      {0, 0}, {4, 2}, 22.0);
}

TEST_F(JpsTest, PillarsAndPockets) {
  // Scattered obstacles: many forced neighbours on the way, and goals in
  // pockets open on one side only. Too many turns to count by hand, so the
  // expected cost is Dijkstra's in the first orientation.
  const std::vector<std::string> rows = {
      "...........", "..#....#...", "......###..", ".#.........",
      ".....#.....", "...#...#.#.", ".........#.", "..#.....##.",
  };
  const Grid base = MakeGrid(rows);
  for (const auto& [s, g] : {std::pair<Cell, Cell>{{0, 0}, {8, 6}},
                             {{10, 7}, {0, 7}},
                             {{7, 3}, {8, 1}},
                             {{3, 4}, {10, 0}}}) {
    auto d = dijkstra().Plan(base, PlanRequest::Between(s, g),
                             StopCondition::None(), scratch_);
    ASSERT_TRUE(d.ok() && d->found());
    ExpectCostInEveryOrientation(rows, s, g, d->cost);
  }
}

TEST_F(JpsTest, GoalOnTheMapEdgeAndLongRows) {
  // Scans cross 64-cell word boundaries and stop at the map edge.
  Grid grid = Grid::Create(200, 3).value();
  for (int32_t x : {63, 64, 127, 128, 191}) grid.set_cost(x, 1, kLethalCost);
  auto r = Plan(grid, {0, 1}, {199, 1});
  ASSERT_TRUE(r.ok() && r->found());
  auto d = dijkstra().Plan(grid, PlanRequest::Between({0, 1}, {199, 1}),
                           StopCondition::None(), scratch_);
  ASSERT_TRUE(d.ok() && d->found());
  EXPECT_NEAR(r->cost, d->cost, 1e-9);
  EXPECT_TRUE(MeasurePath(grid, r->path, {}).valid);
}

TEST_F(JpsTest, RefusesWeightedMapsAndFourConnectivity) {
  Grid grid = MakeGrid({"....", ".3..", "...."});
  auto r = Plan(grid, {0, 0}, {3, 2});
  EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition);
  const std::string message(r.status().message());
  EXPECT_NE(message.find("jps"), std::string::npos) << message;
  EXPECT_NE(message.find("(1, 1)"), std::string::npos) << message;
  EXPECT_NE(message.find("cost_weight 0"), std::string::npos) << message;

  // With cell costs ignored the same map is uniform.
  CostParams ignore_costs;
  ignore_costs.cost_weight = 0.0;
  r = Plan(grid, {0, 0}, {3, 2}, ignore_costs);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_NEAR(r->cost, 1 + 2 * kSqrt2, 1e-12);

  CostParams four;
  four.connectivity = Connectivity::kFour;
  r = Plan(MakeGrid({"...", "..."}), {0, 0}, {2, 1}, four);
  EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_NE(r.status().message().find("8-connectivity"), std::string::npos)
      << r.status();

  // Endpoint errors come first, as for every planner.
  r = Plan(grid, {0, 0}, {9, 9});
  EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
}

TEST_F(JpsTest, UniformNonZeroCostScalesEveryStep) {
  // Every traversable cell costs 2 * 28: uniform, so allowed; each step costs
  // its length times 1 + 56 / 252. The pillar rules out both diagonals next to
  // it: 3 + sqrt 2 instead of the octile 1 + 2 sqrt 2.
  Grid grid = MakeGrid({"2222", "2#22", "2222"});
  auto r = Plan(grid, {0, 0}, {3, 2});
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_TRUE(r->found());
  const double factor = 1.0 + 56.0 / 252.0;
  EXPECT_NEAR(r->cost, (3 + kSqrt2) * factor, 1e-12);
  EXPECT_NEAR(r->length, 3 + kSqrt2, 1e-12);
  EXPECT_DOUBLE_EQ(MeasurePath(grid, r->path, {}).cost, r->cost);
}

TEST_F(JpsTest, UnknownCellsFollowTheOption) {
  Grid grid = MakeGrid({".?.", "#?#", ".?."});
  auto r = Plan(grid, {0, 0}, {0, 2});
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->outcome, PlanOutcome::kNoPath);
  CostParams params;
  params.unknown_is_free = true;  // unknown cells then cost as free ones
  r = Plan(grid, {0, 0}, {0, 2}, params);
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_TRUE(r->found());
  // Down the unknown column; the walls rule out the diagonals.
  EXPECT_NEAR(r->cost, 4.0, 1e-12);
  // Unknown-as-free next to a costed cell is not uniform.
  Grid mixed = MakeGrid({"1?.", "...", "..."});
  EXPECT_EQ(Plan(mixed, {1, 1}, {2, 2}, params).status().code(),
            absl::StatusCode::kFailedPrecondition);
}

TEST_F(JpsTest, ExpansionBudgetRunsOut) {
  Grid grid = MakeGrid({
      "S.........",
      "########..",
      "..........",
      "..########",
      ".........G",
  });
  auto r = Plan(grid, {0, 0}, {9, 4}, {},
                StopCondition(absl::InfiniteFuture(), nullptr, 2));
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->outcome, PlanOutcome::kExpansionLimit);
  EXPECT_LE(r->expansions, 2);
  EXPECT_TRUE(r->path.empty());
  r = Plan(grid, {0, 0}, {9, 4});
  ASSERT_TRUE(r.ok() && r->found());
  EXPECT_GT(r->expansions, 2);
}

TEST_F(JpsTest, DeadlineAndCancellationStopTheSearch) {
  Grid grid = Grid::Create(300, 300).value();
  auto r = Plan(grid, {0, 0}, {299, 299}, {},
                StopCondition(absl::Now() - absl::Seconds(1), nullptr, 0));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kTimeout);
  EXPECT_TRUE(r->path.empty());
  std::atomic<bool> cancelled{true};
  r = Plan(grid, {0, 0}, {299, 299}, {},
           StopCondition(absl::InfiniteFuture(), &cancelled, 0));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kCancelled);
}

// The packed copy of the map lives in the SearchScratch between queries; an
// edit to the same Grid object must be seen by the next query.
TEST_F(JpsTest, MapEditedInPlaceBetweenQueries) {
  Grid grid = Grid::Create(150, 100).value();
  for (int32_t y = 0; y < 100; ++y) {
    if (y != 70) grid.set_cost(100, y, kLethalCost);  // a wall with one gap
  }
  const Cell s{10, 10};
  const Cell g{140, 10};
  auto open = Plan(grid, s, g);
  ASSERT_TRUE(open.ok() && open->found());

  grid.set_cost(100, 70, kLethalCost);
  auto closed = Plan(grid, s, g);
  ASSERT_TRUE(closed.ok()) << closed.status();
  EXPECT_EQ(closed->outcome, PlanOutcome::kNoPath);

  grid.set_cost(100, 70, kFreeCost);
  grid.set_cost(100, 10, kFreeCost);  // a shorter way
  auto shortcut = Plan(grid, s, g);
  ASSERT_TRUE(shortcut.ok() && shortcut->found());
  EXPECT_NEAR(shortcut->cost, 130.0, 1e-9);

  grid.set_cost(5, 5, 100);  // no longer uniform
  EXPECT_EQ(Plan(grid, s, g).status().code(),
            absl::StatusCode::kFailedPrecondition);
}

TEST_F(JpsTest, ScratchSharedWithOtherPlannersAndMapSizes) {
  const Planner& astar = *PlannerRegistry::Default().Get("astar");
  Grid big = Grid::Create(70, 65).value();
  for (int32_t y = 0; y < 60; ++y) big.set_cost(35, y, kLethalCost);
  Grid small = MakeGrid({"...", ".#.", "..."});
  for (int i = 0; i < 3; ++i) {
    for (const Grid* grid : {&big, &small}) {
      const Cell g{grid->width() - 1, 0};
      auto a = astar.Plan(*grid, PlanRequest::Between({0, 0}, g),
                          StopCondition::None(), scratch_);
      auto j = Plan(*grid, {0, 0}, g);
      ASSERT_TRUE(a.ok() && a->found() && j.ok() && j->found());
      EXPECT_NEAR(j->cost, a->cost, 1e-9);
      EXPECT_TRUE(MeasurePath(*grid, j->path, {}).valid);
    }
  }
}

// Random uniform-cost grids against Dijkstra: the same answer (path or not),
// the same cost, and a legal path whose measure is the reported cost.
void CheckRandomGrids(int trials, int max_side, uint32_t seed,
                      SearchScratch& scratch) {
  const Planner& jps = *PlannerRegistry::Default().Get("jps");
  const Planner& dijkstra = *PlannerRegistry::Default().Get("dijkstra");
  std::mt19937 rng(seed);
  int found = 0;
  for (int trial = 0; trial < trials; ++trial) {
    const int w = 1 + static_cast<int>(rng() % max_side);
    const int h = 1 + static_cast<int>(rng() % max_side);
    Grid grid = Grid::Create(w, h).value();
    const int obstacle_pct = static_cast<int>(rng() % 50);
    // A uniform cost other than free on some maps, unknown cells on others.
    const uint8_t traversable = trial % 9 == 0 ? 100 : kFreeCost;
    CostParams params;
    params.unknown_is_free = trial % 5 == 0 && traversable == kFreeCost;
    params.cost_weight = trial % 4 == 0 ? 0.0 : 1.0;
    for (uint8_t& v : grid.mutable_cells()) {
      v = traversable;
      if (static_cast<int>(rng() % 100) < obstacle_pct) {
        v = rng() % 4 == 0 ? kUnknownCost : kLethalCost;
      }
    }
    std::vector<Cell> open;
    for (int32_t y = 0; y < h; ++y) {
      for (int32_t x = 0; x < w; ++x) {
        if (Traversable(grid.cost(x, y), params.unknown_is_free))
          open.push_back({x, y});
      }
    }
    if (open.empty()) continue;
    const Cell s = open[rng() % open.size()];
    const Cell g = open[rng() % open.size()];
    const PlanRequest request = PlanRequest::Between(s, g, params);
    auto j = jps.Plan(grid, request, StopCondition::None(), scratch);
    auto d = dijkstra.Plan(grid, request, StopCondition::None(), scratch);
    ASSERT_TRUE(j.ok()) << "trial " << trial << ": " << j.status();
    ASSERT_TRUE(d.ok()) << d.status();
    ASSERT_EQ(j->found(), d->found()) << "trial " << trial;
    if (!d->found()) continue;
    ++found;
    ASSERT_NEAR(j->cost, d->cost, 1e-9 * (1 + d->cost)) << "trial " << trial;
    ASSERT_EQ(j->path.front(), s);
    ASSERT_EQ(j->path.back(), g);
    const PathMeasure m = MeasurePath(grid, j->path, params);
    ASSERT_TRUE(m.valid) << "trial " << trial << " step " << m.first_invalid;
    ASSERT_DOUBLE_EQ(m.cost, j->cost) << "trial " << trial;
    ASSERT_DOUBLE_EQ(m.length, j->length) << "trial " << trial;
  }
  EXPECT_GT(found, trials / 2);
}

TEST_F(JpsTest, RandomSmallGridsMatchDijkstra) {
  CheckRandomGrids(5000, 16, 20240611, scratch_);
}

TEST_F(JpsTest, RandomGridsAcrossWordBoundariesMatchDijkstra) {
  CheckRandomGrids(300, 140, 77, scratch_);
}

// Through a derived store, as the server plans: the version's packed map is
// advanced from the previous version's after random updates (words and
// tiles across 64-cell boundaries, costs breaking and restoring uniformity)
// and every answer equals Dijkstra's and JPS's without a store; a map that
// stopped being uniform is refused exactly as without one, and one that is
// uniform again is planned on (the version's cost set is then a stale
// superset, settled by the full check).
TEST_F(JpsTest, DerivedStoreAdvancedAcrossUpdatesMatchesDijkstra) {
  const Planner& jps = *PlannerRegistry::Default().Get("jps");
  const Planner& dijkstra = *PlannerRegistry::Default().Get("dijkstra");
  std::mt19937 rng(424242);
  for (int map = 0; map < 12; ++map) {
    const int w = 60 + static_cast<int>(rng() % 90);
    const int h = 60 + static_cast<int>(rng() % 90);
    Grid grid = Grid::Create(w, h).value();
    for (uint8_t& v : grid.mutable_cells()) v = rng() % 100 < 25 ? kLethalCost : kFreeCost;
    CostParams params;
    params.unknown_is_free = map % 3 == 0;
    testing::AdvancingStore store;
    for (int step = 0; step < 30; ++step) {
      const int changes = 1 + static_cast<int>(rng() % 40);
      for (int i = 0; i < changes; ++i) {
        const uint32_t r = rng() % 100;
        const uint8_t cost = r < 45 ? kLethalCost : r < 90 ? kFreeCost
                             : r < 96 ? kUnknownCost : 77;
        grid.set_cost(static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h), cost);
      }
      store.SetGrid(grid);
      // Several queries a version, so more of the advanced bits are read.
      for (int q = 0; q < 4; ++q) {
        const Cell s{static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h)};
        const Cell g{static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h)};
        PlanRequest request = PlanRequest::Between(s, g, params);
        auto plain = jps.Plan(grid, request, StopCondition::None(), scratch_);
        request.derived = &store;
        auto shared = jps.Plan(grid, request, StopCondition::None(), scratch_);
        const std::string where = absl::StrCat("map ", map, " step ", step, " query ", q);
        ASSERT_EQ(shared.status().code(), plain.status().code())
            << where << ": " << shared.status() << " vs " << plain.status();
        if (!plain.ok()) {
          EXPECT_EQ(shared.status().message(), plain.status().message()) << where;
          continue;
        }
        auto d = dijkstra.Plan(grid, PlanRequest::Between(s, g, params),
                               StopCondition::None(), scratch_);
        ASSERT_TRUE(d.ok()) << d.status();
        ASSERT_EQ(shared->found(), d->found()) << where;
        if (!d->found()) continue;
        ASSERT_NEAR(shared->cost, d->cost, 1e-9 * (1 + d->cost)) << where;
        ASSERT_EQ(shared->path, plain->path) << where;
      }
    }
    EXPECT_GT(store.stats().advances, 0);
  }
}

struct CountingExtension final : SearchScratch::Extension {
  int value = 0;
  size_t MemoryBytes() const override { return 100; }
};
struct OtherExtension final : SearchScratch::Extension {
  size_t MemoryBytes() const override { return 0; }
};

TEST(SearchScratchExtension, OneInstancePerTypeAndScratch) {
  SearchScratch a;
  SearchScratch b;
  const size_t before = a.MemoryBytes();
  a.extension<CountingExtension>().value = 5;
  a.extension<OtherExtension>();
  EXPECT_EQ(a.extension<CountingExtension>().value, 5);
  EXPECT_EQ(b.extension<CountingExtension>().value, 0);
  EXPECT_EQ(a.MemoryBytes(), before + 100);
}

TEST(BitGrid, TransposeSwapsRowsAndColumns) {
  std::mt19937_64 rng(5);
  uint64_t a[64];
  uint64_t original[64];
  for (int i = 0; i < 64; ++i) original[i] = a[i] = rng();
  internal::Transpose64(a);
  for (int r = 0; r < 64; ++r) {
    for (int c = 0; c < 64; ++c) {
      ASSERT_EQ((a[r] >> c) & 1, (original[c] >> r) & 1) << r << "," << c;
    }
  }
}

// Every instruction set the machine has packs exactly like the portable loop
// and flags the same uniform-cost violations.
TEST(BitGrid, PackingAgreesAcrossInstructionSets) {
  std::mt19937 rng(11);
  int compared = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const int w = 1 + static_cast<int>(rng() % 200);
    const int h = 1 + static_cast<int>(rng() % 40);
    Grid grid = Grid::Create(w, h).value();
    const uint8_t palette[] = {kFreeCost,           kFreeCost,      7,
                               kMaxTraversableCost, kInscribedCost, kLethalCost,
                               kUnknownCost};
    const int kinds = 2 + static_cast<int>(rng() % 6);
    for (uint8_t& v : grid.mutable_cells()) v = palette[rng() % kinds];
    internal::PackRule rule;
    rule.unknown_is_free = rng() % 2 == 0;
    rule.check_uniform = rng() % 4 != 0;
    rule.uniform_cost = rng() % 3 == 0 ? 7 : kFreeCost;
    const size_t tiles = static_cast<size_t>((w + 63) / 64) * ((h + 63) / 64);

    internal::BitLines expected;
    expected.Reset(h, w);
    std::vector<uint8_t> dirty(tiles, 0);
    const bool expected_uniform = internal::PackRows(
        internal::PackIsa::kScalar, grid, rule, expected, dirty);
    for (internal::PackIsa isa :
         {internal::PackIsa::kSse2, internal::PackIsa::kAvx512}) {
      if (!internal::PackIsaAvailable(isa)) continue;
      internal::BitLines rows;
      rows.Reset(h, w);
      std::vector<uint8_t> isa_dirty(tiles, 0);
      EXPECT_EQ(internal::PackRows(isa, grid, rule, rows, isa_dirty),
                expected_uniform);
      EXPECT_EQ(isa_dirty, dirty);
      for (int32_t y = -1; y <= h; ++y) {
        for (int32_t x = -1; x <= w; ++x) {
          ASSERT_EQ(internal::BitLines::Get(rows.Line(y), x),
                    internal::BitLines::Get(expected.Line(y), x))
              << "trial " << trial << " cell " << x << "," << y;
        }
      }
      // Packing the same grid again changes nothing.
      std::fill(isa_dirty.begin(), isa_dirty.end(), 0);
      internal::PackRows(isa, grid, rule, rows, isa_dirty);
      EXPECT_EQ(std::count(isa_dirty.begin(), isa_dirty.end(), 1), 0);
      ++compared;
    }
    for (int32_t y = 0; y < h; ++y) {
      for (int32_t x = 0; x < w; ++x) {
        ASSERT_EQ(internal::BitLines::Get(expected.Line(y), x),
                  Traversable(grid.cost(x, y), rule.unknown_is_free));
      }
    }
  }
  EXPECT_GT(compared, 0);
}

}  // namespace
}  // namespace pathd
