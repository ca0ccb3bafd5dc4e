// MapStore with a journal: a version is visible to readers and listeners
// only once the journal reports it durable, and a change whose write failed
// is never visible and its version never shown for other content.
// Regression test for "a change is visible before it is durable, and a failed
// write's version is reused".
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "absl/synchronization/mutex.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/map_store.h"

namespace pathd::server {
namespace {

using ::testing::ElementsAre;
using ::testing::IsEmpty;

// A journal whose WaitDurable blocks until the test releases it with the
// outcome of the "disk write".
class GatedJournal : public MapJournal {
 public:
  absl::Status Writable() override {
    absl::MutexLock lock(&mu_);
    return failed_.ok() ? absl::OkStatus() : absl::UnavailableError("log failed");
  }
  absl::StatusOr<std::string> EncodeCreate(std::string_view, uint64_t,
                                           const Grid&) override {
    return std::string("c");
  }
  std::string EncodeUpdate(std::string_view, uint64_t,
                           absl::Span<const MapChange>) override {
    return "u";
  }
  std::string EncodeDelete(std::string_view, uint64_t) override { return "d"; }
  uint64_t Append(std::string_view, std::string,
                  std::shared_ptr<const MapSnapshot>) override {
    absl::MutexLock lock(&mu_);
    return ++appended_;
  }
  absl::Status WaitDurable(uint64_t /*sequence*/) override {
    absl::MutexLock lock(&mu_);
    mu_.Await(absl::Condition(
        +[](GatedJournal* j) ABSL_NO_THREAD_SAFETY_ANALYSIS { return j->released_; }, this));
    if (!failed_.ok()) return failed_;
    return absl::OkStatus();
  }

  void AwaitAppended(uint64_t n) {
    absl::MutexLock lock(&mu_);
    awaited_ = n;
    mu_.Await(absl::Condition(this, &GatedJournal::ReachedAwaited));
  }
  void Release(absl::Status outcome) {
    absl::MutexLock lock(&mu_);
    released_ = true;
    failed_ = std::move(outcome);
  }

 private:
  bool ReachedAwaited() const ABSL_SHARED_LOCKS_REQUIRED(mu_) {
    return appended_ >= awaited_;
  }

  absl::Mutex mu_;
  uint64_t appended_ ABSL_GUARDED_BY(mu_) = 0;
  uint64_t awaited_ ABSL_GUARDED_BY(mu_) = 0;
  bool released_ ABSL_GUARDED_BY(mu_) = false;
  absl::Status failed_ ABSL_GUARDED_BY(mu_);
};

class MapStoreJournalTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(store_.Create("m", *Grid::Create(8, 8), false).ok());
    store_.AddListener([this](std::string_view, const std::shared_ptr<const MapSnapshot>& s) {
      absl::MutexLock lock(&mu_);
      heard_.push_back(s == nullptr ? 0 : s->version);
    });
    store_.SetJournal(&journal_);
  }
  std::vector<uint64_t> Heard() {
    absl::MutexLock lock(&mu_);
    return heard_;
  }
  uint64_t Visible() { return (*store_.Get("m"))->version; }

  MapStore store_{1 << 20};
  GatedJournal journal_;
  absl::Mutex mu_;
  std::vector<uint64_t> heard_ ABSL_GUARDED_BY(mu_);
};

TEST_F(MapStoreJournalTest, UpdateIsInvisibleUntilDurable) {
  absl::StatusOr<MapUpdateResult> result;
  std::thread writer([&] { result = store_.Update("m", {MapChange::ForCell(1, 1, 9)}, {}); });
  journal_.AwaitAppended(1);
  // Logged, not yet on disk: readers and watchers still see version 1.
  EXPECT_EQ(Visible(), 1u);
  EXPECT_EQ((*store_.Get("m"))->grid->cost(1, 1), 0);
  EXPECT_THAT(Heard(), IsEmpty());
  journal_.Release(absl::OkStatus());
  writer.join();
  ASSERT_TRUE(result.ok()) << result.status();
  EXPECT_EQ(result->snapshot->version, 2u);
  EXPECT_EQ(Visible(), 2u);
  EXPECT_THAT(Heard(), ElementsAre(2u));
}

TEST_F(MapStoreJournalTest, FailedWriteIsNeverVisibleAndItsVersionNeverReused) {
  absl::StatusOr<MapUpdateResult> result;
  std::thread writer([&] { result = store_.Update("m", {MapChange::ForCell(1, 1, 9)}, {}); });
  journal_.AwaitAppended(1);
  journal_.Release(absl::InternalError("cannot write wal: No space left on device"));
  writer.join();
  EXPECT_EQ(result.status().code(), absl::StatusCode::kInternal);
  EXPECT_EQ(Visible(), 1u);
  EXPECT_THAT(Heard(), IsEmpty());
  // Every later change is refused, so version 2 never names other content.
  EXPECT_EQ(store_.Update("m", {MapChange::ForCell(2, 2, 5)}, {}).status().code(),
            absl::StatusCode::kUnavailable);
  EXPECT_EQ(store_.Delete("m").status().code(), absl::StatusCode::kUnavailable);
  EXPECT_EQ(Visible(), 1u);
  EXPECT_THAT(Heard(), IsEmpty());
}

TEST_F(MapStoreJournalTest, DeleteAndCreateAreInvisibleUntilDurable) {
  std::thread deleter([&] { EXPECT_TRUE(store_.Delete("m").ok()); });
  journal_.AwaitAppended(1);
  EXPECT_EQ(Visible(), 1u);  // the deletion is not durable yet
  EXPECT_EQ(store_.size(), 1u);
  // Writers see the logged state: the name is free for a new map.
  std::thread creator([&] { EXPECT_TRUE(store_.Create("m", *Grid::Create(4, 4), false).ok()); });
  journal_.AwaitAppended(2);
  EXPECT_EQ((*store_.Get("m"))->grid->width(), 8);
  journal_.Release(absl::OkStatus());
  deleter.join();
  creator.join();
  EXPECT_EQ((*store_.Get("m"))->grid->width(), 4);
  EXPECT_EQ(Visible(), 1u);
  // The deletion reached the listeners; the new map (no watchers yet) did not.
  EXPECT_THAT(Heard(), ElementsAre(0u));
}

TEST_F(MapStoreJournalTest, UpdateAsyncAnswersOnlyOnceDurable) {
  absl::Mutex mu;
  std::optional<absl::StatusOr<MapUpdateResult>> answer;
  // The default OnDurable blocks in WaitDurable; run the call on a thread.
  std::thread caller([&] {
    store_.UpdateAsync("m", {MapChange::ForCell(3, 3, 7)}, {},
                       [&](absl::StatusOr<MapUpdateResult> result) {
                         absl::MutexLock lock(&mu);
                         answer = std::move(result);
                       });
  });
  journal_.AwaitAppended(1);
  {
    absl::MutexLock lock(&mu);
    EXPECT_FALSE(answer.has_value());
  }
  EXPECT_EQ(Visible(), 1u);
  journal_.Release(absl::OkStatus());
  caller.join();
  absl::MutexLock lock(&mu);
  ASSERT_TRUE(answer.has_value());
  ASSERT_TRUE(answer->ok());
  EXPECT_EQ((*answer)->snapshot->version, 2u);
  EXPECT_EQ(Visible(), 2u);
}

}  // namespace
}  // namespace pathd::server
