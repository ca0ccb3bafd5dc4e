// JPS+ (jps_plus) and its jump tables: tables advanced through random update
// sequences equal a fresh build entry for entry; plans equal Dijkstra's cost
// and jps's path and expansions on random maps, on maps edited between
// queries through a derived store, and on Moving AI scenarios sampled across
// every shared map file; the refusals are jps's. PATHD_JPS_PLUS_CASES scales
// the randomised counts (default 20; the ASan run lowers it).
#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_replace.h"
#include "absl/time/clock.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/map_io/map_io.h"
#include "core/planners/jps/jump_table.h"
#include "core/search/path_measure.h"
#include "core/search/planner.h"
#include "core/search/registry.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/testing/advancing_store.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

namespace fs = std::filesystem;
using internal::JumpTable;

int Cases() {
  if (const char* env = std::getenv("PATHD_JPS_PLUS_CASES")) {
    return std::max(1, std::atoi(env));
  }
  return 20;
}

const Planner& Get(const char* name) { return *PlannerRegistry::Default().Get(name); }

// Every entry of every direction and every passability bit.
void ExpectSameTable(const JumpTable& a, const JumpTable& b, const std::string& where) {
  ASSERT_EQ(a.width(), b.width());
  ASSERT_EQ(a.height(), b.height());
  for (int32_t y = 0; y < a.height(); ++y) {
    for (int32_t x = 0; x < a.width(); ++x) {
      ASSERT_EQ(a.Free(x, y), b.Free(x, y)) << where << " at " << x << "," << y;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (dx == 0 && dy == 0) continue;
          ASSERT_EQ(a.Entry(x, y, dx, dy), b.Entry(x, y, dx, dy))
              << where << " at " << x << "," << y << " direction " << dx << "," << dy;
        }
      }
    }
  }
}

// The jump distances written out from their definition by stepping cell by
// cell (a reference apart from the table's recurrences).
int32_t ReferenceEntry(const Grid& grid, bool unknown_is_free, int32_t x, int32_t y,
                       int dx, int dy) {
  auto free = [&](int32_t cx, int32_t cy) {
    return grid.InBounds(Cell{cx, cy}) && Traversable(grid.cost(cx, cy), unknown_is_free);
  };
  auto straight_jump = [&](int32_t cx, int32_t cy, int sx, int sy) {
    // (cx, cy) entered from (cx - sx, cy - sy) has a forced neighbour.
    const int px = sy;
    const int py = sx;
    for (int side = -1; side <= 1; side += 2) {
      if (free(cx + side * px, cy + side * py) &&
          !free(cx - sx + side * px, cy - sy + side * py)) {
        return true;
      }
    }
    return false;
  };
  auto straight = [&](int32_t cx, int32_t cy, int sx, int sy) {
    for (int32_t k = 1;; ++k) {
      const int32_t nx = cx + k * sx;
      const int32_t ny = cy + k * sy;
      if (!free(nx, ny)) return -(k - 1);
      if (straight_jump(nx, ny, sx, sy)) return k;
    }
  };
  if (dx == 0 || dy == 0) return straight(x, y, dx, dy);
  for (int32_t k = 1;; ++k) {
    const int32_t px = x + (k - 1) * dx;
    const int32_t py = y + (k - 1) * dy;
    if (!free(px + dx, py) || !free(px, py + dy) || !free(px + dx, py + dy)) {
      return -(k - 1);
    }
    if (straight(px + dx, py + dy, dx, 0) > 0 || straight(px + dx, py + dy, 0, dy) > 0) {
      return k;
    }
  }
}

Grid RandomGrid(std::mt19937& rng, int32_t w, int32_t h, int obstacle_pct) {
  Grid grid = Grid::Create(w, h).value();
  for (uint8_t& v : grid.mutable_cells()) {
    v = static_cast<int>(rng() % 100) < obstacle_pct
            ? (rng() % 4 == 0 ? kUnknownCost : kLethalCost)
            : kFreeCost;
  }
  return grid;
}

TEST(JumpTable, BuildMatchesTheDefinition) {
  std::mt19937 rng(19);
  for (int trial = 0; trial < 40; ++trial) {
    const int32_t w = 1 + static_cast<int32_t>(rng() % 40);
    const int32_t h = 1 + static_cast<int32_t>(rng() % 40);
    const Grid grid = RandomGrid(rng, w, h, static_cast<int>(rng() % 50));
    const bool unknown_is_free = trial % 3 == 0;
    const auto table = JumpTable::Build(grid, unknown_is_free);
    for (int32_t y = 0; y < h; ++y) {
      for (int32_t x = 0; x < w; ++x) {
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            if (dx == 0 && dy == 0) continue;
            ASSERT_EQ(table->Entry(x, y, dx, dy),
                      ReferenceEntry(grid, unknown_is_free, x, y, dx, dy))
                << "trial " << trial << " at " << x << "," << y << " direction " << dx
                << "," << dy;
          }
        }
      }
    }
  }
}

