// MapStore: versions, optimistic concurrency, batch atomicity, snapshot
// immutability, name and size validation, concurrent readers and writers,
// and the recycling of grid buffers behind O(changed) updates.
#include "server/map_store.h"

#include <atomic>
#include <deque>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "absl/synchronization/mutex.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace pathd::server {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

Grid FreeGrid(int32_t w, int32_t h) { return *Grid::Create(w, h, kFreeCost); }

// The cells whose cost differs between two grids of one size, row-major.
std::vector<Cell> Differences(const Grid& a, const Grid& b) {
  std::vector<Cell> out;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a.cells()[i] != b.cells()[i]) out.push_back(a.CellAt(i));
  }
  return out;
}

TEST(MapStoreTest, CreateStartsAtVersionOneAndReplaceContinuesIt) {
  MapStore store(1 << 20);
  auto a = store.Create("a", FreeGrid(4, 3), false);
  ASSERT_TRUE(a.ok()) << a.status();
  EXPECT_EQ((*a)->version, 1u);
  EXPECT_EQ((*a)->name, "a");
  EXPECT_EQ((*a)->grid->width(), 4);

  auto again = store.Create("a", FreeGrid(2, 2), false);
  EXPECT_EQ(again.status().code(), absl::StatusCode::kAlreadyExists);
  EXPECT_THAT(again.status().message(), HasSubstr("'a'"));

  ASSERT_TRUE(store.Update("a", {MapChange::ForCell(0, 0, 7)}, std::nullopt).ok());
  auto replaced = store.Create("a", FreeGrid(2, 2), true);
  ASSERT_TRUE(replaced.ok()) << replaced.status();
  EXPECT_EQ((*replaced)->version, 3u);
  EXPECT_EQ((*store.Get("a"))->grid->width(), 2);
}

TEST(MapStoreTest, UpdateMakesNewVersionAndLeavesOldSnapshotAlone) {
  MapStore store(1 << 20);
  ASSERT_TRUE(store.Create("m", FreeGrid(5, 5), false).ok());
  const std::shared_ptr<const MapSnapshot> v1 = *store.Get("m");

  auto result = store.Update(
      "m", {MapChange::ForCell(1, 2, 254), MapChange::ForRect(3, 3, 4, 4, 100)},
      std::nullopt);
  ASSERT_TRUE(result.ok()) << result.status();
  EXPECT_EQ(result->snapshot->version, 2u);
  EXPECT_EQ(result->cells_changed, 5);
  EXPECT_EQ(result->snapshot->grid->cost(1, 2), 254);
  EXPECT_EQ(result->snapshot->grid->cost(4, 4), 100);

  // The snapshot taken before the update is untouched.
  EXPECT_EQ(v1->version, 1u);
  EXPECT_EQ(v1->grid->cost(1, 2), kFreeCost);
  EXPECT_EQ(v1->grid->cost(4, 4), kFreeCost);
  EXPECT_EQ((*store.Get("m"))->version, 2u);
}

TEST(MapStoreTest, CellsChangedCountsAgainstThePreviousVersion) {
  MapStore store(1 << 20);
  ASSERT_TRUE(store.Create("m", FreeGrid(4, 4), false).ok());
  // Set then restore (0,0); set (1,1) to its current value; change (2,2).
  auto result = store.Update("m",
                             {MapChange::ForCell(0, 0, 9), MapChange::ForCell(0, 0, 0),
                              MapChange::ForCell(1, 1, 0), MapChange::ForCell(2, 2, 3)},
                             std::nullopt);
  ASSERT_TRUE(result.ok()) << result.status();
  EXPECT_EQ(result->cells_changed, 1);
  EXPECT_EQ(result->snapshot->version, 2u);
}

TEST(MapStoreTest, StaleExpectedVersionIsAborted) {
  MapStore store(1 << 20);
  ASSERT_TRUE(store.Create("x", FreeGrid(3, 3), false).ok());
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(store.Update("x", {MapChange::ForCell(0, 0, i)}, std::nullopt).ok());
  }
  auto stale = store.Update("x", {MapChange::ForCell(1, 1, 1)}, 4);
  EXPECT_EQ(stale.status().code(), absl::StatusCode::kAborted);
  EXPECT_EQ(stale.status().message(), "map 'x' is at version 5, expected 4");
  EXPECT_EQ((*store.Get("x"))->grid->cost(1, 1), kFreeCost);

  auto fresh = store.Update("x", {MapChange::ForCell(1, 1, 1)}, 5);
  ASSERT_TRUE(fresh.ok()) << fresh.status();
  EXPECT_EQ(fresh->snapshot->version, 6u);
}

TEST(MapStoreTest, BatchWithOneBadChangeAppliesNothing) {
  MapStore store(1 << 20);
  ASSERT_TRUE(store.Create("m", FreeGrid(10, 10), false).ok());
  auto bad = store.Update("m",
                          {MapChange::ForCell(0, 0, 254), MapChange::ForRect(0, 0, 9, 9, 50),
                           MapChange::ForCell(10, 3, 254)},
                          std::nullopt);
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(bad.status().message(), HasSubstr("change 2"));
  EXPECT_THAT(bad.status().message(), HasSubstr("(10, 3)"));

  const auto current = *store.Get("m");
  EXPECT_EQ(current->version, 1u);
  for (uint8_t c : current->grid->cells()) ASSERT_EQ(c, kFreeCost);
}

