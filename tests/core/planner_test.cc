// One suite runs every registered planner through the same cases; optimal
// planners are checked against Dijkstra, and Dijkstra itself against an
// independent Bellman-Ford relaxation on small random grids.
#include <atomic>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "absl/time/clock.h"
#include "core/cost_model.h"
#include "core/grid.h"
#include "core/planner.h"
#include "gtest/gtest.h"

namespace pathd {
namespace {

Grid MakeGrid(const std::vector<std::string>& rows) {
  // '.' free, '#' lethal, '?' unknown, digits d -> cost d * 28 (weighted).
  const int32_t h = static_cast<int32_t>(rows.size());
  const int32_t w = static_cast<int32_t>(rows[0].size());
  Grid grid = Grid::Create(w, h).value();
  for (int32_t y = 0; y < h; ++y) {
    for (int32_t x = 0; x < w; ++x) {
      const char c = rows[y][x];
      uint8_t v = kFreeCost;
      if (c == '#') v = kLethalCost;
      if (c == '?') v = kUnknownCost;
      if (c >= '1' && c <= '9') v = static_cast<uint8_t>((c - '0') * 28);
      grid.set_cost(x, y, v);
    }
  }
  return grid;
}

// Minimum cost from start to every cell by repeated relaxation of every legal
// move until nothing changes: slow, obviously correct, shares no code with the
// planners' search loops (only the cost model's CellFactor).
std::vector<double> BellmanFord(const Grid& grid, Cell start, const CostParams& p) {
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> dist(grid.size(), inf);
  dist[grid.Index(start)] = 0.0;
  auto ok = [&](int x, int y) {
    return grid.InBounds(x, y) && Traversable(grid.cost(x, y), p.unknown_is_free);
  };
  for (bool changed = true; changed;) {
    changed = false;
    for (int y = 0; y < grid.height(); ++y) {
      for (int x = 0; x < grid.width(); ++x) {
        const double d = dist[grid.Index(x, y)];
        if (d == inf) continue;
        for (int m = 0; m < MoveCount(p.connectivity); ++m) {
          const int nx = x + kMoves[m].dx, ny = y + kMoves[m].dy;
          if (!ok(nx, ny)) continue;
          if (kMoves[m].dx != 0 && kMoves[m].dy != 0 &&
              (!ok(x + kMoves[m].dx, y) || !ok(x, y + kMoves[m].dy))) {
            continue;
          }
          const double nd =
              d + kMoves[m].length * CellFactor(grid.cost(nx, ny), p.cost_weight);
          if (nd < dist[grid.Index(nx, ny)] - 1e-12) {
            dist[grid.Index(nx, ny)] = nd;
            changed = true;
          }
        }
      }
    }
  }
  return dist;
}

// Fewest moves from start to every cell (unit cost per legal move).
std::vector<int> MoveCounts(const Grid& grid, Cell start, const CostParams& p) {
  std::vector<int> moves(grid.size(), -1);
  std::vector<Cell> frontier{start};
  moves[grid.Index(start)] = 0;
  auto ok = [&](int x, int y) {
    return grid.InBounds(x, y) && Traversable(grid.cost(x, y), p.unknown_is_free);
  };
  for (int depth = 1; !frontier.empty(); ++depth) {
    std::vector<Cell> next;
    for (Cell c : frontier) {
      for (int m = 0; m < MoveCount(p.connectivity); ++m) {
        const int nx = c.x + kMoves[m].dx, ny = c.y + kMoves[m].dy;
        if (!ok(nx, ny) || moves[grid.Index(nx, ny)] >= 0) continue;
        if (kMoves[m].dx != 0 && kMoves[m].dy != 0 &&
            (!ok(c.x + kMoves[m].dx, c.y) || !ok(c.x, c.y + kMoves[m].dy))) {
          continue;
        }
        moves[grid.Index(nx, ny)] = depth;
        next.push_back({nx, ny});
      }
    }
    frontier = std::move(next);
  }
  return moves;
}

class EveryPlanner : public ::testing::TestWithParam<std::string> {
 protected:
  const Planner& planner() const {
    const Planner* p = PlannerRegistry::Default().Get(GetParam());
    EXPECT_NE(p, nullptr);
    return *p;
  }
  absl::StatusOr<PlanResult> Plan(const Grid& grid, Cell s, Cell g,
                                  CostParams params = {},
                                  StopCondition stop = StopCondition::None()) {
    return planner().Plan(grid, PlanRequest::Between(s, g, params), stop, scratch_);
  }
  SearchScratch scratch_;
};

TEST_P(EveryPlanner, StartEqualsGoal) {
  Grid grid = MakeGrid({"...", "...", "..."});
  auto r = Plan(grid, {1, 1}, {1, 1});
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_TRUE(r->found());
  ASSERT_EQ(r->path.size(), 1u);
  EXPECT_EQ(r->path[0], (Cell{1, 1}));
  EXPECT_EQ(r->cost, 0.0);
  EXPECT_EQ(r->length, 0.0);
}

TEST_P(EveryPlanner, UnreachableGoalIsAnOutcomeNotAnError) {
  Grid grid = MakeGrid({"..#..", "..#..", "..#.."});
  auto r = Plan(grid, {0, 0}, {4, 2});
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->outcome, PlanOutcome::kNoPath);
  EXPECT_TRUE(r->path.empty());
}

TEST_P(EveryPlanner, DiagonalGapIsNotPassable) {
  // The only way through is a corner between two blocked cells.
  Grid grid = MakeGrid({".#", "#."});
  auto r = Plan(grid, {0, 0}, {1, 1});
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kNoPath);
}