// Random cell flips, filled and cleared blocks, clear-then-set of the same
// cells, and unchanged cells listed as changed: each advanced table equals
// a fresh build of the same grid.
TEST(JumpTable, AdvancedTableEqualsFreshBuild) {
  std::mt19937 rng(2014);
  const int maps = std::max(2, Cases() / 2);
  for (int map = 0; map < maps; ++map) {
    // Sides across the 16-cell tiles and the 64-cell words of the rows.
    const int32_t w = 20 + static_cast<int32_t>(rng() % 130);
    const int32_t h = 20 + static_cast<int32_t>(rng() % 130);
    Grid grid = RandomGrid(rng, w, h, static_cast<int>(rng() % 40));
    const bool unknown_is_free = map % 3 == 0;
    std::shared_ptr<const JumpTable> table = JumpTable::Build(grid, unknown_is_free);
    for (int step = 0; step < 25; ++step) {
      std::vector<Cell> changed;
      auto set = [&](int32_t x, int32_t y, uint8_t cost) {
        if (x < 0 || y < 0 || x >= w || y >= h) return;
        grid.set_cost(x, y, cost);
        changed.push_back(Cell{x, y});
      };
      const uint32_t kind = rng() % 4;
      if (kind == 0) {
        const int n = 1 + static_cast<int>(rng() % 30);
        for (int i = 0; i < n; ++i) {
          const Cell c{static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h)};
          const bool free = Traversable(grid.cost(c), unknown_is_free);
          set(c.x, c.y, free ? (rng() % 3 == 0 ? kUnknownCost : kLethalCost) : kFreeCost);
        }
      } else if (kind == 1 || kind == 2) {
        // A block filled (1) or cleared (2).
        const int32_t bx = static_cast<int32_t>(rng() % w);
        const int32_t by = static_cast<int32_t>(rng() % h);
        const int32_t bw = 1 + static_cast<int32_t>(rng() % 12);
        const int32_t bh = 1 + static_cast<int32_t>(rng() % 12);
        for (int32_t y = by; y < by + bh; ++y) {
          for (int32_t x = bx; x < bx + bw; ++x) set(x, y, kind == 1 ? kLethalCost : kFreeCost);
        }
      } else {
        // Clear then set back: listed, but most end as they were.
        const int n = 1 + static_cast<int>(rng() % 20);
        std::vector<std::pair<Cell, uint8_t>> old;
        for (int i = 0; i < n; ++i) {
          const Cell c{static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h)};
          old.push_back({c, grid.cost(c)});
          set(c.x, c.y, kFreeCost);
        }
        for (size_t i = 0; i < old.size(); i += 2) set(old[i].first.x, old[i].first.y, old[i].second);
      }
      table = JumpTable::Advance(*table, grid, changed);
      const auto fresh = JumpTable::Build(grid, unknown_is_free);
      ExpectSameTable(*table, *fresh, absl::StrCat("map ", map, " step ", step));
      if (HasFatalFailure()) return;
    }
  }
}

class JpsPlusTest : public ::testing::Test {
 protected:
  // jps_plus against Dijkstra (cost, found) and jps (the same path and
  // expansions: the same search over the same jump points), with a legal
  // path whose measure is the reported cost.
  void ExpectAsJps(const Grid& grid, const PlanRequest& request, const std::string& where) {
    auto p = Get("jps_plus").Plan(grid, request, StopCondition::None(), scratch_);
    PlanRequest plain_request = request;
    plain_request.derived = nullptr;
    auto j = Get("jps").Plan(grid, plain_request, StopCondition::None(), scratch_);
    ASSERT_EQ(p.status().code(), j.status().code()) << where << ": " << p.status();
    if (!j.ok()) {
      EXPECT_EQ(p.status().message(),
                absl::StrReplaceAll(std::string(j.status().message()), {{"planner jps ", "planner jps_plus "}}))
          << where;
      return;
    }
    auto d = Get("dijkstra").Plan(grid, plain_request, StopCondition::None(), scratch_);
    ASSERT_TRUE(d.ok()) << d.status();
    ASSERT_EQ(p->found(), d->found()) << where;
    if (!d->found()) return;
    ASSERT_NEAR(p->cost, d->cost, 1e-9 * (1 + d->cost)) << where;
    ASSERT_EQ(p->path, j->path) << where;
    ASSERT_EQ(p->expansions, j->expansions) << where;
    const PathMeasure m = MeasurePath(grid, p->path, request.cost);
    ASSERT_TRUE(m.valid) << where;
    ASSERT_DOUBLE_EQ(m.cost, p->cost) << where;
  }