TEST(MapStoreTest, RejectsBadChanges) {
  MapStore store(1 << 20);
  ASSERT_TRUE(store.Create("m", FreeGrid(10, 10), false).ok());

  auto empty = store.Update("m", {}, std::nullopt);
  EXPECT_EQ(empty.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(empty.status().message(), HasSubstr("no changes"));

  auto cost = store.Update("m", {MapChange::ForCell(1, 1, 256)}, std::nullopt);
  EXPECT_EQ(cost.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(cost.status().message(), HasSubstr("cost 256"));

  auto inverted = store.Update("m", {MapChange::ForRect(5, 1, 2, 3, 1)}, std::nullopt);
  EXPECT_EQ(inverted.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(inverted.status().message(), HasSubstr("min > max"));

  auto off = store.Update("m", {MapChange::ForRect(5, 5, 10, 6, 1)}, std::nullopt);
  EXPECT_EQ(off.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(off.status().message(), HasSubstr("change 0"));
  EXPECT_THAT(off.status().message(), HasSubstr("outside the 10 x 10 map"));

  auto negative = store.Update("m", {MapChange::ForCell(-1, 0, 1)}, std::nullopt);
  EXPECT_EQ(negative.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ((*store.Get("m"))->version, 1u);
}

TEST(MapStoreTest, UnknownMapsAreNotFound) {
  MapStore store(1 << 20);
  EXPECT_EQ(store.Get("nope").status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(store.Get("nope").status().message(), "map 'nope' not found");
  EXPECT_EQ(store.Delete("nope").status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(store.Update("nope", {MapChange::ForCell(0, 0, 1)}, std::nullopt)
                .status()
                .code(),
            absl::StatusCode::kNotFound);
}

// A name no map can have is a bad request on lookups too, and the answer
// never quotes it whole (a 1 MiB name used to come back inside NOT_FOUND's
// message, beyond what gRPC's metadata can carry).
TEST(MapStoreTest, LookupsOfInvalidNamesAreInvalidArgument) {
  MapStore store(1 << 20);
  ASSERT_TRUE(store.Create("m", FreeGrid(2, 2), false).ok());
  for (const std::string& bad :
       {std::string(), std::string(1 << 20, 'n'), std::string("a/b"), std::string(".."),
        std::string("m\0", 2)}) {
    const absl::Status get = store.Get(bad).status();
    EXPECT_EQ(get.code(), absl::StatusCode::kInvalidArgument) << bad.size();
    EXPECT_THAT(get.message(), HasSubstr("map name")) << bad.size();
    EXPECT_LE(get.message().size(), 512u);
    EXPECT_EQ(store.Delete(bad).status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(store.Update(bad, {MapChange::ForCell(0, 0, 1)}, std::nullopt)
                  .status()
                  .code(),
              absl::StatusCode::kInvalidArgument);
  }
  EXPECT_EQ((*store.Get("m"))->version, 1u);
}

// Overlapping rectangles are legal, but a batch may write at most
// MaxBatchWrites cells in total; checked before the copy is made.
TEST(MapStoreTest, BatchesWritingTooManyCellsAreRefused) {
  MapStore store(1 << 20);
  ASSERT_TRUE(store.Create("m", FreeGrid(16, 16), false).ok());
  const Grid& grid = *(*store.Get("m"))->grid;
  const int64_t limit = MapStore::MaxBatchWrites(grid);
  EXPECT_EQ(limit, MapStore::kMinBatchWrites);
  // Exactly at the limit is fine, one cell more is not.
  std::vector<MapChange> changes(static_cast<size_t>(limit / 256),
                                 MapChange::ForRect(0, 0, 15, 15, 9));
  ASSERT_TRUE(store.Update("m", changes, std::nullopt).ok());
  changes.push_back(MapChange::ForCell(3, 3, 1));
  const auto over = store.Update("m", changes, std::nullopt);
  EXPECT_EQ(over.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(over.status().message(),
              HasSubstr(absl::StrFormat("write %d cells in total", limit + 1)));
  EXPECT_EQ((*store.Get("m"))->version, 2u);
  EXPECT_EQ(MapStore::MaxBatchWrites(FreeGrid(1024, 1024)),
            MapStore::kMaxWritesPerCell * 1024 * 1024);
}

// Many tall rectangles would need more row spans than the map has bytes; the
// update then compares whole rows and must find exactly the same cells.
TEST(MapStoreTest, ChangedCellsAreExactForBatchesOfManyRows) {
  MapStore store(1 << 20);
  // 6000 cells: 588 rows of spans (7 kB) outweigh them, and the 561 changed
  // cells stay within what an update lists.
  ASSERT_TRUE(store.Create("m", FreeGrid(200, 30), false).ok());
  std::vector<MapChange> changes;
  for (int32_t x = 2; x < 65; x += 3) changes.push_back(MapChange::ForRect(x, 1, x, 28, 7));
  // Undone again: counted as no change.
  changes.push_back(MapChange::ForRect(5, 1, 5, 28, 0));
  changes.push_back(MapChange::ForCell(19, 29, 4));
  const Grid before = *(*store.Get("m"))->grid;
  auto result = store.Update("m", changes, std::nullopt);
  ASSERT_TRUE(result.ok()) << result.status();
  const std::vector<Cell> expected = Differences(before, *result->snapshot->grid);
  EXPECT_EQ(expected.size(), 20u * 28u + 1u);
  ASSERT_TRUE(result->snapshot->changes_known);
  EXPECT_EQ(result->snapshot->changed_cells, expected);
  EXPECT_EQ(result->cells_changed, static_cast<int64_t>(expected.size()));
}

TEST(MapStoreTest, DeleteReturnsLastVersionAndKeepsHeldSnapshots) {
  MapStore store(1 << 20);
  ASSERT_TRUE(store.Create("d", FreeGrid(3, 3), false).ok());
  ASSERT_TRUE(store.Update("d", {MapChange::ForCell(0, 0, 1)}, std::nullopt).ok());
  const auto held = *store.Get("d");
  auto last = store.Delete("d");
  ASSERT_TRUE(last.ok()) << last.status();
  EXPECT_EQ(*last, 2u);
  EXPECT_EQ(store.Get("d").status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(held->grid->cost(0, 0), 1);
  // The name is free again and starts over.
  auto again = store.Create("d", FreeGrid(1, 1), false);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ((*again)->version, 1u);
}

// Caches tell a re-created map from the one they were built on by map_id, not
// by version (a re-created map starts again at version 1).
TEST(MapStoreTest, MapIdIsKeptByUpdatesAndRenewedByEveryCreate) {
  MapStore store(1 << 20);
  const auto v1 = *store.Create("m", FreeGrid(3, 3), false);
  const auto other = *store.Create("other", FreeGrid(3, 3), false);
  EXPECT_NE(v1->map_id, 0u);
  EXPECT_NE(other->map_id, v1->map_id);
  const auto v2 = store.Update("m", {MapChange::ForCell(0, 0, 1)}, std::nullopt)->snapshot;
  EXPECT_EQ(v2->map_id, v1->map_id);
  const auto replaced = *store.Create("m", FreeGrid(3, 3), true);
  EXPECT_NE(replaced->map_id, v1->map_id);
  ASSERT_TRUE(store.Delete("m").ok());
  const auto recreated = *store.Create("m", FreeGrid(3, 3), false);
  EXPECT_EQ(recreated->version, 1u);
  EXPECT_NE(recreated->map_id, v1->map_id);
  EXPECT_NE(recreated->map_id, replaced->map_id);
}

TEST(MapStoreTest, ListIsSortedByName) {
  MapStore store(1 << 20);
  for (const char* name : {"zeta", "Alpha", "beta", "alpha-2"}) {
    ASSERT_TRUE(store.Create(name, FreeGrid(1, 1), false).ok());
  }
  std::vector<std::string> names;
  for (const auto& s : store.List()) names.push_back(s->name);
  EXPECT_THAT(names, ElementsAre("Alpha", "alpha-2", "beta", "zeta"));
  EXPECT_EQ(store.size(), 4u);
}

TEST(MapStoreTest, ValidatesNames) {
  EXPECT_TRUE(MapStore::ValidateName("a").ok());
  EXPECT_TRUE(MapStore::ValidateName("Warehouse_2.floor-1").ok());
  EXPECT_TRUE(MapStore::ValidateName(std::string(128, 'n')).ok());

  const auto empty = MapStore::ValidateName("");
  EXPECT_EQ(empty.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(empty.message(), HasSubstr("empty"));

  const auto too_long = MapStore::ValidateName(std::string(129, 'n'));
  EXPECT_EQ(too_long.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(too_long.message(), HasSubstr("128"));

  const auto dot = MapStore::ValidateName(".hidden");
  EXPECT_EQ(dot.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(dot.message(), HasSubstr("start with '.'"));

  for (const char* bad : {"a b", "a/b", "x/../y", "caf\xc3\xa9", "x:y"}) {
    const auto s = MapStore::ValidateName(bad);
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << bad;
    EXPECT_THAT(s.message(), HasSubstr("position")) << bad;
  }

  MapStore store(1 << 20);
  EXPECT_EQ(store.Create("bad name", FreeGrid(1, 1), false).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(MapStoreTest, MaxCellsIsEnforced) {
  MapStore store(100);
  EXPECT_TRUE(store.Create("fits", FreeGrid(10, 10), false).ok());
  auto big = store.Create("big", FreeGrid(11, 10), false);
  EXPECT_EQ(big.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(big.status().message(), HasSubstr("max_map_cells"));
  EXPECT_THAT(big.status().message(), HasSubstr("100"));
  // Overflowing products are refused, not wrapped.
  EXPECT_EQ(store.CheckSize(int64_t{1} << 40, int64_t{1} << 40).code(),
            absl::StatusCode::kResourceExhausted);
}

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

}  // namespace
}  // namespace pathd::server