TEST_P(EveryPlanner, BlockedOrOffMapEndpointsNameTheEndpoint) {
  Grid grid = MakeGrid({"..#", "...", "..."});
  auto r = Plan(grid, {2, 0}, {0, 0});
  EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("start"), std::string::npos) << r.status();
  r = Plan(grid, {0, 0}, {2, 0});
  EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("goal"), std::string::npos) << r.status();
  r = Plan(grid, {-1, 0}, {0, 0});
  EXPECT_NE(r.status().message().find("start"), std::string::npos) << r.status();
  EXPECT_NE(r.status().message().find("outside"), std::string::npos) << r.status();
  r = Plan(grid, {0, 0}, {0, 3});
  EXPECT_NE(r.status().message().find("goal"), std::string::npos) << r.status();
}

TEST_P(EveryPlanner, UnknownCellsFollowTheOption) {
  Grid grid = MakeGrid({".?.", "#?#", ".?."});
  CostParams params;
  auto r = Plan(grid, {0, 0}, {0, 2}, params);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kNoPath);
  params.unknown_is_free = true;
  r = Plan(grid, {0, 0}, {0, 2}, params);
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(r->found());
}

TEST_P(EveryPlanner, BadCostParametersAreInvalidArgument) {
  Grid grid = MakeGrid({"..", ".."});
  CostParams params;
  params.cost_weight = -1.0;
  EXPECT_EQ(Plan(grid, {0, 0}, {1, 1}, params).status().code(),
            absl::StatusCode::kInvalidArgument);
  params.cost_weight = std::nan("");
  EXPECT_EQ(Plan(grid, {0, 0}, {1, 1}, params).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST_P(EveryPlanner, ExpiredDeadlineStopsTheSearch) {
  Grid grid = Grid::Create(300, 300).value();
  StopCondition stop(absl::Now() - absl::Seconds(1), nullptr, 0);
  auto r = Plan(grid, {0, 0}, {299, 299}, {}, stop);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kTimeout);
  EXPECT_TRUE(r->path.empty());
}

TEST_P(EveryPlanner, CancelFlagStopsTheSearch) {
  Grid grid = Grid::Create(300, 300).value();
  std::atomic<bool> cancelled{true};
  auto r = Plan(grid, {0, 0}, {299, 299}, {},
                StopCondition(absl::InfiniteFuture(), &cancelled, 0));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kCancelled);
}

TEST_P(EveryPlanner, ExpansionBudgetRunsOut) {
  Grid grid = Grid::Create(100, 100).value();
  auto r = Plan(grid, {0, 0}, {99, 99}, {},
                StopCondition(absl::InfiniteFuture(), nullptr, 10));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kExpansionLimit);
  EXPECT_LE(r->expansions, 10);
}