  SearchScratch scratch_;
};

TEST_F(JpsPlusTest, IsRegisteredWithJpsPreconditions) {
  const PlannerTraits& t = Get("jps_plus").traits();
  EXPECT_TRUE(t.optimal);
  EXPECT_TRUE(t.needs_uniform_cost);
  EXPECT_TRUE(t.needs_eight_connected);
}

TEST_F(JpsPlusTest, RandomGridsMatchDijkstraAndJps) {
  std::mt19937 rng(31);
  const int trials = 100 * Cases();
  for (int trial = 0; trial < trials; ++trial) {
    const int32_t w = 1 + static_cast<int32_t>(rng() % (trial % 2 ? 16 : 90));
    const int32_t h = 1 + static_cast<int32_t>(rng() % (trial % 2 ? 16 : 90));
    Grid grid = RandomGrid(rng, w, h, static_cast<int>(rng() % 45));
    CostParams params;
    params.unknown_is_free = trial % 5 == 0;
    params.cost_weight = trial % 4 == 0 ? 0.0 : 1.0;
    if (trial % 9 == 0) {
      for (uint8_t& v : grid.mutable_cells()) {
        if (v == kFreeCost) v = 100;
      }
      params.unknown_is_free = false;
    }
    std::vector<Cell> open;
    for (int32_t y = 0; y < h; ++y) {
      for (int32_t x = 0; x < w; ++x) {
        if (Traversable(grid.cost(x, y), params.unknown_is_free)) open.push_back({x, y});
      }
    }
    if (open.empty()) continue;
    // Half the goals on the start's row, column or diagonal: the goal checks
    // inside a jump.
    const Cell s = open[rng() % open.size()];
    Cell g = open[rng() % open.size()];
    if (trial % 2 == 0) {
      const int dir = static_cast<int>(rng() % 8);
      const int dx = dir < 3 ? -1 : dir < 5 ? 0 : 1;
      const int dy = dir % 3 == 0 ? -1 : dir % 3 == 1 ? 0 : 1;
      const int32_t k = 1 + static_cast<int32_t>(rng() % 20);
      const Cell c{s.x + k * (dx == 0 && dy == 0 ? 1 : dx), s.y + k * dy};
      if (grid.InBounds(c) && Traversable(grid.cost(c), params.unknown_is_free)) g = c;
    }
    ExpectAsJps(grid, PlanRequest::Between(s, g, params), absl::StrCat("trial ", trial));
    if (HasFatalFailure()) return;
  }
}

// Through a derived store, as the server plans: the table is advanced from
// the previous version's, and every answer is jps's and Dijkstra's.
TEST_F(JpsPlusTest, DerivedStoreAdvancedAcrossUpdatesMatchesDijkstra) {
  std::mt19937 rng(424243);
  const int maps = std::max(2, Cases() / 2);
  for (int map = 0; map < maps; ++map) {
    const int32_t w = 40 + static_cast<int32_t>(rng() % 100);
    const int32_t h = 40 + static_cast<int32_t>(rng() % 100);
    Grid grid = RandomGrid(rng, w, h, 25);
    CostParams params;
    params.unknown_is_free = map % 3 == 0;
    testing::AdvancingStore store(testing::AdvancingStore::Options{.pad_with_unchanged = map % 2 == 1});
    for (int step = 0; step < 30; ++step) {
      const int changes = 1 + static_cast<int>(rng() % 40);
      for (int i = 0; i < changes; ++i) {
        const uint32_t r = rng() % 100;
        // Cost 77 breaks uniformity; a later step may restore it.
        const uint8_t cost = r < 45 ? kLethalCost : r < 90 ? kFreeCost : r < 96 ? kUnknownCost : 77;
        grid.set_cost(static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h), cost);
      }
      store.SetGrid(grid);
      const Cell s{static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h)};
      const Cell g{static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h)};
      PlanRequest request = PlanRequest::Between(s, g, params);
      request.derived = &store;
      ExpectAsJps(grid, request, absl::StrCat("map ", map, " step ", step));
      if (HasFatalFailure()) return;
    }
    EXPECT_GT(store.stats().advances, 0);
  }
}

