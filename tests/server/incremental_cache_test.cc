// IncrementalCache: hits and misses, repairs that follow map versions (by the
// request and queued by the store listener), eviction under a byte budget,
// concurrent readers during updates, and re-created maps. Every answer is
// checked against a fresh Dijkstra search on the version the answer names.
#include "server/incremental_cache.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <thread>
#include <vector>

#include "absl/synchronization/mutex.h"
#include "absl/synchronization/notification.h"
#include "core/search/registry.h"
#include "core/search/path_measure.h"
#include "core/map/inflation.h"
#include "core/search/planner.h"
#include "gtest/gtest.h"
#include "server/map_store.h"
#include "server/worker_pool.h"

namespace pathd::server {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// A seeded random weighted grid: about 20% lethal, the rest free or weighted.
Grid RandomGrid(int32_t width, int32_t height, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> pick(0, 99);
  Grid grid = Grid::Create(width, height).value();
  for (int32_t y = 0; y < height; ++y) {
    for (int32_t x = 0; x < width; ++x) {
      const int r = pick(rng);
      grid.set_cost(x, y, r < 20   ? kLethalCost
                          : r < 60 ? kFreeCost
                                   : static_cast<uint8_t>(2 * r));
    }
  }
  return grid;
}

// Random traversable cells of `grid`.
std::vector<Cell> FreeCells(const Grid& grid, int count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int32_t> x(0, grid.width() - 1);
  std::uniform_int_distribution<int32_t> y(0, grid.height() - 1);
  std::vector<Cell> cells;
  while (static_cast<int>(cells.size()) < count) {
    const Cell c{x(rng), y(rng)};
    if (Traversable(grid.cost(c), false)) cells.push_back(c);
  }
  return cells;
}

// The registry's Dijkstra: the reference every cached answer must equal.
double DijkstraCost(const Grid& grid, Cell start, Cell goal, const CostParams& cost) {
  SearchScratch scratch;
  const Planner* dijkstra = PlannerRegistry::Default().Get("dijkstra");
  absl::StatusOr<PlanResult> result =
      dijkstra->Plan(grid, PlanRequest::Between(start, goal, cost), StopCondition::None(),
                     scratch);
  EXPECT_TRUE(result.ok()) << result.status();
  if (!result.ok() || !result->found()) return kInf;
  return result->cost;
}

// The cost a cached answer reports for `start`, +infinity for "no path".
double SpmCost(const IncrementalCache::SpmAnswer& answer, Cell start) {
  absl::StatusOr<PlanResult> result = answer.field->PathFrom(start);
  EXPECT_TRUE(result.ok()) << result.status();
  if (!result.ok() || !result->found()) return kInf;
  // The path must be legal on the grid the field was computed on.
  const PathMeasure measure = MeasurePath(*answer.grid, result->path, CostParams());
  EXPECT_TRUE(measure.valid);
  EXPECT_NEAR(measure.cost, result->cost, 1e-9);
  return result->cost;
}

void ExpectSameCost(double actual, double expected, const std::string& what) {
  if (std::isinf(expected)) {
    EXPECT_TRUE(std::isinf(actual)) << what << ": " << actual;
  } else {
    EXPECT_NEAR(actual, expected, 1e-4 * std::max(1.0, expected)) << what;
  }
}

IncrementalCache::Key KeyFor(const std::string& map, Cell goal, double radius = 0.0) {
  IncrementalCache::Key key;
  key.map = map;
  key.goal = goal;
  key.robot_radius_cells = radius;
  return key;
}

bool Free(const Grid& grid, Cell c) { return Traversable(grid.cost(c), false); }

// Sets every cell of `cells` to `cost` in one update.
MapUpdateResult SetCells(MapStore& store, const std::string& map,
                         const std::vector<Cell>& cells, uint32_t cost) {
  std::vector<MapChange> changes;
  for (Cell c : cells) changes.push_back(MapChange::ForCell(c.x, c.y, cost));
  absl::StatusOr<MapUpdateResult> result = store.Update(map, changes, std::nullopt);
  EXPECT_TRUE(result.ok()) << result.status();
  return *std::move(result);
}

// Runs an empty job on a one-thread pool and waits for it: every job queued
// before it has run by then.
void DrainPool(WorkerPool& pool) {
  absl::Notification done;
  ASSERT_TRUE(pool.Submit(MakeJob([&done](SearchScratch&) { done.Notify(); })).ok());
  done.WaitForNotification();
}

class IncrementalCacheTest : public ::testing::Test {
 protected:
  IncrementalCacheTest() : store_(1 << 20), inflation_(4) {}

