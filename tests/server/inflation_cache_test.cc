// InflationCache: one computation per (map version, shape), shared by
// concurrent requests, never matched to a different or freed version; a new
// version's shaped grid advanced from the previous version's, equal to
// shaping it afresh.
#include "server/inflation_cache.h"

#include <atomic>
#include <memory>
#include <optional>
#include <random>
#include <thread>
#include <vector>

#include "absl/status/status.h"
#include "absl/time/clock.h"
#include "gtest/gtest.h"
#include "server/map_store.h"

namespace pathd::server {
namespace {

// Marks cell (0,0) with the radius, cell (1,0) with the clearance and cell
// (2,0) with the inflation radius so tests can tell results apart, and
// counts calls.
struct FakeInflate {
  std::atomic<int>* calls;
  absl::Duration delay = absl::ZeroDuration();
  absl::StatusOr<Grid> operator()(const Grid& grid, const GridShape& shape) const {
    calls->fetch_add(1);
    absl::SleepFor(delay);
    const double radius = shape.robot_radius_cells;
    if (radius > 100) return absl::InvalidArgumentError("radius too large");
    Grid copy = grid;
    copy.set_cost(0, 0, static_cast<uint8_t>(radius));
    copy.set_cost(1, 0, static_cast<uint8_t>(shape.min_clearance_cells));
    copy.set_cost(2, 0, static_cast<uint8_t>(shape.inflation_radius_cells));
    return copy;
  }
};

// Advancing is never expected of these tests' sources (each is its own map
// or its changes are unknown).
absl::StatusOr<ShapedGridAdvance> NoAdvance(const Grid&, const Grid&,
                                            absl::Span<const Cell>, const GridShape&) {
  return absl::InternalError("advanced");
}

InflationCache FakeCache(std::atomic<int>* calls, size_t entries,
                         absl::Duration delay = absl::ZeroDuration()) {
  return InflationCache(FakeInflate{calls, delay}, &NoAdvance, entries);
}

// A map version of its own map (a new map id each time) unless `map_id` says.
MapSnapshot MakeSource(std::optional<uint64_t> map_id = std::nullopt,
                       uint64_t version = 1) {
  static std::atomic<uint64_t> next_id{1000};
  MapSnapshot snapshot;
  snapshot.name = "m";
  snapshot.map_id = map_id.has_value() ? *map_id : next_id.fetch_add(1);
  snapshot.version = version;
  snapshot.grid = std::make_shared<const Grid>(Grid::Create(4, 4).value());
  return snapshot;
}

TEST(InflationCache, ComputesOncePerVersionAndRadius) {
  std::atomic<int> calls{0};
  InflationCache cache = FakeCache(&calls, 8);
  const MapSnapshot v1 = MakeSource();
  auto a = cache.Get(v1, 3.0);
  ASSERT_TRUE(a.ok());
  EXPECT_EQ((*a)->cost(0, 0), 3);
  auto b = cache.Get(v1, 3.0);
  ASSERT_TRUE(b.ok());
  EXPECT_EQ(a->get(), b->get());
  EXPECT_EQ(calls.load(), 1);
  auto c = cache.Get(v1, 5.0);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ((*c)->cost(0, 0), 5);
  // Another map's grid is a different source.
  const MapSnapshot v2 = MakeSource();
  ASSERT_TRUE(cache.Get(v2, 3.0).ok());
  EXPECT_EQ(calls.load(), 3);
  const InflationCache::Stats stats = cache.stats();
  EXPECT_EQ(stats.hits, 1);
  EXPECT_EQ(stats.misses, 3);
  EXPECT_EQ(stats.builds, 3);
  EXPECT_EQ(stats.advances, 0);
  EXPECT_EQ(stats.entries, 3u);
}

// The clearance and the inflation costs are part of the key: the same radius
// with and without them, or with other values, is another grid;
// unknown_is_free only counts with either (GridShape::Of).
TEST(InflationCache, ClearanceAndInflationArePartOfTheShape) {
  std::atomic<int> calls{0};
  InflationCache cache = FakeCache(&calls, 16);
  const MapSnapshot v1 = MakeSource();
  auto plain = cache.Get(v1, 3.0);
  auto clear = cache.Get(v1, GridShape::Of(3.0, 0.0, 0.0, 7.0, false));
  auto clear_unknown = cache.Get(v1, GridShape::Of(3.0, 0.0, 0.0, 7.0, true));
  auto wider = cache.Get(v1, GridShape::Of(3.0, 0.0, 0.0, 9.0, false));
  auto inflated = cache.Get(v1, GridShape::Of(3.0, 11.0, 0.5, 0.0, false));
  auto steeper = cache.Get(v1, GridShape::Of(3.0, 11.0, 0.7, 0.0, false));
  auto inflated_unknown = cache.Get(v1, GridShape::Of(3.0, 11.0, 0.5, 0.0, true));
  ASSERT_TRUE(plain.ok() && clear.ok() && clear_unknown.ok() && wider.ok() &&
              inflated.ok() && steeper.ok() && inflated_unknown.ok());
  EXPECT_EQ((*plain)->cost(1, 0), 0);
  EXPECT_EQ((*clear)->cost(1, 0), 7);
  EXPECT_EQ((*wider)->cost(1, 0), 9);
  EXPECT_EQ((*inflated)->cost(2, 0), 11);
  EXPECT_NE(clear->get(), clear_unknown->get());
  EXPECT_NE(inflated->get(), steeper->get());
  EXPECT_NE(inflated->get(), inflated_unknown->get());
  EXPECT_EQ(calls.load(), 7);
  // Without a clearance or inflation costs unknown_is_free does not split the
  // radius's entry, nor does a scaling without an inflation radius.
  auto again = cache.Get(v1, GridShape::Of(3.0, 0.0, 0.9, 0.0, true));
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->get(), plain->get());
  EXPECT_EQ(calls.load(), 7);
}

TEST(InflationCache, FreedVersionsAreNeverMatched) {
  std::atomic<int> calls{0};
  InflationCache cache = FakeCache(&calls, 8);
  for (uint64_t version = 1; version <= 5; ++version) {
    // The allocator may well reuse the address of the freed grid; the cache
    // must notice the old version is gone. (Versions of one map whose
    // changes are unknown: each is shaped in full.)
    const MapSnapshot source = MakeSource(7, version);
    ASSERT_TRUE(cache.Get(source, 2.0).ok());
  }
  EXPECT_EQ(calls.load(), 5);
  // The newest version's entry stays for the next version to advance from.
  EXPECT_LE(cache.stats().entries, 1u);
}

TEST(InflationCache, ConcurrentRequestsShareOneComputation) {
  std::atomic<int> calls{0};
  InflationCache cache = FakeCache(&calls, 8, absl::Milliseconds(50));
  const MapSnapshot source = MakeSource();
  std::vector<std::thread> threads;
  std::vector<const Grid*> seen(8, nullptr);
  for (int i = 0; i < 8; ++i) {
    threads.emplace_back([&, i] {
      auto r = cache.Get(source, 4.0);
      if (r.ok()) seen[i] = r->get();
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(calls.load(), 1);
  for (const Grid* g : seen) EXPECT_EQ(g, seen[0]);
  EXPECT_NE(seen[0], nullptr);
}

TEST(InflationCache, ErrorsAreReturnedAndNotCached) {
  std::atomic<int> calls{0};
  InflationCache cache = FakeCache(&calls, 8);
  const MapSnapshot source = MakeSource();
  EXPECT_EQ(cache.Get(source, 500.0).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(cache.Get(source, 500.0).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(calls.load(), 2);
  EXPECT_EQ(cache.stats().entries, 0u);
}

TEST(InflationCache, EvictsTheLeastRecentlyUsed) {
  std::atomic<int> calls{0};
  InflationCache cache = FakeCache(&calls, 2);
  const MapSnapshot source = MakeSource();
  ASSERT_TRUE(cache.Get(source, 1.0).ok());
  ASSERT_TRUE(cache.Get(source, 2.0).ok());
  ASSERT_TRUE(cache.Get(source, 1.0).ok());  // 1 is now the most recent
  ASSERT_TRUE(cache.Get(source, 3.0).ok());  // evicts 2
  EXPECT_EQ(cache.stats().entries, 2u);
  EXPECT_EQ(calls.load(), 3);
  ASSERT_TRUE(cache.Get(source, 1.0).ok());
  EXPECT_EQ(calls.load(), 3);
  ASSERT_TRUE(cache.Get(source, 2.0).ok());
  EXPECT_EQ(calls.load(), 4);
}

// A 256 x 192 map with random walls, at 0.05 m per cell.
Grid RandomMap(std::mt19937& rng) {
  Grid grid = Grid::Create(256, 192).value();
  grid.set_resolution(0.05);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (uint8_t& c : grid.mutable_cells()) c = u(rng) < 0.04 ? kLethalCost : kFreeCost;
  return grid;
}

// Through the real store and the real shaping: every version after the
// first is advanced from the one before (whose stored grid is gone by then,
// as a map store's old versions are), and equals shaping it afresh.
TEST(InflationCache, AdvancesEachVersionFromThePreviousOne) {
  MapStore store(1 << 20);
  InflationCache cache(4);
  std::mt19937 rng(3);
  ASSERT_TRUE(store.Create("m", RandomMap(rng), false).ok());
  // Nav2's defaults at 5 cm: 0.55 m, 10 per metre; a 0.2 m robot; clearance.
  const GridShape shape = GridShape::Of(4.0, 11.0, 0.5, 3.0, false);
  std::uniform_int_distribution<int> x(0, 255), y(0, 191);
  for (int step = 0; step < 6; ++step) {
    std::shared_ptr<const MapSnapshot> snapshot = store.Get("m").value();
    absl::StatusOr<std::shared_ptr<const Grid>> shaped = cache.Get(*snapshot, shape);
    ASSERT_TRUE(shaped.ok()) << shaped.status();
    EXPECT_EQ((*shaped)->cells(), ShapeGrid(*snapshot->grid, shape)->cells())
        << "version " << snapshot->version;
    EXPECT_EQ(cache.Get(*snapshot, shape)->get(), shaped->get());  // a hit
    std::vector<MapChange> changes;
    for (int i = 0; i < 5; ++i) {
      changes.push_back(MapChange::ForCell(x(rng), y(rng), i % 2 == 0 ? kLethalCost : 0));
    }
    changes.push_back(
        MapChange::ForRect(10, 10, 13, 12, step % 2 == 0 ? kLethalCost : 0));
    snapshot.reset();
    ASSERT_TRUE(store.Update("m", changes, std::nullopt).ok());
  }
  const InflationCache::Stats stats = cache.stats();
  EXPECT_EQ(stats.builds, 1);
  EXPECT_EQ(stats.advances, 5);
  EXPECT_EQ(stats.hits, 6);
  // One entry per shape: each version's replaced the one before.
  EXPECT_EQ(stats.entries, 1u);
}

// Versions skipped, whether the older stored grid still lives or was
// freed: the newest snapshot's history lists the cells of the versions in
// between, and the shaped grid advances with them, equal to one shaped
// afresh. A re-created map (a new map id) never advances from the old one.
TEST(InflationCache, AdvancesAcrossVersionsOnlyWhenTheChangesAreKnown) {
  MapStore store(1 << 20);
  InflationCache cache(8);
  std::mt19937 rng(4);
  ASSERT_TRUE(store.Create("m", RandomMap(rng), false).ok());
  const GridShape shape = GridShape::Of(2.0, 6.0, 0.8, 0.0, false);
  std::shared_ptr<const MapSnapshot> v1 = store.Get("m").value();
  ASSERT_TRUE(cache.Get(*v1, shape).ok());
  auto update = [&](int x, int y, uint8_t cost) {
    ASSERT_TRUE(store.Update("m", {MapChange::ForCell(x, y, cost)}, std::nullopt).ok());
  };
  update(5, 5, kLethalCost);
  update(40, 30, kLethalCost);
  std::shared_ptr<const MapSnapshot> v3 = store.Get("m").value();
  ASSERT_EQ(v3->version, 3u);
  ASSERT_TRUE(cache.Get(*v3, shape).ok());
  EXPECT_EQ(cache.stats().advances, 1);
  EXPECT_EQ((*cache.Get(*v3, shape))->cells(), ShapeGrid(*v3->grid, shape)->cells());

  v1.reset();
  v3.reset();
  update(60, 20, kLethalCost);
  update(61, 20, kLethalCost);
  std::shared_ptr<const MapSnapshot> v5 = store.Get("m").value();
  ASSERT_TRUE(cache.Get(*v5, shape).ok());
  EXPECT_EQ(cache.stats().advances, 2);
  EXPECT_EQ(cache.stats().builds, 1);
  EXPECT_EQ((*cache.Get(*v5, shape))->cells(), ShapeGrid(*v5->grid, shape)->cells());

  v5.reset();
  ASSERT_TRUE(store.Create("m", RandomMap(rng), /*replace=*/true).ok());
  std::shared_ptr<const MapSnapshot> replaced = store.Get("m").value();
  ASSERT_TRUE(cache.Get(*replaced, shape).ok());
  EXPECT_EQ(cache.stats().builds, 2);
  EXPECT_EQ((*cache.Get(*replaced, shape))->cells(),
            ShapeGrid(*replaced->grid, shape)->cells());
}

}  // namespace
}  // namespace pathd::server