TEST_F(JpsPlusTest, RefusesWhatJpsRefuses) {
  Grid grid = MakeGrid({"....", ".#..", "...."});
  // A weighted map.
  grid.set_cost(2, 0, 50);
  ExpectAsJps(grid, PlanRequest::Between({0, 0}, {3, 2}), "weighted");
  auto weighted = Get("jps_plus").Plan(grid, PlanRequest::Between({0, 0}, {3, 2}),
                                        StopCondition::None(), scratch_);
  EXPECT_EQ(weighted.status().code(), absl::StatusCode::kFailedPrecondition);
  // Four-connected moves.
  grid.set_cost(2, 0, kFreeCost);
  CostParams four;
  four.connectivity = Connectivity::kFour;
  auto r = Get("jps_plus").Plan(grid, PlanRequest::Between({0, 0}, {3, 2}, four),
                                StopCondition::None(), scratch_);
  EXPECT_FALSE(r.ok());
  ExpectAsJps(grid, PlanRequest::Between({0, 0}, {3, 2}, four), "four-connected");
  // A blocked goal, an off-map start.
  ExpectAsJps(grid, PlanRequest::Between({0, 0}, {1, 1}), "blocked goal");
  ExpectAsJps(grid, PlanRequest::Between({-1, 0}, {3, 2}), "off-map start");
}

// The table's 32 bytes a cell bound the map; jps (a bit a cell) still plans.
TEST_F(JpsPlusTest, RefusesMapsPastTheTableBound) {
  const int32_t w = 4097;
  const int32_t h = static_cast<int32_t>(internal::kJumpTableMaxCells / 4096);
  absl::StatusOr<Grid> made = Grid::Create(w, h, kFreeCost);
  ASSERT_TRUE(made.ok()) << made.status();
  const Grid& grid = *made;
  ASSERT_GT(static_cast<int64_t>(grid.size()), internal::kJumpTableMaxCells);
  const PlanRequest request = PlanRequest::Between({0, 0}, {w - 1, h - 1});
  auto r = Get("jps_plus").Plan(grid, request, StopCondition::None(), scratch_);
  ASSERT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition) << r.status();
  EXPECT_THAT(std::string(r.status().message()),
              ::testing::HasSubstr("jps_plus supports maps of up to 8388608 cells"));
  EXPECT_THAT(std::string(r.status().message()), ::testing::HasSubstr("4097 x 2048"));
  auto j = Get("jps").Plan(grid, request, StopCondition::None(), scratch_);
  ASSERT_TRUE(j.ok()) << j.status();
  EXPECT_TRUE(j->found());
}

TEST_F(JpsPlusTest, StartEqualsGoalUnreachableAndBorders) {
  const Grid grid = MakeGrid({
      "..........",
      ".########.",
      ".#......#.",
      ".#......#.",
      ".########.",
      "..........",
  });
  auto same = Get("jps_plus").Plan(grid, PlanRequest::Between({3, 2}, {3, 2}),
                                   StopCondition::None(), scratch_);
  ASSERT_TRUE(same.ok());
  ASSERT_TRUE(same->found());
  EXPECT_EQ(same->path, (std::vector<Cell>{Cell{3, 2}}));
  EXPECT_EQ(same->cost, 0.0);
  auto walled = Get("jps_plus").Plan(grid, PlanRequest::Between({0, 0}, {3, 2}),
                                     StopCondition::None(), scratch_);
  ASSERT_TRUE(walled.ok());
  EXPECT_FALSE(walled->found());
  // Goals on straight runs and diagonals along every border, from corners.
  const Cell corners[] = {{0, 0}, {9, 0}, {0, 5}, {9, 5}};
  for (const Cell& s : corners) {
    for (const Cell& g : corners) {
      ExpectAsJps(grid, PlanRequest::Between(s, g), absl::StrCat(s.x, ",", s.y, " to ", g.x, ",", g.y));
    }
    for (int32_t x = 0; x < 10; ++x) {
      ExpectAsJps(grid, PlanRequest::Between(s, {x, 0}), "top row");
      ExpectAsJps(grid, PlanRequest::Between(s, {x, 5}), "bottom row");
    }
  }
  // The goal on an open diagonal and on a straight run before a wall.
  const Grid open = MakeGrid({"......", "......", "......", "......", ".....#"});
  ExpectAsJps(open, PlanRequest::Between({0, 0}, {3, 3}), "diagonal");
  ExpectAsJps(open, PlanRequest::Between({0, 4}, {3, 4}), "straight before wall");
  ExpectAsJps(open, PlanRequest::Between({0, 0}, {5, 2}), "past the diagonal");
}

