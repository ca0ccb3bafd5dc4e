// InflationCache: one computation per (map version, shape), shared by
// concurrent requests, never matched to a different or freed version.
#include "server/inflation_cache.h"

#include <atomic>
#include <memory>
#include <thread>
#include <vector>

#include "absl/status/status.h"
#include "absl/time/clock.h"
#include "gtest/gtest.h"

namespace pathd::server {
namespace {

// Marks cell (0,0) with the radius and cell (1,0) with the clearance so
// tests can tell results apart, and counts calls.
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
    return copy;
  }
};

std::shared_ptr<const Grid> MakeSource() {
  return std::make_shared<const Grid>(Grid::Create(4, 4).value());
}

TEST(InflationCache, ComputesOncePerVersionAndRadius) {
  std::atomic<int> calls{0};
  InflationCache cache(FakeInflate{&calls}, 8);
  auto v1 = MakeSource();
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
  // A new version of the map is a different source.
  auto v2 = MakeSource();
  ASSERT_TRUE(cache.Get(v2, 3.0).ok());
  EXPECT_EQ(calls.load(), 3);
  const InflationCache::Stats stats = cache.stats();
  EXPECT_EQ(stats.hits, 1);
  EXPECT_EQ(stats.misses, 3);
  EXPECT_EQ(stats.entries, 3u);
}

// The clearance is part of the key: the same radius with and without it, or
// with another clearance, is another grid; unknown_is_free only counts with
// a clearance (GridShape::Of).
TEST(InflationCache, ClearanceIsPartOfTheShape) {
  std::atomic<int> calls{0};
  InflationCache cache(FakeInflate{&calls}, 8);
  auto v1 = MakeSource();
  auto plain = cache.Get(v1, 3.0);
  auto clear = cache.Get(v1, GridShape::Of(3.0, 7.0, false));
  auto clear_unknown = cache.Get(v1, GridShape::Of(3.0, 7.0, true));
  auto wider = cache.Get(v1, GridShape::Of(3.0, 9.0, false));
  ASSERT_TRUE(plain.ok() && clear.ok() && clear_unknown.ok() && wider.ok());
  EXPECT_EQ((*plain)->cost(1, 0), 0);
  EXPECT_EQ((*clear)->cost(1, 0), 7);
  EXPECT_EQ((*wider)->cost(1, 0), 9);
  EXPECT_NE(clear->get(), clear_unknown->get());
  EXPECT_EQ(calls.load(), 4);
  // Without a clearance unknown_is_free does not split the radius's entry.
  auto again = cache.Get(v1, GridShape::Of(3.0, 0.0, true));
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->get(), plain->get());
  EXPECT_EQ(calls.load(), 4);
}

TEST(InflationCache, FreedVersionsAreNeverMatched) {
  std::atomic<int> calls{0};
  InflationCache cache(FakeInflate{&calls}, 8);
  for (int i = 0; i < 5; ++i) {
    // The allocator may well reuse the address of the freed grid; the cache
    // must notice the old version is gone.
    auto source = MakeSource();
    ASSERT_TRUE(cache.Get(source, 2.0).ok());
  }
  EXPECT_EQ(calls.load(), 5);
  EXPECT_LE(cache.stats().entries, 1u);
}

TEST(InflationCache, ConcurrentRequestsShareOneComputation) {
  std::atomic<int> calls{0};
  InflationCache cache(FakeInflate{&calls, absl::Milliseconds(50)}, 8);
  auto source = MakeSource();
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
  InflationCache cache(FakeInflate{&calls}, 8);
  auto source = MakeSource();
  EXPECT_EQ(cache.Get(source, 500.0).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(cache.Get(source, 500.0).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(calls.load(), 2);
  EXPECT_EQ(cache.stats().entries, 0u);
}

TEST(InflationCache, EvictsTheLeastRecentlyUsed) {
  std::atomic<int> calls{0};
  InflationCache cache(FakeInflate{&calls}, 2);
  auto source = MakeSource();
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

}  // namespace
}  // namespace pathd::server