  std::shared_ptr<const MapSnapshot> Create(const std::string& name, Grid grid) {
    auto snapshot = store_.Create(name, std::move(grid), /*replace=*/false);
    EXPECT_TRUE(snapshot.ok()) << snapshot.status();
    return *snapshot;
  }
  std::shared_ptr<const MapSnapshot> Current(const std::string& name) {
    return store_.Get(name).value();
  }

  MapStore store_;
  InflationCache inflation_;
};

TEST_F(IncrementalCacheTest, SecondLookupOfAKeyIsAHit) {
  IncrementalCache cache(inflation_, size_t{1} << 30);
  const auto v1 = Create("m", RandomGrid(24, 20, 1));
  const std::vector<Cell> cells = FreeCells(*v1->grid, 12, 2);
  const Cell goal = cells[0];

  auto first = cache.GetSpm(KeyFor("m", goal), v1, StopCondition::None());
  ASSERT_TRUE(first.ok()) << first.status();
  EXPECT_FALSE(first->cache_hit);
  EXPECT_GT(first->expansions, 0);
  EXPECT_EQ(first->map_version, 1u);
  auto second = cache.GetSpm(KeyFor("m", goal), v1, StopCondition::None());
  ASSERT_TRUE(second.ok());
  EXPECT_TRUE(second->cache_hit);
  EXPECT_EQ(second->expansions, 0);
  EXPECT_EQ(second->field, first->field);
  for (Cell start : cells) {
    ExpectSameCost(SpmCost(*second, start), DijkstraCost(*v1->grid, start, goal, {}),
                   "spm");
  }
  // Another goal, another connectivity: other entries.
  ASSERT_FALSE(cache.GetSpm(KeyFor("m", cells[1]), v1, StopCondition::None())->cache_hit);
  IncrementalCache::Key four = KeyFor("m", goal);
  four.cost.connectivity = Connectivity::kFour;
  ASSERT_FALSE(cache.GetSpm(four, v1, StopCondition::None())->cache_hit);

  for (size_t i = 1; i < cells.size(); ++i) {
    auto plan = cache.PlanDStarLite(KeyFor("m", goal), v1, cells[i], StopCondition::None());
    ASSERT_TRUE(plan.ok()) << plan.status();
    EXPECT_EQ(plan->cache_hit, i > 1);
    EXPECT_EQ(plan->map_version, 1u);
    const double expected = DijkstraCost(*v1->grid, cells[i], goal, {});
    ExpectSameCost(plan->result.found() ? plan->result.cost : kInf, expected, "dstar");
  }

  const IncrementalCache::Stats spm = cache.stats(IncrementalCache::Kind::kSpm);
  EXPECT_EQ(spm.hits, 1);
  EXPECT_EQ(spm.misses, 3);
  EXPECT_EQ(spm.entries, 3);
  EXPECT_GT(spm.bytes, 0);
  EXPECT_EQ(spm.budget_bytes, int64_t{1} << 29);
  const IncrementalCache::Stats dstar = cache.stats(IncrementalCache::Kind::kDStarLite);
  EXPECT_EQ(dstar.hits, static_cast<int64_t>(cells.size()) - 2);
  EXPECT_EQ(dstar.misses, 1);
  EXPECT_EQ(dstar.entries, 1);
}

TEST_F(IncrementalCacheTest, RequestRepairsAnEntryBehindItsSnapshot) {
  IncrementalCache cache(inflation_, size_t{1} << 30);  // no Follow: lazy only
  const auto v1 = Create("m", RandomGrid(32, 32, 3));
  const std::vector<Cell> cells = FreeCells(*v1->grid, 20, 4);
  const Cell goal = cells[0];
  ASSERT_TRUE(cache.GetSpm(KeyFor("m", goal), v1, StopCondition::None()).ok());
  ASSERT_TRUE(cache.PlanDStarLite(KeyFor("m", goal), v1, cells[1], StopCondition::None()).ok());

  // Block cells along the current path and free a wall cell elsewhere.
  const PlanResult before =
      cache.GetSpm(KeyFor("m", goal), v1, StopCondition::None())->field->PathFrom(cells[1])
          .value();
  std::vector<Cell> blocked;
  for (size_t i = 1; i + 1 < before.path.size(); i += 3) blocked.push_back(before.path[i]);
  ASSERT_FALSE(blocked.empty());
  SetCells(store_, "m", blocked, kLethalCost);
  const auto v2 = Current("m");
  ASSERT_EQ(v2->version, 2u);

  auto spm = cache.GetSpm(KeyFor("m", goal), v2, StopCondition::None());
  ASSERT_TRUE(spm.ok()) << spm.status();
  EXPECT_TRUE(spm->cache_hit);
  EXPECT_EQ(spm->map_version, 2u);
  EXPECT_EQ(spm->repaired_cells, static_cast<int64_t>(blocked.size()));
  EXPECT_EQ(spm->grid, v2->grid);
  for (Cell start : cells) {
    if (!Free(*v2->grid, start)) continue;
    ExpectSameCost(SpmCost(*spm, start), DijkstraCost(*v2->grid, start, goal, {}),
                   "spm v2");
  }
  auto dstar = cache.PlanDStarLite(KeyFor("m", goal), v2, cells[1], StopCondition::None());
  ASSERT_TRUE(dstar.ok()) << dstar.status();
  EXPECT_TRUE(dstar->cache_hit);
  EXPECT_EQ(dstar->map_version, 2u);
  EXPECT_EQ(dstar->repaired_cells, static_cast<int64_t>(blocked.size()));
  ExpectSameCost(dstar->result.found() ? dstar->result.cost : kInf,
                 DijkstraCost(*v2->grid, cells[1], goal, {}), "dstar v2");
  EXPECT_EQ(cache.stats(IncrementalCache::Kind::kSpm).repairs, 1);
  EXPECT_EQ(cache.stats(IncrementalCache::Kind::kDStarLite).repairs, 1);

  // Two versions behind: the grids are compared instead of using one
  // version's change list, and the answer is still exact.
  SetCells(store_, "m", blocked, kFreeCost);
  SetCells(store_, "m", {cells[2]}, 100);
  const auto v4 = Current("m");
  spm = cache.GetSpm(KeyFor("m", goal), v4, StopCondition::None());
  ASSERT_TRUE(spm.ok());
  EXPECT_EQ(spm->map_version, 4u);
  EXPECT_EQ(spm->repaired_cells,
            static_cast<int64_t>(ChangedCells(*v2->grid, *v4->grid)->size()));
  for (Cell start : cells) {
    if (!Free(*v4->grid, start)) continue;
    ExpectSameCost(SpmCost(*spm, start), DijkstraCost(*v4->grid, start, goal, {}),
                   "spm v4");
  }
  // A request holding an older snapshot gets the entry's newer version, named.
  auto old = cache.GetSpm(KeyFor("m", goal), v2, StopCondition::None());
  ASSERT_TRUE(old.ok());
  EXPECT_EQ(old->map_version, 4u);
}

TEST_F(IncrementalCacheTest, UpdateQueuesARepairWithoutARequest) {
  WorkerPool pool(WorkerPool::Options{1, 16});
  IncrementalCache cache(inflation_, size_t{1} << 30);
  cache.Follow(store_, pool);
  const auto v1 = Create("m", RandomGrid(32, 32, 5));
  const std::vector<Cell> cells = FreeCells(*v1->grid, 10, 6);
  const Cell goal = cells[0];
  ASSERT_TRUE(cache.GetSpm(KeyFor("m", goal), v1, StopCondition::None()).ok());
  ASSERT_TRUE(cache.PlanDStarLite(KeyFor("m", goal), v1, cells[1], StopCondition::None()).ok());

  SetCells(store_, "m", {cells[3], cells[4], cells[5]}, kLethalCost);
  DrainPool(pool);
  EXPECT_EQ(cache.stats(IncrementalCache::Kind::kSpm).repairs, 1);
  EXPECT_EQ(cache.stats(IncrementalCache::Kind::kDStarLite).repairs, 1);

  const auto v2 = Current("m");
  auto spm = cache.GetSpm(KeyFor("m", goal), v2, StopCondition::None());
  ASSERT_TRUE(spm.ok());
  EXPECT_TRUE(spm->cache_hit);
  EXPECT_EQ(spm->map_version, 2u);
  // Already repaired in the background: this request did nothing.
  EXPECT_EQ(spm->repaired_cells, 0);
  EXPECT_EQ(spm->expansions, 0);
  for (Cell start : cells) {
    if (!Free(*v2->grid, start)) continue;
    ExpectSameCost(SpmCost(*spm, start), DijkstraCost(*v2->grid, start, goal, {}),
                   "spm");
  }
  auto dstar = cache.PlanDStarLite(KeyFor("m", goal), v2, cells[1], StopCondition::None());
  ASSERT_TRUE(dstar.ok());
  EXPECT_EQ(dstar->map_version, 2u);
  EXPECT_EQ(dstar->repaired_cells, 0);
  ExpectSameCost(dstar->result.found() ? dstar->result.cost : kInf,
                 DijkstraCost(*v2->grid, cells[1], goal, {}), "dstar");
  pool.Shutdown(WorkerPool::ShutdownMode::kDrain);
}

TEST_F(IncrementalCacheTest, EvictionUnderASmallBudgetKeepsAnswersExact) {
  const auto v1 = Create("m", RandomGrid(40, 40, 7));
  const std::vector<Cell> goals = FreeCells(*v1->grid, 8, 8);
  const std::vector<Cell> starts = FreeCells(*v1->grid, 6, 9);
  // Measure one entry of each kind, then allow about two of each.
  size_t spm_bytes = 0;
  size_t dstar_bytes = 0;
  {
    IncrementalCache probe(inflation_, size_t{1} << 30);
    ASSERT_TRUE(probe.GetSpm(KeyFor("m", goals[0]), v1, StopCondition::None()).ok());
    ASSERT_TRUE(
        probe.PlanDStarLite(KeyFor("m", goals[0]), v1, starts[0], StopCondition::None())
            .ok());
    spm_bytes = static_cast<size_t>(probe.stats(IncrementalCache::Kind::kSpm).bytes);
    dstar_bytes = static_cast<size_t>(probe.stats(IncrementalCache::Kind::kDStarLite).bytes);
  }
  ASSERT_GT(spm_bytes, 0u);
  ASSERT_GT(dstar_bytes, 0u);
  // Each kind gets half the budget, and the two kinds' entries differ in
  // size, so each kind gets a cache with room for about two of its entries.
  IncrementalCache spm_cache(inflation_, 2 * (spm_bytes * 5 / 2));
  IncrementalCache dstar_cache(inflation_, 2 * (dstar_bytes * 5 / 2));

  for (int round = 0; round < 2; ++round) {
    for (Cell goal : goals) {
      auto spm = spm_cache.GetSpm(KeyFor("m", goal), v1, StopCondition::None());
      ASSERT_TRUE(spm.ok()) << spm.status();
      for (Cell start : starts) {
        const double expected = DijkstraCost(*v1->grid, start, goal, {});
        ExpectSameCost(SpmCost(*spm, start), expected, "spm");
        auto dstar =
            dstar_cache.PlanDStarLite(KeyFor("m", goal), v1, start, StopCondition::None());
        ASSERT_TRUE(dstar.ok()) << dstar.status();
        ExpectSameCost(dstar->result.found() ? dstar->result.cost : kInf, expected,
                       "dstar");
      }
      for (const IncrementalCache::Stats s :
           {spm_cache.stats(IncrementalCache::Kind::kSpm),
            dstar_cache.stats(IncrementalCache::Kind::kDStarLite)}) {
        EXPECT_LE(s.bytes, s.budget_bytes);
        EXPECT_LE(s.entries, 2);
      }
    }
  }
  // 8 goals cycled twice with room for 2: every goal's first lookup misses.
  const IncrementalCache::Stats spm = spm_cache.stats(IncrementalCache::Kind::kSpm);
  EXPECT_EQ(spm.misses, 16);
  EXPECT_EQ(spm.hits, 0);
  EXPECT_GE(spm.evictions, 14);
  const IncrementalCache::Stats dstar =
      dstar_cache.stats(IncrementalCache::Kind::kDStarLite);
  EXPECT_EQ(dstar.misses, 16);
  EXPECT_EQ(dstar.hits, 16 * (static_cast<int64_t>(starts.size()) - 1));
  EXPECT_GE(dstar.evictions, 14);
}

// Several threads query one map while another flips a wall between the goal
// and the starts on and off, and the listener queues repairs. Each answer
// names its version; checking it against Dijkstra on exactly that version's
// grid catches any answer computed on a mix of versions or labelled with the
// wrong one (the wall makes neighbouring versions' costs differ).
TEST_F(IncrementalCacheTest, ConcurrentQueriesDuringUpdatesMatchTheirVersion) {
  constexpr int32_t kSize = 32;
  constexpr int32_t kWall = kSize / 2;
  WorkerPool pool(WorkerPool::Options{2, 64});
  IncrementalCache cache(inflation_, size_t{1} << 30);
  cache.Follow(store_, pool);
  Grid grid = RandomGrid(kSize, kSize, 11);
  for (int32_t y = 0; y < kSize; ++y) grid.set_cost(kWall, y, kFreeCost);
  const auto v1 = Create("m", grid);
  const Cell goal = FreeCells(*v1->grid, 1, 12)[0];
  std::vector<Cell> starts;
  for (Cell c : FreeCells(*v1->grid, 64, 13)) {
    if ((c.x < kWall) != (goal.x < kWall) && c.x != kWall) starts.push_back(c);
  }
  ASSERT_GE(starts.size(), 8u);

  absl::Mutex mu;
  std::map<uint64_t, std::shared_ptr<const MapSnapshot>> versions;
  versions[1] = v1;
  struct Answer {
    bool spm;
    Cell start;
    uint64_t version;
    double cost;
  };
  std::vector<Answer> answers;

  std::thread updater([&] {
    for (int i = 0; i < 40; ++i) {
      // The wall leaves a gap in the last two rows.
      auto result = store_.Update(
          "m", {MapChange::ForRect(kWall, 0, kWall, kSize - 3,
                                   i % 2 == 0 ? kLethalCost : kFreeCost)},
          std::nullopt);
      ASSERT_TRUE(result.ok()) << result.status();
      absl::MutexLock lock(&mu);
      versions[result->snapshot->version] = result->snapshot;
    }
  });
  std::vector<std::thread> readers;
  for (int t = 0; t < 4; ++t) {
    readers.emplace_back([&, t] {
      for (int i = 0; i < 25; ++i) {
        const Cell start = starts[static_cast<size_t>(t * 25 + i) % starts.size()];
        const auto snapshot = store_.Get("m").value();
        Answer answer{(i + t) % 2 == 0, start, 0, kInf};
        if (answer.spm) {
          auto spm = cache.GetSpm(KeyFor("m", goal), snapshot, StopCondition::None());
          ASSERT_TRUE(spm.ok()) << spm.status();
          ASSERT_GE(spm->map_version, snapshot->version);
          answer.version = spm->map_version;
          answer.cost = SpmCost(*spm, start);
        } else {
          auto dstar =
              cache.PlanDStarLite(KeyFor("m", goal), snapshot, start, StopCondition::None());
          ASSERT_TRUE(dstar.ok()) << dstar.status();
          ASSERT_GE(dstar->map_version, snapshot->version);
          answer.version = dstar->map_version;
          if (dstar->result.found()) answer.cost = dstar->result.cost;
        }
        absl::MutexLock lock(&mu);
        answers.push_back(answer);
      }
    });
  }
  updater.join();
  for (std::thread& r : readers) r.join();
  pool.Shutdown(WorkerPool::ShutdownMode::kDrain);

  ASSERT_EQ(answers.size(), 100u);
  for (const Answer& a : answers) {
    ASSERT_EQ(versions.count(a.version), 1u) << a.version;
    ExpectSameCost(a.cost, DijkstraCost(*versions[a.version]->grid, a.start, goal, {}),
                   (a.spm ? "spm v" : "dstar v") + std::to_string(a.version));
  }
}

TEST_F(IncrementalCacheTest, DeletedAndRecreatedMapIsRebuilt) {
  WorkerPool pool(WorkerPool::Options{1, 16});
  IncrementalCache cache(inflation_, size_t{1} << 30);
  cache.Follow(store_, pool);
  const auto old_v1 = Create("m", RandomGrid(24, 24, 21));
  const Cell goal{0, 0};
  Grid open = Grid::Create(24, 24).value();
  ASSERT_TRUE(
      cache.GetSpm(KeyFor("open", goal), Create("open", open), StopCondition::None()).ok());
  // Make the goal free on the random map too.
  SetCells(store_, "m", {goal}, kFreeCost);
  SetCells(store_, "m", {Cell{5, 5}}, kFreeCost);
  const auto old_v3 = Current("m");
  ASSERT_EQ(old_v3->version, 3u);
  ASSERT_TRUE(cache.GetSpm(KeyFor("m", goal), old_v3, StopCondition::None()).ok());
  ASSERT_TRUE(
      cache.PlanDStarLite(KeyFor("m", goal), old_v3, Cell{5, 5}, StopCondition::None()).ok());
  ASSERT_EQ(cache.stats(IncrementalCache::Kind::kSpm).entries, 2);

  // Deleting drops the map's entries (not the other map's).
  ASSERT_TRUE(store_.Delete("m").ok());
  EXPECT_EQ(cache.stats(IncrementalCache::Kind::kSpm).entries, 1);
  EXPECT_EQ(cache.stats(IncrementalCache::Kind::kDStarLite).entries, 0);

  // Re-created with other contents: version 1 again, nothing reused.
  const auto new_v1 = Create("m", open);
  auto spm = cache.GetSpm(KeyFor("m", goal), new_v1, StopCondition::None());
  ASSERT_TRUE(spm.ok());
  EXPECT_FALSE(spm->cache_hit);
  EXPECT_EQ(spm->map_version, 1u);
  ExpectSameCost(SpmCost(*spm, Cell{23, 23}), DijkstraCost(open, Cell{23, 23}, goal, {}),
                 "new map");

  // A request still holding the deleted map's snapshot does not get the new
  // map's field: the entry is rebuilt for it, and back for the new map.
  auto stale = cache.GetSpm(KeyFor("m", goal), old_v3, StopCondition::None());
  ASSERT_TRUE(stale.ok());
  EXPECT_FALSE(stale->cache_hit);
  EXPECT_EQ(stale->map_version, 3u);
  ExpectSameCost(SpmCost(*stale, Cell{5, 5}),
                 DijkstraCost(*old_v3->grid, Cell{5, 5}, goal, {}), "old map");
  auto back = cache.GetSpm(KeyFor("m", goal), new_v1, StopCondition::None());
  ASSERT_TRUE(back.ok());
  EXPECT_FALSE(back->cache_hit);
  EXPECT_EQ(back->map_version, 1u);
  ExpectSameCost(SpmCost(*back, Cell{23, 23}), DijkstraCost(open, Cell{23, 23}, goal, {}),
                 "new map again");
  auto dstar = cache.PlanDStarLite(KeyFor("m", goal), new_v1, Cell{5, 5},
                                   StopCondition::None());
  ASSERT_TRUE(dstar.ok());
  EXPECT_FALSE(dstar->cache_hit);
  ExpectSameCost(dstar->result.cost, DijkstraCost(open, Cell{5, 5}, goal, {}), "dstar");
  pool.Shutdown(WorkerPool::ShutdownMode::kDrain);
}

TEST_F(IncrementalCacheTest, RobotRadiusPlansOnTheInflatedVersion) {
  IncrementalCache cache(inflation_, size_t{1} << 30);
  Grid grid = Grid::Create(20, 12).value();
  for (int32_t y = 0; y < 8; ++y) grid.set_cost(10, y, kLethalCost);
  const auto v1 = Create("m", grid);
  const Cell goal{18, 2};
  const Cell start{1, 2};
  auto spm = cache.GetSpm(KeyFor("m", goal, 1.5), v1, StopCondition::None());
  ASSERT_TRUE(spm.ok()) << spm.status();
  const Grid inflated = InflateObstacles(grid, 1.5).value();
  EXPECT_EQ(spm->grid->cells(), inflated.cells());
  ExpectSameCost(SpmCost(*spm, start), DijkstraCost(inflated, start, goal, {}), "v1");
  // The radius is part of the key.
  EXPECT_FALSE(cache.GetSpm(KeyFor("m", goal), v1, StopCondition::None())->cache_hit);

  // An update is repaired on the inflated grids (the change list of the
  // stored map would miss the inflated ring).
  SetCells(store_, "m", {Cell{10, 8}, Cell{10, 9}}, kLethalCost);
  const auto v2 = Current("m");
  spm = cache.GetSpm(KeyFor("m", goal, 1.5), v2, StopCondition::None());
  ASSERT_TRUE(spm.ok());
  EXPECT_TRUE(spm->cache_hit);
  const Grid inflated2 = InflateObstacles(*v2->grid, 1.5).value();
  EXPECT_EQ(spm->repaired_cells,
            static_cast<int64_t>(ChangedCells(inflated, inflated2)->size()));
  ExpectSameCost(SpmCost(*spm, start), DijkstraCost(inflated2, start, goal, {}), "v2");
}

TEST(ChangesBetweenTest, UsesTheUpdatesListOnlyForOneStepOfTheStoredGrid) {
  MapStore store(1 << 16);
  ASSERT_TRUE(store.Create("m", Grid::Create(8, 8).value(), false).ok());
  const auto v1 = store.Get("m").value();
  ASSERT_TRUE(store.Update("m", {MapChange::ForRect(1, 1, 2, 2, kLethalCost)}, std::nullopt)
                  .ok());
  const auto v2 = store.Get("m").value();
  ASSERT_TRUE(v2->changes_known);
  auto one_step = ChangesBetween(*v1->grid, 1, *v2->grid, *v2);
  ASSERT_TRUE(one_step.ok());
  EXPECT_EQ(*one_step, v2->changed_cells);
  EXPECT_EQ(one_step->size(), 4u);

  ASSERT_TRUE(store.Update("m", {MapChange::ForCell(5, 5, 9)}, std::nullopt).ok());
  const auto v3 = store.Get("m").value();
  auto two_steps = ChangesBetween(*v1->grid, 1, *v3->grid, *v3);
  ASSERT_TRUE(two_steps.ok());
  EXPECT_EQ(two_steps->size(), 5u);

  // A copy of the grid (an inflated one, say) is compared, not trusted.
  Grid copy = *v2->grid;
  copy.set_cost(7, 7, kLethalCost);
  auto compared = ChangesBetween(*v1->grid, 1, copy, *v2);
  ASSERT_TRUE(compared.ok());
  EXPECT_EQ(compared->size(), 5u);

  EXPECT_FALSE(
      ChangesBetween(Grid::Create(4, 4).value(), 1, *v2->grid, *v2).ok());
}

}  // namespace
}  // namespace pathd::server