// Without a store the table lives in the scratch and follows a grid edited
// in place; an edit that a refused query saw first (the map turned
// weighted) must still reach the table used by the next query.
TEST_F(JpsPlusTest, TableFollowsAGridEditedAfterARefusedQuery) {
  Grid grid = MakeGrid({
      "..........",
      "..........",
      "..........",
      "..........",
  });
  ExpectAsJps(grid, PlanRequest::Between({0, 0}, {9, 3}), "before");
  // A wall with a gap, and one weighted cell: refused with cost_weight 1.
  for (int32_t y = 0; y < 3; ++y) grid.set_cost(5, y, kLethalCost);
  grid.set_cost(0, 3, 90);
  auto refused = Get("jps_plus").Plan(grid, PlanRequest::Between({1, 0}, {9, 0}),
                                      StopCondition::None(), scratch_);
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kFailedPrecondition);
  CostParams ignore_costs;
  ignore_costs.cost_weight = 0.0;
  ExpectAsJps(grid, PlanRequest::Between({1, 0}, {9, 0}, ignore_costs), "after the edit");
}

// A past deadline or a cancelled query stops the table build (with and
// without a store) and then the search; nothing half-built is kept.
TEST_F(JpsPlusTest, DeadlineAndCancellationStopTheBuildAndTheSearch) {
  const Grid grid = Grid::Create(300, 300).value();
  testing::AdvancingStore store;
  store.SetGrid(grid);
  for (const bool with_store : {false, true}) {
    PlanRequest request = PlanRequest::Between({0, 0}, {299, 299});
    if (with_store) request.derived = &store;
    auto r = Get("jps_plus").Plan(grid, request,
                                  StopCondition(absl::Now() - absl::Seconds(1), nullptr, 0),
                                  scratch_);
    ASSERT_TRUE(r.ok()) << r.status();
    EXPECT_EQ(r->outcome, PlanOutcome::kTimeout);
    EXPECT_TRUE(r->path.empty());
    std::atomic<bool> cancelled{true};
    r = Get("jps_plus").Plan(grid, request, StopCondition(absl::InfiniteFuture(), &cancelled, 0),
                             scratch_);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->outcome, PlanOutcome::kCancelled);
    ExpectAsJps(grid, request, with_store ? "store, after the stops" : "after the stops");
  }
}

// Moving AI scenarios sampled across every shared map file (the files are
// sorted by length, so a stride over the whole file): the stored optimal
// length, and jps's answer.
TEST_F(JpsPlusTest, MovingAiScenariosSampledAcrossEveryMap) {
  fs::path root = "../shared/benchmarks/movingai";
  if (const char* env = std::getenv("PATHD_MOVINGAI_DIR")) root = env;
  std::error_code ec;
  if (!fs::is_directory(root, ec)) {
    GTEST_SKIP() << "Moving AI benchmarks not found at " << root;
  }
  int maps = 0;
  for (const auto& entry : fs::recursive_directory_iterator(root, ec)) {
    const fs::path& p = entry.path();
    if (p.extension() != ".map" || !fs::exists(p.string() + ".scen")) continue;
    auto grid = ReadMovingAiMapFile(p.string());
    ASSERT_TRUE(grid.ok()) << grid.status();
    auto file = ReadMovingAiScenarioFileWithVersion(p.string() + ".scen");
    ASSERT_TRUE(file.ok()) << file.status();
    const size_t count = file->scenarios.size();
    const size_t samples = static_cast<size_t>(Cases());
    for (size_t k = 0; k < samples && count > 0; ++k) {
      const Scenario& s = file->scenarios[k * (count - 1) / std::max<size_t>(1, samples - 1)];
      const std::string where = absl::StrCat(p.filename().string(), " line ", s.line);
      auto r = Get("jps_plus").Plan(*grid, PlanRequest::Between(s.start, s.goal),
                                    StopCondition::None(), scratch_);
      ASSERT_TRUE(r.ok()) << where << ": " << r.status();
      ASSERT_TRUE(r->found()) << where;
      EXPECT_NEAR(r->cost, s.optimal_length, ScenarioTolerance(s, file->version)) << where;
      auto j = Get("jps").Plan(*grid, PlanRequest::Between(s.start, s.goal),
                               StopCondition::None(), scratch_);
      ASSERT_TRUE(j.ok());
      EXPECT_EQ(r->path, j->path) << where;
    }
    ++maps;
  }
  std::printf("jps_plus: %d scenarios on each of %d Moving AI maps\n", Cases(), maps);
}

}  // namespace
}  // namespace pathd