TEST_P(EveryPlanner, FourAndEightConnectivity) {
  Grid grid = Grid::Create(10, 10).value();
  CostParams four;
  four.connectivity = Connectivity::kFour;
  auto r4 = Plan(grid, {0, 0}, {9, 9}, four);
  ASSERT_TRUE(r4.ok());
  ASSERT_TRUE(r4->found());
  EXPECT_EQ(r4->path.size(), 19u);  // 18 straight moves
  EXPECT_TRUE(MeasurePath(grid, r4->path, four).valid);
  auto r8 = Plan(grid, {0, 0}, {9, 9});
  ASSERT_TRUE(r8.ok());
  ASSERT_TRUE(r8->found());
  EXPECT_EQ(r8->path.size(), 10u);  // 9 diagonal moves
  EXPECT_NEAR(r8->length, 9 * kSqrt2, 1e-9);
}

TEST_P(EveryPlanner, SearchScratchIsReusedAcrossMapSizes) {
  Grid big = Grid::Create(50, 50).value();
  Grid small = MakeGrid({"...", ".#.", "..."});
  for (int i = 0; i < 3; ++i) {
    auto a = Plan(big, {0, 0}, {49, 0});
    ASSERT_TRUE(a.ok() && a->found());
    auto b = Plan(small, {0, 0}, {2, 2});
    ASSERT_TRUE(b.ok() && b->found());
    EXPECT_EQ(b->path.front(), (Cell{0, 0}));
    EXPECT_EQ(b->path.back(), (Cell{2, 2}));
  }
}

// Random weighted grids, 4- and 8-connected: every found path is a legal move
// sequence whose reported cost and length match a re-measurement; optimal
// planners match an independent Bellman-Ford; fewest-move planners match a
// reference BFS in moves.
TEST_P(EveryPlanner, RandomWeightedGridsAgreeWithReferences) {
  std::mt19937 rng(20261123);
  const PlannerTraits& traits = planner().traits();
  int found = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const int w = 2 + static_cast<int>(rng() % 14);
    const int h = 2 + static_cast<int>(rng() % 14);
    Grid grid = Grid::Create(w, h).value();
    const int obstacle_pct = static_cast<int>(rng() % 40);
    for (size_t i = 0; i < grid.size(); ++i) {
      const int roll = static_cast<int>(rng() % 100);
      uint8_t v = kFreeCost;
      if (roll < obstacle_pct) {
        v = (rng() % 5 == 0) ? kUnknownCost : kLethalCost;
      } else if (rng() % 3 == 0) {
        v = static_cast<uint8_t>(rng() % 253);
      }
      grid.mutable_cells()[i] = v;
    }
    CostParams params;
    params.connectivity = (trial % 2) ? Connectivity::kFour : Connectivity::kEight;
    params.cost_weight = (trial % 5 == 0) ? 0.0 : static_cast<double>(rng() % 400) / 100.0;
    params.unknown_is_free = trial % 7 == 0;
    const Cell s{static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h)};
    const Cell g{static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h)};
    auto r = Plan(grid, s, g, params);
    const bool endpoints_ok = Traversable(grid.cost(s), params.unknown_is_free) &&
                              Traversable(grid.cost(g), params.unknown_is_free);
    if (!endpoints_ok) {
      EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
      continue;
    }
    ASSERT_TRUE(r.ok()) << r.status();
    const std::vector<double> dist = BellmanFord(grid, s, params);
    const bool reachable = std::isfinite(dist[grid.Index(g)]);
    ASSERT_EQ(r->found(), reachable) << "trial " << trial;
    if (!reachable) continue;
    ++found;
    ASSERT_EQ(r->path.front(), s);
    ASSERT_EQ(r->path.back(), g);
    const PathMeasure m = MeasurePath(grid, r->path, params);
    ASSERT_TRUE(m.valid) << "trial " << trial << " step " << m.first_invalid;
    EXPECT_NEAR(r->cost, m.cost, 1e-9 * (1 + m.cost));
    EXPECT_NEAR(r->length, m.length, 1e-9 * (1 + m.length));
    if (traits.optimal) {
      EXPECT_NEAR(r->cost, dist[grid.Index(g)], 1e-9 * (1 + r->cost))
          << "trial " << trial;
    }
    if (traits.fewest_moves) {
      const std::vector<int> moves = MoveCounts(grid, s, params);
      EXPECT_EQ(static_cast<int>(r->path.size()) - 1, moves[grid.Index(g)])
          << "trial " << trial;
    }
  }
  EXPECT_GT(found, 200);
}

