// map_store_test: concurrent readers and writers seeing whole versions, and
// the recycling of grid buffers behind O(changed) updates.
#include "server/map_store.h"

#include <atomic>
#include <deque>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/status.h"
#include "absl/synchronization/mutex.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/server/map_store_test_util.h"

namespace pathd::server::map_store_test {

using ::testing::ElementsAre;

// Writers repaint the whole map with one value per update; readers must only
// ever see uniform maps (no half-applied batch) with non-decreasing versions,
// and every successful compare-and-set update must count.
TEST(MapStoreTest, ConcurrentReadersAndWritersSeeWholeVersions) {
  constexpr int kWriters = 3;
  constexpr int kReaders = 3;
  constexpr int kUpdatesPerWriter = 60;
  MapStore store(1 << 20);
  ASSERT_TRUE(store.Create("shared", FreeGrid(64, 64), false).ok());

  std::atomic<bool> done{false};
  std::atomic<int> reader_failures{0};
  std::atomic<int> cas_successes{0};
  std::vector<std::thread> threads;
  for (int r = 0; r < kReaders; ++r) {
    threads.emplace_back([&] {
      uint64_t last_version = 0;
      while (!done.load()) {
        auto snap = store.Get("shared");
        if (!snap.ok()) {
          ++reader_failures;
          continue;
        }
        const auto& cells = (*snap)->grid->cells();
        for (uint8_t c : cells) {
          if (c != cells.front()) {
            ++reader_failures;
            break;
          }
        }
        if ((*snap)->version < last_version) ++reader_failures;
        last_version = (*snap)->version;
        // Listing and reading another name must not interfere either.
        if (store.List().empty()) ++reader_failures;
      }
    });
  }
  std::vector<std::thread> writers;
  for (int w = 0; w < kWriters; ++w) {
    writers.emplace_back([&, w] {
      for (int i = 0; i < kUpdatesPerWriter; ++i) {
        const uint32_t value = static_cast<uint32_t>(1 + (w * kUpdatesPerWriter + i) % 250);
        if (i % 2 == 0) {
          ASSERT_TRUE(store.Update("shared", {MapChange::ForRect(0, 0, 63, 63, value)},
                                   std::nullopt)
                          .ok());
        } else {
          const uint64_t seen = (*store.Get("shared"))->version;
          auto r = store.Update("shared", {MapChange::ForRect(0, 0, 63, 63, value)}, seen);
          if (r.ok()) {
            ++cas_successes;
          } else {
            ASSERT_EQ(r.status().code(), absl::StatusCode::kAborted) << r.status();
          }
        }
      }
    });
  }
  for (auto& t : writers) t.join();
  done.store(true);
  for (auto& t : threads) t.join();

  EXPECT_EQ(reader_failures.load(), 0);
  const uint64_t unconditional = kWriters * ((kUpdatesPerWriter + 1) / 2);
  EXPECT_EQ((*store.Get("shared"))->version,
            1 + unconditional + static_cast<uint64_t>(cas_successes.load()));
}

// Create(replace) and Delete racing with updates must never lose the map's
// invariants: versions only grow while the name exists, and nothing crashes.
TEST(MapStoreTest, ConcurrentReplaceDeleteAndUpdate) {
  MapStore store(1 << 20);
  ASSERT_TRUE(store.Create("churn", FreeGrid(16, 16), false).ok());
  std::atomic<bool> done{false};
  std::thread updater([&] {
    while (!done.load()) {
      auto r = store.Update("churn", {MapChange::ForCell(1, 1, 5)}, std::nullopt);
      if (!r.ok()) {
        ASSERT_EQ(r.status().code(), absl::StatusCode::kNotFound);
      }
    }
  });
  for (int i = 0; i < 200; ++i) {
    if (i % 3 == 0) {
      (void)store.Delete("churn");
      ASSERT_TRUE(store.Create("churn", FreeGrid(16, 16), false).ok());
    } else {
      ASSERT_TRUE(store.Create("churn", FreeGrid(8, 8), true).ok());
    }
  }
  done.store(true);
  updater.join();
  EXPECT_TRUE(store.Get("churn").ok());
}

// Two far-apart cells: the batch's bounding box is the whole map, but only
// the written cells are compared, and changed_cells comes out row-major.
TEST(MapStoreTest, ChangedCellsAreExactAndRowMajorForScatteredBatches) {
  MapStore store(1 << 20);
  ASSERT_TRUE(store.Create("m", FreeGrid(50, 40), false).ok());
  auto result = store.Update(
      "m",
      {MapChange::ForCell(49, 39, 7), MapChange::ForRect(2, 3, 4, 3, 9),
       MapChange::ForRect(3, 3, 6, 4, 0), MapChange::ForCell(0, 0, 5),
       MapChange::ForCell(49, 39, 8)},
      std::nullopt);
  ASSERT_TRUE(result.ok()) << result.status();
  const MapSnapshot& v2 = *result->snapshot;
  ASSERT_TRUE(v2.changes_known);
  // (3..4, 3) were set to 9 and back to 0 by the overlapping rectangle.
  EXPECT_THAT(v2.changed_cells, ElementsAre(Cell{0, 0}, Cell{2, 3}, Cell{49, 39}));
  EXPECT_EQ(result->cells_changed, 3);
  EXPECT_EQ(v2.grid->cost(2, 3), 9);
  EXPECT_EQ(v2.grid->cost(49, 39), 8);
}

// Single-threaded walk through the three ways an update gets its buffer.
TEST(MapStoreTest, UpdatesRecycleReleasedBuffersAndNeverHeldOnes) {
  MapStore store(1 << 20);
  ASSERT_TRUE(store.Create("m", FreeGrid(64, 64), false).ok());
  const Grid* v1_buffer = (*store.Get("m"))->grid.get();

  // Version 1 is still current: no spare yet.
  ASSERT_TRUE(store.Update("m", {MapChange::ForCell(1, 1, 10)}, std::nullopt).ok());
  EXPECT_EQ(store.buffer_stats().allocated, 1);
  // Version 1 was released when version 2 replaced it; version 3 reuses its
  // buffer, replaying version 2's cell.
  auto v3 = store.Update("m", {MapChange::ForCell(2, 2, 20)}, std::nullopt);
  ASSERT_TRUE(v3.ok());
  EXPECT_EQ(v3->snapshot->grid.get(), v1_buffer);
  EXPECT_EQ(v3->snapshot->grid->cost(1, 1), 10);
  EXPECT_EQ(v3->snapshot->grid->cost(2, 2), 20);
  EXPECT_EQ(store.buffer_stats().replayed, 1);

  // A held version keeps its buffer: later versions go elsewhere and it
  // keeps its content.
  const std::shared_ptr<const MapSnapshot> held = v3->snapshot;
  v3 = absl::InternalError("released");
  for (int i = 0; i < 5; ++i) {
    auto r = store.Update("m", {MapChange::ForCell(3, 50, 30 + i)}, std::nullopt);
    ASSERT_TRUE(r.ok());
    EXPECT_NE(r->snapshot->grid.get(), held->grid.get());
  }
  EXPECT_EQ(held->grid->cost(3, 50), kFreeCost);
  EXPECT_EQ(held->grid->cost(2, 2), 20);

  // A large update (over 1/8 of the map) has unknown changes and drops the
  // log, so the next update copies the whole grid into a spare.
  auto big = store.Update("m", {MapChange::ForRect(0, 0, 63, 40, 5)}, std::nullopt);
  ASSERT_TRUE(big.ok());
  EXPECT_FALSE(big->snapshot->changes_known);
  big = absl::InternalError("released");
  const int64_t copied = store.buffer_stats().copied;
  auto after = store.Update("m", {MapChange::ForCell(63, 63, 1)}, std::nullopt);
  ASSERT_TRUE(after.ok());
  EXPECT_EQ(store.buffer_stats().copied, copied + 1);
  EXPECT_EQ(after->snapshot->grid->cost(0, 40), 5);
  EXPECT_EQ(after->snapshot->grid->cost(63, 63), 1);
  EXPECT_EQ(after->snapshot->grid->cost(3, 50), 34);
}

// The main property: thousands of random updates on two maps while holder
// threads keep random old snapshots alive for random times. Every snapshot,
// when taken and when released, equals the reference grid of its version,
// and every version's changed_cells is exactly the difference to the
// previous one.
TEST(MapStoreTest, RecycledBuffersNeverChangeHeldSnapshots) {
  constexpr int kMaps = 2;
  constexpr int kUpdatesPerMap = 2500;
  constexpr int kHolders = 4;
  constexpr int32_t kWidth = 80;
  constexpr int32_t kHeight = 60;
  MapStore store(1 << 20);

  struct References {
    absl::Mutex mu;
    std::map<uint64_t, Grid> by_version ABSL_GUARDED_BY(mu);
  };
  std::vector<References> refs(kMaps);
  for (int m = 0; m < kMaps; ++m) {
    Grid grid = FreeGrid(kWidth, kHeight);
    ASSERT_TRUE(store.Create("m" + std::to_string(m), grid, false).ok());
    absl::MutexLock lock(&refs[m].mu);
    refs[m].by_version.emplace(1, std::move(grid));
  }
  auto reference = [&](int m, uint64_t version) {
    absl::MutexLock lock(&refs[m].mu);
    auto it = refs[m].by_version.find(version);
    return it == refs[m].by_version.end() ? Grid() : it->second;
  };

  std::atomic<int> updaters_left{kMaps};
  std::atomic<int> mismatches{0};
  std::vector<std::thread> threads;
  for (int m = 0; m < kMaps; ++m) {
    threads.emplace_back([&, m] {
      std::mt19937 rng(17 + m);
      auto coord = [&](int32_t n) { return std::uniform_int_distribution<int32_t>(0, n - 1)(rng); };
      auto cost = [&] { return std::uniform_int_distribution<uint32_t>(0, 254)(rng); };
      Grid current = FreeGrid(kWidth, kHeight);
      for (int i = 0; i < kUpdatesPerMap; ++i) {
        std::vector<MapChange> batch;
        const int kind = std::uniform_int_distribution<int>(0, 99)(rng);
        if (kind < 80) {  // a few scattered cells: the replay path
          const int n = std::uniform_int_distribution<int>(1, 12)(rng);
          for (int k = 0; k < n; ++k) {
            batch.push_back(MapChange::ForCell(coord(kWidth), coord(kHeight), cost()));
          }
        } else if (kind < 95) {  // small overlapping rectangles
          for (int k = 0; k < 3; ++k) {
            const int32_t x = coord(kWidth - 8), y = coord(kHeight - 8);
            batch.push_back(MapChange::ForRect(x, y, x + coord(8), y + coord(8), cost()));
          }
        } else if (kind < 98) {  // over the log's budget: drops the log
          const int32_t y = coord(kHeight - 10);
          batch.push_back(MapChange::ForRect(0, y, kWidth - 1, y + 5, cost()));
        } else {  // over 1/8 of the map: changes not tracked
          batch.push_back(MapChange::ForRect(0, 0, kWidth - 1, kHeight / 2, cost()));
        }
        Grid next = current;
        for (const MapChange& c : batch) {
          for (int32_t y = c.y_min; y <= c.y_max; ++y) {
            for (int32_t x = c.x_min; x <= c.x_max; ++x) {
              next.set_cost(x, y, static_cast<uint8_t>(c.cost));
            }
          }
        }
        // Recorded before the update so a holder never sees an unknown version.
        const uint64_t version = static_cast<uint64_t>(i) + 2;
        {
          absl::MutexLock lock(&refs[m].mu);
          refs[m].by_version.emplace(version, next);
        }
        auto r = store.Update("m" + std::to_string(m), batch, std::nullopt);
        ASSERT_TRUE(r.ok()) << r.status();
        ASSERT_EQ(r->snapshot->version, version);
        const std::vector<Cell> diff = Differences(current, next);
        EXPECT_EQ(r->cells_changed, static_cast<int64_t>(diff.size()));
        if (r->snapshot->changes_known) {
          EXPECT_EQ(r->snapshot->changed_cells, diff) << "version " << version;
        } else {
          EXPECT_GT(diff.size(), static_cast<size_t>(kWidth * kHeight / 8));
        }
        if (r->snapshot->grid->cells() != next.cells()) ++mismatches;
        current = std::move(next);
      }
      --updaters_left;
    });
  }
  for (int h = 0; h < kHolders; ++h) {
    threads.emplace_back([&, h] {
      std::mt19937 rng(101 + h);
      struct Held {
        int map;
        std::shared_ptr<const MapSnapshot> snapshot;
        int release_at;
      };
      std::deque<Held> held;
      auto check = [&](const Held& e) {
        const Grid expected = reference(e.map, e.snapshot->version);
        if (expected.cells() != e.snapshot->grid->cells()) ++mismatches;
      };
      for (int step = 0; updaters_left.load() > 0 || !held.empty(); ++step) {
        if (updaters_left.load() > 0) {
          const int m = std::uniform_int_distribution<int>(0, kMaps - 1)(rng);
          Held e{m, *store.Get("m" + std::to_string(m)),
                 step + std::uniform_int_distribution<int>(0, 200)(rng)};
          check(e);
          held.push_back(std::move(e));
        }
        for (auto it = held.begin(); it != held.end();) {
          if (it->release_at <= step || updaters_left.load() == 0) {
            check(*it);
            it = held.erase(it);
          } else {
            ++it;
          }
        }
        if (h % 2 == 0) std::this_thread::yield();
      }
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(mismatches.load(), 0);
  // All three ways of getting a buffer ran.
  const MapStore::BufferStats stats = store.buffer_stats();
  EXPECT_GT(stats.replayed, 0);
  EXPECT_GT(stats.copied, 0);
  EXPECT_GT(stats.allocated, 0);
  // Most updates recycled: held snapshots are few, so allocations stay rare.
  EXPECT_GT(stats.replayed, stats.allocated);
}

// Buffers out in snapshots when their map is deleted, re-created with another
// size or replaced: they are freed, never fed to the new map's pool.
TEST(MapStoreTest, BuffersOfDeletedOrReplacedMapsStayOutOfTheNewMap) {
  MapStore store(1 << 20);
  ASSERT_TRUE(store.Create("m", FreeGrid(30, 20), false).ok());
  std::vector<std::shared_ptr<const MapSnapshot>> old;
  for (int i = 0; i < 4; ++i) {
    auto r = store.Update("m", {MapChange::ForCell(i, 0, 100)}, std::nullopt);
    ASSERT_TRUE(r.ok());
    old.push_back(r->snapshot);
  }
  ASSERT_TRUE(store.Delete("m").ok());
  ASSERT_TRUE(store.Create("m", FreeGrid(10, 10), false).ok());
  old.clear();  // the buffers return to a pool that is gone
  for (int i = 0; i < 5; ++i) {
    auto r = store.Update("m", {MapChange::ForCell(i, i, 7)}, std::nullopt);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->snapshot->grid->width(), 10);
    EXPECT_EQ(r->snapshot->grid->cost(0, 0), 7);
    EXPECT_EQ(r->snapshot->grid->cost(i, i), 7);
    EXPECT_THAT(r->snapshot->changed_cells, ElementsAre(Cell{i, i}));
    old.push_back(r->snapshot);
  }
  // Replaced by a map of the old size with other content while the 10x10
  // versions are out.
  Grid full = *Grid::Create(30, 20, 50);
  ASSERT_TRUE(store.Create("m", full, true).ok());
  old.clear();
  for (int i = 0; i < 5; ++i) {
    auto r = store.Update("m", {MapChange::ForCell(29, 19, 60 + i)}, std::nullopt);
    ASSERT_TRUE(r.ok());
    full.set_cost(29, 19, static_cast<uint8_t>(60 + i));
    EXPECT_EQ(r->snapshot->grid->cells(), full.cells());
  }
}

TEST(MapStoreTest, SnapshotsOutliveTheStore) {
  auto store = std::make_unique<MapStore>(1 << 20);
  ASSERT_TRUE(store->Create("m", FreeGrid(8, 8), false).ok());
  std::vector<std::shared_ptr<const MapSnapshot>> held;
  for (int i = 0; i < 6; ++i) {
    auto r = store->Update("m", {MapChange::ForCell(i, 0, 9)}, std::nullopt);
    ASSERT_TRUE(r.ok());
    if (i % 2 == 0) held.push_back(r->snapshot);
  }
  store.reset();
  // Versions 2, 4 and 6: cells 0..0, 0..2, 0..4 of row 0 set.
  for (size_t k = 0; k < held.size(); ++k) {
    for (int32_t x = 0; x < 8; ++x) {
      EXPECT_EQ(held[k]->grid->cost(x, 0), x <= static_cast<int32_t>(2 * k) ? 9 : 0);
    }
  }
  held.clear();
}

}  // namespace pathd::server::map_store_test
