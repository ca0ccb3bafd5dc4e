// MapStore: versions, optimistic concurrency, batch atomicity, snapshot
// immutability, name and size validation, concurrent readers and writers,
// and the recycling of grid buffers behind O(changed) updates.
#include "server/map_store.h"

#include <optional>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/server/map_store_test_util.h"

namespace pathd::server::map_store_test {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

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

// Each version's history reaches back over the run of updates before it:
// from every older version still reachable, the union it gives covers every
// cell in which that version's grid differs (the grids themselves, held
// here, are the check), at least the newest half of ChangeHistory's bound
// is always reachable, never more than the bound, and a replace starts a
// new run.
TEST(MapStoreTest, ChangesSinceCoversEveryCellAnOlderVersionDiffersIn) {
  MapStore store(1 << 20);
  ASSERT_TRUE(store.Create("m", FreeGrid(40, 30), false).ok());
  std::vector<std::shared_ptr<const MapSnapshot>> held{*store.Get("m")};
  std::mt19937 rng(5);
  const uint8_t costs[] = {kFreeCost, 100, kLethalCost};
  int reached = 0;
  for (int step = 0; step < 150; ++step) {
    std::vector<MapChange> changes;
    const int n = 1 + static_cast<int>(rng() % 4);
    for (int k = 0; k < n; ++k) {
      const int32_t x = static_cast<int32_t>(rng() % 38);
      const int32_t y = static_cast<int32_t>(rng() % 28);
      const uint8_t cost = costs[rng() % 3];
      changes.push_back(k % 2 == 0 ? MapChange::ForCell(x, y, cost)
                                   : MapChange::ForRect(x, y, x + 2, y + 2, cost));
    }
    auto result = store.Update("m", changes, std::nullopt);
    ASSERT_TRUE(result.ok()) << result.status();
    held.push_back(result->snapshot);
    const MapSnapshot& now = *held.back();
    for (size_t i = 0; i + 1 < held.size(); ++i) {
      const uint64_t back = now.version - held[i]->version;
      const std::optional<std::vector<Cell>> since = ChangesSince(now, held[i]->version);
      if (!since.has_value()) {
        EXPECT_GT(back, ChangeHistory::kMaxVersions / 2) << "step " << step;
        continue;
      }
      EXPECT_LE(back, ChangeHistory::kMaxVersions);
      ++reached;
      std::set<std::pair<int32_t, int32_t>> listed;
      for (const Cell& c : *since) listed.insert({c.x, c.y});
      for (const Cell& c : Differences(*held[i]->grid, *now.grid)) {
        ASSERT_TRUE(listed.count({c.x, c.y})) << "step " << step << ": version "
                                               << held[i]->version << " differs at "
                                               << CellToString(c) << ", not listed";
      }
    }
  }
  EXPECT_GT(reached, 150 * 25);
  const uint64_t last = held.back()->version;
  auto replaced = store.Create("m", FreeGrid(40, 30), true);
  ASSERT_TRUE(replaced.ok());
  EXPECT_FALSE(ChangesSince(**replaced, last).has_value());
  auto after = store.Update("m", {MapChange::ForCell(1, 1, kLethalCost)}, std::nullopt);
  ASSERT_TRUE(after.ok());
  const std::optional<std::vector<Cell>> one = ChangesSince(*after->snapshot, last + 1);
  ASSERT_TRUE(one.has_value());
  EXPECT_EQ(*one, std::vector<Cell>{(Cell{1, 1})});
  EXPECT_FALSE(ChangesSince(*after->snapshot, last).has_value());
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

}  // namespace pathd::server::map_store_test