INSTANTIATE_TEST_SUITE_P(Registry, EveryPlanner,
                         ::testing::ValuesIn(PlannerRegistry::Default().Names()),
                         [](const auto& info) { return info.param; });

TEST(PlannerRegistry, CreatesByNameAndListsNames) {
  const PlannerRegistry& registry = PlannerRegistry::Default();
  auto names = registry.Names();
  EXPECT_NE(std::find(names.begin(), names.end(), "astar"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "dijkstra"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "bfs"), names.end());
  auto p = registry.Create("astar");
  ASSERT_TRUE(p.ok());
  EXPECT_EQ((*p)->name(), "astar");
  auto unknown = registry.Create("nope");
  EXPECT_EQ(unknown.status().code(), absl::StatusCode::kNotFound);
  EXPECT_NE(unknown.status().message().find("dijkstra"), std::string::npos);
}

TEST(AStar, WeightedCellsAreAvoidedWhenCheaper) {
  // A band of costly cells: with weight 3 crossing it costs 7 + 4 = 11, going
  // around 4 + 4 * sqrt(2) = 9.66.
  Grid grid = MakeGrid({".........", "....9....", "....9....", "....9....",
                        "........."});
  SearchScratch scratch;
  const Planner* astar = PlannerRegistry::Default().Get("astar");
  CostParams heavy;
  heavy.cost_weight = 3.0;
  auto r = astar->Plan(grid, PlanRequest::Between({0, 2}, {8, 2}, heavy), StopCondition::None(),
                       scratch);
  ASSERT_TRUE(r.ok() && r->found());
  for (Cell c : r->path) EXPECT_NE(grid.cost(c), 9 * 28) << CellToString(c);
  EXPECT_NEAR(r->cost, 4 + 4 * kSqrt2, 1e-9);
  // Ignoring costs, straight through is shortest.
  CostParams flat;
  flat.cost_weight = 0.0;
  r = astar->Plan(grid, PlanRequest::Between({0, 2}, {8, 2}, flat), StopCondition::None(),
                  scratch);
  ASSERT_TRUE(r.ok() && r->found());
  EXPECT_DOUBLE_EQ(r->cost, 8.0);
}

TEST(AStar, ExpandsNoMoreThanDijkstra) {
  Grid grid = Grid::Create(64, 64).value();
  SearchScratch scratch;
  const PlanRequest req = PlanRequest::Between({3, 5}, {60, 50});
  auto a = PlannerRegistry::Default().Get("astar")->Plan(grid, req,
                                                          StopCondition::None(), scratch);
  auto d = PlannerRegistry::Default().Get("dijkstra")->Plan(
      grid, req, StopCondition::None(), scratch);
  ASSERT_TRUE(a.ok() && d.ok());
  EXPECT_DOUBLE_EQ(a->cost, d->cost);
  EXPECT_LT(a->expansions, d->expansions / 4);
}

TEST(Grid, WorldCellRoundTripWithRotation) {
  Grid grid = Grid::Create(20, 10).value();
  grid.set_resolution(0.05);
  grid.set_origin({-1.0, 2.0, 0.3});
  for (Cell c : {Cell{0, 0}, Cell{19, 9}, Cell{7, 3}}) {
    auto back = grid.WorldToCell(grid.CellCenter(c));
    ASSERT_TRUE(back.ok());
    EXPECT_EQ(*back, c);
  }
  EXPECT_EQ(grid.WorldToCell({100, 100}).status().code(), absl::StatusCode::kOutOfRange);
  EXPECT_EQ(grid.WorldToCell({std::nan(""), 0}).status().code(),
            absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace pathd
