// MemoryBudget's admission rules (issue 15): every limit refuses with
// RESOURCE_EXHAUSTED naming its flag, the caches' bytes count against the
// total, one caller gets only its share, and released bytes are free again.
#include "server/memory_budget.h"

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace pathd::server {
namespace {

using ::testing::HasSubstr;
using Part = MemoryBudget::Part;

constexpr int64_t kMiB = int64_t{1} << 20;

void ExpectRefused(const absl::Status& status, const char* flag) {
  EXPECT_EQ(status.code(), absl::StatusCode::kResourceExhausted) << status;
  EXPECT_THAT(status.message(), HasSubstr(flag)) << status;
}

TEST(MemoryBudgetTest, SessionBytesAreBoundedAndReleasedBytesAreFreeAgain) {
  MemoryBudget budget({.total_bytes = 0, .session_bytes = 100 * kMiB, .max_watchers = 10,
                       .caller_share = 1.0});
  auto a = budget.Reserve(Part::kSessions, "peer:a", 60 * kMiB, "session a");
  ASSERT_TRUE(a.ok()) << a.status();
  ExpectRefused(budget.Reserve(Part::kSessions, "peer:b", 50 * kMiB, "session b").status(),
                "--session_memory_bytes");
  EXPECT_EQ(budget.refusals(), 1);
  EXPECT_EQ(budget.reserved(Part::kSessions), 60 * kMiB);
  a->Release();
  EXPECT_EQ(budget.reserved(Part::kSessions), 0);
  EXPECT_TRUE(budget.Reserve(Part::kSessions, "peer:b", 50 * kMiB, "session b").ok());
  // The temporary's destructor released it.
  EXPECT_EQ(budget.reserved(Part::kSessions), 0);
}

TEST(MemoryBudgetTest, CachesCountAgainstTheTotal) {
  int64_t caches = 70 * kMiB;
  MemoryBudget budget({.total_bytes = 100 * kMiB, .session_bytes = 0,
                       .max_watchers = 10, .caller_share = 1.0,
                       .cache_bytes = [&caches] { return caches; }});
  auto watcher = budget.Reserve(Part::kWatchers, "peer:a", 20 * kMiB, "watcher");
  ASSERT_TRUE(watcher.ok());
  ExpectRefused(budget.Reserve(Part::kSessions, "peer:a", 20 * kMiB, "session").status(),
                "--memory_budget_bytes");
  caches = 10 * kMiB;  // the caches evicted
  EXPECT_TRUE(budget.Reserve(Part::kSessions, "peer:a", 20 * kMiB, "session").ok());
}

TEST(MemoryBudgetTest, WatchersAreCountedAndOneCallerGetsOnlyItsShare) {
  MemoryBudget budget({.total_bytes = 0, .session_bytes = 0, .max_watchers = 4,
                       .caller_share = 0.5});
  std::vector<MemoryBudget::Reservation> held;
  for (int i = 0; i < 2; ++i) {
    auto r = budget.Reserve(Part::kWatchers, "peer:a", kMiB, "watcher");
    ASSERT_TRUE(r.ok()) << r.status();
    held.push_back(*std::move(r));
  }
  ExpectRefused(budget.Reserve(Part::kWatchers, "peer:a", kMiB, "watcher").status(),
                "--caller_memory_share");
  for (int i = 0; i < 2; ++i) {
    auto r = budget.Reserve(Part::kWatchers, "peer:b", kMiB, "watcher");
    ASSERT_TRUE(r.ok()) << r.status();
    held.push_back(*std::move(r));
  }
  ExpectRefused(budget.Reserve(Part::kWatchers, "peer:c", kMiB, "watcher").status(),
                "--max_watchers");
  EXPECT_EQ(budget.holders(Part::kWatchers), 4);
  held.clear();
  EXPECT_EQ(budget.holders(Part::kWatchers), 0);
}

TEST(MemoryBudgetTest, OneCallerGetsOnlyItsShareOfTheSessionBytes) {
  MemoryBudget budget({.total_bytes = 0, .session_bytes = 100 * kMiB,
                       .max_watchers = 10, .caller_share = 0.5});
  auto first = budget.Reserve(Part::kSessions, "token:1", 40 * kMiB, "session");
  ASSERT_TRUE(first.ok());
  ExpectRefused(budget.Reserve(Part::kSessions, "token:1", 20 * kMiB, "session").status(),
                "--caller_memory_share");
  EXPECT_TRUE(budget.Reserve(Part::kSessions, "token:2", 50 * kMiB, "session").ok());
}

TEST(MemoryBudgetTest, ResizeGrowsWithinTheLimitsAndUpdateFollowsTheRealSize) {
  MemoryBudget budget({.total_bytes = 100 * kMiB, .session_bytes = 0,
                       .max_watchers = 10, .caller_share = 1.0});
  auto r = budget.Reserve(Part::kWatchers, "peer:a", 10 * kMiB, "watcher");
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(r->Resize(50 * kMiB).ok());
  ExpectRefused(r->Resize(150 * kMiB), "--memory_budget_bytes");
  EXPECT_EQ(r->bytes(), 50 * kMiB);  // unchanged by the refusal
  r->Update(120 * kMiB);             // in use either way
  EXPECT_EQ(budget.reserved(Part::kWatchers), 120 * kMiB);
  EXPECT_TRUE(r->Resize(5 * kMiB).ok());
  EXPECT_EQ(budget.reserved(Part::kWatchers), 5 * kMiB);
}

}  // namespace
}  // namespace pathd::server
