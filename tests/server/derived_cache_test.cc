// The derived-representation cache: one value per (grid, key), built once
// under concurrency, advanced from an older version of the same map with
// the cells that changed, evicted by bytes.
#include "server/derived_cache.h"

#include <atomic>
#include <chrono>
#include <memory>
#include <new>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "absl/synchronization/notification.h"
#include "absl/time/clock.h"
#include "core/search/stop_condition.h"
#include "gtest/gtest.h"

namespace pathd::server {
namespace {

// A derived value that remembers how it was made.
struct Made {
  int generation = 0;
  std::vector<Cell> changed;
};

struct Counters {
  std::atomic<int> builds{0};
  std::atomic<int> advances{0};
};

DerivedRecipe Recipe(Counters* counters, size_t bytes = 100) {
  DerivedRecipe recipe;
  recipe.build = [counters](const Grid&, DerivedStop&) -> std::shared_ptr<const void> {
    ++counters->builds;
    return std::make_shared<const Made>();
  };
  recipe.advance = [counters](const void* previous, const Grid&,
                              absl::Span<const Cell> changed,
                              DerivedStop&) -> std::shared_ptr<const void> {
    ++counters->advances;
    auto made = std::make_shared<Made>();
    made->generation = static_cast<const Made*>(previous)->generation + 1;
    made->changed.assign(changed.begin(), changed.end());
    return made;
  };
  recipe.bytes = [bytes](const void*) { return bytes; };
  return recipe;
}

std::shared_ptr<const MapSnapshot> Snapshot(uint64_t map_id, uint64_t version,
                                            std::shared_ptr<const Grid> grid,
                                            std::vector<Cell> changed = {},
                                            std::shared_ptr<const ChangeHistory> history = nullptr) {
  auto s = std::make_shared<MapSnapshot>();
  s->history = std::move(history);
  s->name = "m";
  s->map_id = map_id;
  s->version = version;
  s->grid = std::move(grid);
  s->changes_known = !changed.empty();
  s->changed_cells = std::move(changed);
  return s;
}

// Under `stop` when given, else never stopping.
std::shared_ptr<const Made> Get(DerivedCache& cache,
                                const std::shared_ptr<const MapSnapshot>& s,
                                const std::string& key, const DerivedRecipe& recipe,
                                DerivedStop* stop = nullptr) {
  DerivedStop never;
  return std::static_pointer_cast<const Made>(
      cache.For(s, s->grid, 0.0)->Get(key, recipe, stop != nullptr ? *stop : never));
}

TEST(DerivedCacheTest, OneValuePerGridAndKey) {
  DerivedCache cache(1 << 20);
  Counters counters;
  const DerivedRecipe recipe = Recipe(&counters);
  auto v1 = Snapshot(1, 1, std::make_shared<const Grid>(*Grid::Create(4, 4)));
  auto a = Get(cache, v1, "k", recipe);
  auto b = Get(cache, v1, "k", recipe);
  EXPECT_EQ(a, b);
  Get(cache, v1, "other", recipe);
  EXPECT_EQ(counters.builds, 2);
  EXPECT_EQ(cache.stats().hits, 1);
  EXPECT_EQ(cache.stats().entries, 2u);
}

TEST(DerivedCacheTest, ConcurrentMissesBuildOnce) {
  DerivedCache cache(1 << 20);
  Counters counters;
  const DerivedRecipe recipe = Recipe(&counters);
  auto v1 = Snapshot(1, 1, std::make_shared<const Grid>(*Grid::Create(4, 4)));
  std::vector<std::thread> threads;
  std::vector<std::shared_ptr<const Made>> got(8);
  for (int i = 0; i < 8; ++i) {
    threads.emplace_back([&, i] { got[i] = Get(cache, v1, "k", recipe); });
  }
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(counters.builds, 1);
  for (const auto& g : got) EXPECT_EQ(g, got[0]);
}

TEST(DerivedCacheTest, ANewVersionAdvancesWithItsChangedCells) {
  DerivedCache cache(1 << 20);
  Counters counters;
  const DerivedRecipe recipe = Recipe(&counters);
  Grid grid = *Grid::Create(4, 4);
  auto v1 = Snapshot(1, 1, std::make_shared<const Grid>(grid));
  Get(cache, v1, "k", recipe);
  grid.set_cost(2, 1, kLethalCost);
  auto v2 = Snapshot(1, 2, std::make_shared<const Grid>(grid), {{2, 1}});
  auto advanced = Get(cache, v2, "k", recipe);
  EXPECT_EQ(counters.builds, 1);
  EXPECT_EQ(counters.advances, 1);
  EXPECT_EQ(advanced->generation, 1);
  ASSERT_EQ(advanced->changed.size(), 1u);
  EXPECT_EQ(advanced->changed[0], (Cell{2, 1}));
  // With v2's grid gone, v3's recorded changes still describe the step.
  grid.set_cost(0, 3, kLethalCost);
  auto v3 = Snapshot(1, 3, std::make_shared<const Grid>(grid), {{0, 3}});
  v2.reset();
  advanced.reset();
  auto third = Get(cache, v3, "k", recipe);
  EXPECT_EQ(counters.advances, 2);
  EXPECT_EQ(third->generation, 2);
  EXPECT_EQ(third->changed.size(), 1u);
  // Changes not recorded (a large update): v3's grid and v4's are compared.
  grid.set_cost(3, 3, kLethalCost);
  grid.set_cost(1, 0, kLethalCost);
  auto v4 = Snapshot(1, 4, std::make_shared<const Grid>(grid));
  auto fourth = Get(cache, v4, "k", recipe);
  EXPECT_EQ(fourth->generation, 3);
  EXPECT_EQ(fourth->changed.size(), 2u);
  const std::vector<DerivedCache::EntryInfo> entries = cache.Entries("m");
  ASSERT_FALSE(entries.empty());
  EXPECT_EQ(entries[0].version, 4u);
  EXPECT_TRUE(entries[0].advanced);
  EXPECT_EQ(entries[0].changed_cells, 2);
}

// Several updates between two queries, the older grid's buffer gone: the
// value advances with the cells of every update since its version, taken
// from the newest snapshot's history, instead of building again; a history
// that does not reach back (a new run) builds.
TEST(DerivedCacheTest, AVersionSeveralUpdatesOnAdvancesWithTheirCellsFromTheHistory) {
  DerivedCache cache(1 << 20);
  Counters counters;
  const DerivedRecipe recipe = Recipe(&counters);
  Grid grid = *Grid::Create(4, 4);
  auto v1 = Snapshot(1, 1, std::make_shared<const Grid>(grid));
  Get(cache, v1, "k", recipe);
  v1.reset();  // the buffer goes back to the pool: no grids to compare
  std::shared_ptr<const ChangeHistory> history;
  std::shared_ptr<const MapSnapshot> latest;
  for (uint64_t version = 2; version <= 4; ++version) {
    const Cell cell{static_cast<int32_t>(version) - 2, 1};
    grid.set_cost(cell, kLethalCost);
    history = ExtendHistory(history, version, {cell});
    latest = Snapshot(1, version, std::make_shared<const Grid>(grid), {cell}, history);
  }
  auto advanced = Get(cache, latest, "k", recipe);
  EXPECT_EQ(counters.builds, 1);
  EXPECT_EQ(counters.advances, 1);
  ASSERT_EQ(advanced->changed.size(), 3u);  // versions 4, 3, 2
  EXPECT_EQ(advanced->changed[0], (Cell{2, 1}));
  EXPECT_EQ(advanced->changed[2], (Cell{0, 1}));
  // Version 7 of a new run (a replace between): nothing reaches back to 4.
  grid.set_cost(3, 3, kLethalCost);
  auto s7 = Snapshot(1, 7, std::make_shared<const Grid>(grid), {{3, 3}},
                     ExtendHistory(nullptr, 7, {{3, 3}}));
  latest.reset();
  advanced.reset();
  Get(cache, s7, "k", recipe);
  EXPECT_EQ(counters.builds, 2);
  EXPECT_EQ(counters.advances, 1);
}

TEST(DerivedCacheTest, AnotherMapIdOrRadiusBuildsAfresh) {
  DerivedCache cache(1 << 20);
  Counters counters;
  const DerivedRecipe recipe = Recipe(&counters);
  auto v1 = Snapshot(1, 1, std::make_shared<const Grid>(*Grid::Create(4, 4)));
  Get(cache, v1, "k", recipe);
  // Re-created under the same name: a new id, version 1 again.
  auto recreated = Snapshot(2, 2, std::make_shared<const Grid>(*Grid::Create(4, 4)));
  Get(cache, recreated, "k", recipe);
  // An inflated grid of the first map: not advanced from the stored grid's.
  auto inflated = std::make_shared<const Grid>(*Grid::Create(4, 4));
  DerivedStop never;
  cache.For(v1, inflated, 1.5)->Get("k", recipe, never);
  EXPECT_EQ(counters.builds, 3);
  EXPECT_EQ(counters.advances, 0);
}

TEST(DerivedCacheTest, EvictsLeastRecentlyUsedBeyondItsBytes) {
  DerivedCache cache(250);
  Counters counters;
  const DerivedRecipe recipe = Recipe(&counters, 100);
  auto v1 = Snapshot(1, 1, std::make_shared<const Grid>(*Grid::Create(4, 4)));
  Get(cache, v1, "a", recipe);
  Get(cache, v1, "b", recipe);
  Get(cache, v1, "c", recipe);
  EXPECT_LE(cache.stats().bytes, 250u);
  EXPECT_EQ(cache.stats().entries, 2u);
  Get(cache, v1, "a", recipe);  // evicted: built again
  EXPECT_EQ(counters.builds, 4);
}

TEST(DerivedCacheTest, ABuildThatThrowsLeavesNoEntryBehind) {
  DerivedCache cache(1 << 20);
  Counters counters;
  DerivedRecipe recipe = Recipe(&counters);
  DerivedRecipe failing = recipe;
  failing.build = [](const Grid&, DerivedStop&) -> std::shared_ptr<const void> {
    throw std::bad_alloc();
  };
  auto v1 = Snapshot(1, 1, std::make_shared<const Grid>(*Grid::Create(4, 4)));
  EXPECT_THROW(Get(cache, v1, "k", failing), std::bad_alloc);
  EXPECT_EQ(cache.stats().entries, 0u);
  // The next request builds (it would wait forever on a half-made entry).
  EXPECT_NE(Get(cache, v1, "k", recipe), nullptr);
  EXPECT_EQ(counters.builds, 1);
}

// An entry whose grid is freed stays while it is the newest of its map and
// key (the next version advances from it), and goes once a newer one
// exists; an entry of another key is not what supersedes it.
TEST(DerivedCacheTest, EntriesOfFreedVersionsStayUntilANewerOneExists) {
  DerivedCache cache(1 << 20);
  Counters counters;
  const DerivedRecipe recipe = Recipe(&counters);
  Grid grid = *Grid::Create(4, 4);
  auto v1 = Snapshot(1, 1, std::make_shared<const Grid>(grid));
  Get(cache, v1, "a", recipe);
  Get(cache, v1, "b", recipe);
  v1.reset();
  grid.set_cost(1, 1, kLethalCost);
  auto v2 = Snapshot(1, 2, std::make_shared<const Grid>(grid), {{1, 1}});
  // a advances and its v1 entry goes; b's v1 entry is still the newest b.
  Get(cache, v2, "a", recipe);
  EXPECT_EQ(cache.stats().entries, 2u);
  v2.reset();
  grid.set_cost(2, 2, kLethalCost);
  auto v3 = Snapshot(1, 3, std::make_shared<const Grid>(grid), {{2, 2}},
                     ExtendHistory(ExtendHistory(nullptr, 2, {{1, 1}}), 3, {{2, 2}}));
  Get(cache, v3, "a", recipe);
  EXPECT_EQ(cache.stats().entries, 2u);  // a@3, b@1
  // b advances from its v1 entry across both updates.
  auto b = Get(cache, v3, "b", recipe);
  EXPECT_EQ(b->changed.size(), 2u);
  EXPECT_EQ(cache.stats().entries, 2u);  // a@3, b@3
  EXPECT_EQ(counters.builds, 2);
  EXPECT_EQ(counters.advances, 3);
}

// Through a real store: a deleted or replaced map's entries go at once,
// whatever the budget; another map's stay.
TEST(DerivedCacheTest, ADeletedOrReplacedMapsEntriesAreDropped) {
  MapStore store(1 << 20);
  DerivedCache cache(1 << 20);
  cache.Follow(store);
  Counters counters;
  const DerivedRecipe recipe = Recipe(&counters);
  ASSERT_TRUE(store.Create("m", *Grid::Create(8, 8), false).ok());
  ASSERT_TRUE(store.Create("other", *Grid::Create(8, 8), false).ok());
  Get(cache, *store.Get("m"), "k", recipe);
  Get(cache, *store.Get("other"), "k", recipe);
  ASSERT_TRUE(store.Update("m", {MapChange::ForCell(1, 1, kLethalCost)}, std::nullopt).ok());
  EXPECT_EQ(cache.stats().entries, 2u);  // m's v1 stays: its next version advances from it
  ASSERT_TRUE(store.Create("m", *Grid::Create(8, 8), /*replace=*/true).ok());
  EXPECT_EQ(cache.stats().entries, 1u);
  Get(cache, *store.Get("m"), "k", recipe);
  EXPECT_EQ(cache.stats().entries, 2u);
  ASSERT_TRUE(store.Delete("m").ok());
  EXPECT_EQ(cache.stats().entries, 1u);
  EXPECT_EQ(cache.Entries("other").size(), 1u);
}

// A build that ignores its stop: it notifies `started`, then returns a
// value once `release` is notified (or after 20 s, so a test whose waiter
// never returns fails instead of hanging).
DerivedRecipe BlockingRecipe(absl::Notification* started, absl::Notification* release) {
  DerivedRecipe recipe;
  recipe.build = [started, release](const Grid&, DerivedStop&) -> std::shared_ptr<const void> {
    started->Notify();
    release->WaitForNotificationWithTimeout(absl::Seconds(20));
    return std::make_shared<const Made>();
  };
  recipe.bytes = [](const void*) { return size_t{100}; };
  return recipe;
}

// A build that polls its stop every millisecond until it fires (or, so a
// store that never passes the stop fails the test instead of hanging it,
// for at most 20 s), then gives up; `started` is notified when it begins.
DerivedRecipe PollingRecipe(absl::Notification* started, std::atomic<int>* gave_up) {
  DerivedRecipe recipe;
  recipe.build = [started, gave_up](const Grid&,
                                    DerivedStop& stop) -> std::shared_ptr<const void> {
    if (started != nullptr && !started->HasBeenNotified()) started->Notify();
    const absl::Time give_up_anyway = absl::Now() + absl::Seconds(20);
    while (absl::Now() < give_up_anyway) {
      if (stop.Stopped()) {
        stop.Note("building the slow thing");
        ++*gave_up;
        return nullptr;
      }
      absl::SleepFor(absl::Milliseconds(1));
    }
    return std::make_shared<const Made>();
  };
  recipe.bytes = [](const void*) { return size_t{100}; };
  recipe.what = "the slow thing";
  return recipe;
}

TEST(DerivedCacheTest, ABuildThatPollsGivesUpAtTheQueryDeadline) {
  DerivedCache cache(1 << 20);
  std::atomic<int> gave_up{0};
  const DerivedRecipe recipe = PollingRecipe(nullptr, &gave_up);
  auto v1 = Snapshot(1, 1, std::make_shared<const Grid>(*Grid::Create(4, 4)));
  const StopCondition condition(absl::Now() + absl::Milliseconds(50), nullptr, 0);
  DerivedStop stop(condition);
  EXPECT_EQ(Get(cache, v1, "k", recipe, &stop), nullptr);
  EXPECT_EQ(gave_up, 1);
  EXPECT_EQ(stop.Outcome(), PlanOutcome::kTimeout);
  EXPECT_EQ(stop.stopped_while(), "building the slow thing");
  // The unfinished entry is gone, and the next query builds anew.
  EXPECT_EQ(cache.stats().entries, 0u);
  EXPECT_EQ(cache.stats().stopped_builds, 1);
  EXPECT_EQ(cache.stats().builds, 0);
  EXPECT_TRUE(cache.Entries("m").empty());
  Counters counters;
  EXPECT_NE(Get(cache, v1, "k", Recipe(&counters)), nullptr);
  EXPECT_EQ(counters.builds, 1);
  EXPECT_EQ(cache.stats().entries, 1u);
}

TEST(DerivedCacheTest, ACancelledBuildGivesUp) {
  DerivedCache cache(1 << 20);
  std::atomic<int> gave_up{0};
  const DerivedRecipe recipe = PollingRecipe(nullptr, &gave_up);
  auto v1 = Snapshot(1, 1, std::make_shared<const Grid>(*Grid::Create(4, 4)));
  std::atomic<bool> cancelled{false};
  const StopCondition condition(absl::InfiniteFuture(), &cancelled, 0);
  DerivedStop stop(condition);
  std::thread canceller([&] {
    absl::SleepFor(absl::Milliseconds(30));
    cancelled = true;
  });
  EXPECT_EQ(Get(cache, v1, "k", recipe, &stop), nullptr);
  canceller.join();
  EXPECT_EQ(stop.Outcome(), PlanOutcome::kCancelled);
  EXPECT_EQ(cache.stats().entries, 0u);
}

TEST(DerivedCacheTest, AQueryAlreadyStoppedStartsNoBuild) {
  DerivedCache cache(1 << 20);
  Counters counters;
  auto v1 = Snapshot(1, 1, std::make_shared<const Grid>(*Grid::Create(4, 4)));
  const StopCondition condition(absl::Now() - absl::Seconds(1), nullptr, 0);
  DerivedStop stop(condition);
  DerivedRecipe recipe = Recipe(&counters);
  recipe.what = "the thing";
  EXPECT_EQ(Get(cache, v1, "k", recipe, &stop), nullptr);
  EXPECT_EQ(counters.builds, 0);
  EXPECT_EQ(stop.stopped_while(), "building the thing");
  EXPECT_EQ(cache.stats().entries, 0u);
  // A value already there is still answered.
  Get(cache, v1, "k", recipe);
  EXPECT_NE(Get(cache, v1, "k", recipe, &stop), nullptr);
}

TEST(DerivedCacheTest, AWaiterWithADeadlineReturnsAtItWhileTheBuildGoesOn) {
  DerivedCache cache(1 << 20);
  auto v1 = Snapshot(1, 1, std::make_shared<const Grid>(*Grid::Create(4, 4)));
  // The builder has no deadline and finishes when released.
  absl::Notification started, release;
  const DerivedRecipe blocking = BlockingRecipe(&started, &release);
  std::shared_ptr<const Made> built;
  std::thread builder([&] { built = Get(cache, v1, "k", blocking); });
  started.WaitForNotification();

  Counters counters;
  DerivedRecipe waiter_recipe = Recipe(&counters);
  waiter_recipe.what = "the blocked thing";
  const StopCondition condition(absl::Now() + absl::Milliseconds(100), nullptr, 0);
  DerivedStop stop(condition);
  absl::Notification waiter_done;
  std::shared_ptr<const Made> waited;
  std::thread waiter([&] {
    waited = Get(cache, v1, "k", waiter_recipe, &stop);
    waiter_done.Notify();
  });
  // A waiter that ignored its deadline would still be waiting; release the
  // builder then, so the test fails instead of hanging.
  EXPECT_TRUE(waiter_done.WaitForNotificationWithTimeout(absl::Seconds(10)))
      << "the waiter outlived its deadline by seconds";
  EXPECT_FALSE(release.HasBeenNotified());
  release.Notify();
  waiter.join();
  builder.join();
  EXPECT_EQ(waited, nullptr);
  EXPECT_EQ(stop.Outcome(), PlanOutcome::kTimeout);
  EXPECT_EQ(stop.stopped_while(), "waiting for another query's build of the blocked thing");
  EXPECT_EQ(counters.builds, 0) << "the waiter must not build beside the builder";
  EXPECT_NE(built, nullptr);
  EXPECT_EQ(cache.stats().stopped_waits, 1);
  EXPECT_EQ(cache.stats().stopped_builds, 0);
  EXPECT_EQ(cache.stats().entries, 1u);
}

TEST(DerivedCacheTest, ACancelledWaiterStopsWaiting) {
  DerivedCache cache(1 << 20);
  auto v1 = Snapshot(1, 1, std::make_shared<const Grid>(*Grid::Create(4, 4)));
  absl::Notification started, release;
  const DerivedRecipe blocking = BlockingRecipe(&started, &release);
  std::thread builder([&] { Get(cache, v1, "k", blocking); });
  started.WaitForNotification();
  std::atomic<bool> cancelled{false};
  const StopCondition condition(absl::InfiniteFuture(), &cancelled, 0);
  DerivedStop stop(condition);
  absl::Notification waiter_done;
  std::thread waiter([&] {
    EXPECT_EQ(Get(cache, v1, "k", blocking, &stop), nullptr);
    waiter_done.Notify();
  });
  cancelled = true;
  EXPECT_TRUE(waiter_done.WaitForNotificationWithTimeout(absl::Seconds(10)))
      << "the cancelled waiter kept waiting";
  release.Notify();
  waiter.join();
  builder.join();
  EXPECT_EQ(stop.Outcome(), PlanOutcome::kCancelled);
}

TEST(DerivedCacheTest, APatientWaiterGetsTheValueAfterAnImpatientBuilderGivesUp) {
  DerivedCache cache(1 << 20);
  auto v1 = Snapshot(1, 1, std::make_shared<const Grid>(*Grid::Create(4, 4)));
  // The impatient query builds under a 300 ms deadline and gives up at it.
  absl::Notification started;
  std::atomic<int> gave_up{0};
  const DerivedRecipe slow = PollingRecipe(&started, &gave_up);
  const StopCondition impatient_condition(absl::Now() + absl::Milliseconds(300), nullptr,
                                          0);
  DerivedStop impatient_stop(impatient_condition);
  std::shared_ptr<const Made> impatient;
  std::thread builder([&] { impatient = Get(cache, v1, "k", slow, &impatient_stop); });
  started.WaitForNotification();
  // The patient one (no deadline) waits on that build, then builds itself.
  Counters counters;
  const DerivedRecipe quick = Recipe(&counters);
  const StopCondition patient_condition;
  DerivedStop patient_stop(patient_condition);
  const std::shared_ptr<const Made> patient = Get(cache, v1, "k", quick, &patient_stop);
  builder.join();
  EXPECT_EQ(impatient, nullptr);
  EXPECT_EQ(gave_up, 1);
  ASSERT_NE(patient, nullptr) << patient_stop.stopped_while();
  EXPECT_EQ(patient_stop.stopped_while(), "");
  EXPECT_EQ(counters.builds, 1);
  EXPECT_EQ(cache.stats().stopped_builds, 1);
  EXPECT_EQ(cache.stats().entries, 1u);
  EXPECT_EQ(Get(cache, v1, "k", quick), patient);
}

}  // namespace
}  // namespace pathd::server
