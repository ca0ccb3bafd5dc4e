// DurableStore on a real directory: maps and versions survive reopening,
// snapshots replace old segments, a torn final record is cut away, and
// corruption elsewhere stops Open with DATA_LOSS naming the file.
#include "server/storage/durable_store.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "absl/strings/str_cat.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/map_store.h"
#include "server/storage/wal_format.h"

namespace pathd::server {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

constexpr int64_t kMaxCells = 1 << 20;

class DurableStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("pathd_durable_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override {
    durable_.reset();
    fs::remove_all(dir_);
  }

  // A fresh store recovered from dir_ (as a restarted pathd would be).
  absl::Status Reopen(DurableStore::Options options = {}) {
    durable_.reset();
    store_ = std::make_unique<MapStore>(kMaxCells);
    options.dir = dir_.string();
    absl::StatusOr<std::unique_ptr<DurableStore>> opened =
        DurableStore::Open(options, *store_);
    if (!opened.ok()) return opened.status();
    durable_ = *std::move(opened);
    return absl::OkStatus();
  }

  std::vector<std::string> Files(const std::string& prefix) const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind(prefix, 0) == 0) names.push_back(name);
    }
    std::sort(names.begin(), names.end());
    return names;
  }

  std::string Read(const std::string& file) const {
    std::ifstream in(dir_ / file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }
  void Write(const std::string& file, const std::string& bytes) const {
    std::ofstream out(dir_ / file, std::ios::binary | std::ios::trunc);
    out << bytes;
  }

  void CreateAndUpdate() {
    ASSERT_TRUE(store_->Create("a", *Grid::Create(8, 8), false).ok());
    ASSERT_TRUE(store_->Update("a", {MapChange::ForRect(1, 1, 3, 3, 254)}, {}).ok());
    ASSERT_TRUE(store_->Update("a", {MapChange::ForCell(7, 7, 9)}, {}).ok());
    ASSERT_TRUE(store_->Create("b", *Grid::Create(4, 4, 1), false).ok());
  }

  fs::path dir_;
  std::unique_ptr<MapStore> store_;
  std::unique_ptr<DurableStore> durable_;
};

TEST_F(DurableStoreTest, MapsAndVersionsSurviveReopening) {
  ASSERT_TRUE(Reopen().ok());
  CreateAndUpdate();
  ASSERT_TRUE(store_->Delete("b").ok());
  ASSERT_TRUE(store_->Create("c", *Grid::Create(2, 2), false).ok());
  ASSERT_TRUE(store_->Create("c", *Grid::Create(3, 3, 5), /*replace=*/true).ok());

  ASSERT_TRUE(Reopen().ok());
  EXPECT_EQ(durable_->recovery().maps, 2);
  auto a = store_->Get("a");
  ASSERT_TRUE(a.ok());
  EXPECT_EQ((*a)->version, 3u);
  EXPECT_EQ((*a)->grid->cost(2, 2), 254);
  EXPECT_EQ((*a)->grid->cost(7, 7), 9);
  EXPECT_EQ(store_->Get("b").status().code(), absl::StatusCode::kNotFound);
  auto c = store_->Get("c");
  ASSERT_TRUE(c.ok());
  EXPECT_EQ((*c)->version, 2u);
  EXPECT_EQ((*c)->grid->width(), 3);
  // Versions continue where they were, and the next update is logged too.
  auto next = store_->Update("a", {MapChange::ForCell(0, 0, 1)}, uint64_t{3});
  ASSERT_TRUE(next.ok()) << next.status();
  EXPECT_EQ(next->snapshot->version, 4u);
  ASSERT_TRUE(Reopen().ok());
  EXPECT_EQ((*store_->Get("a"))->version, 4u);
}

TEST_F(DurableStoreTest, CheckpointReplacesSegmentsWithSnapshots) {
  ASSERT_TRUE(Reopen().ok());
  CreateAndUpdate();
  ASSERT_TRUE(store_->Create("gone", *Grid::Create(2, 2), false).ok());
  ASSERT_TRUE(durable_->Checkpoint().ok());
  ASSERT_TRUE(store_->Delete("gone").ok());
  ASSERT_TRUE(store_->Update("b", {MapChange::ForCell(0, 0, 3)}, {}).ok());
  ASSERT_TRUE(durable_->Checkpoint().ok());
  EXPECT_THAT(Files("map-"), ::testing::ElementsAre("map-a.snap", "map-b.snap"));
  EXPECT_EQ(Files("wal-").size(), 1u);  // only the active segment
  EXPECT_GE(durable_->stats().segments_deleted, 2);

  ASSERT_TRUE(Reopen().ok());
  EXPECT_EQ(durable_->recovery().snapshots, 2);
  EXPECT_EQ(durable_->recovery().records_replayed, 0);
  EXPECT_EQ((*store_->Get("a"))->version, 3u);
  EXPECT_EQ((*store_->Get("b"))->version, 2u);
  EXPECT_EQ((*store_->Get("b"))->grid->cost(0, 0), 3);
  EXPECT_FALSE(store_->Get("gone").ok());
}

TEST_F(DurableStoreTest, SmallSegmentLimitRotatesAndCompactsInTheBackground) {
  DurableStore::Options options;
  options.snapshot_log_bytes = 256;
  ASSERT_TRUE(Reopen(options).ok());
  ASSERT_TRUE(store_->Create("a", *Grid::Create(16, 16), false).ok());
  for (int i = 0; i < 200; ++i) {
    ASSERT_TRUE(store_->Update("a", {MapChange::ForCell(i % 16, i / 16 % 16, i % 250)}, {})
                    .ok());
  }
  ASSERT_TRUE(Reopen(options).ok());
  EXPECT_EQ((*store_->Get("a"))->version, 201u);
  EXPECT_EQ((*store_->Get("a"))->grid->cost(199 % 16, 199 / 16 % 16), 199);
}

TEST_F(DurableStoreTest, TornFinalRecordIsCutAwayAndReported) {
  ASSERT_TRUE(Reopen().ok());
  CreateAndUpdate();
  durable_.reset();
  const std::string segment = Files("wal-").back();
  const std::string clean = Read(segment);
  // Half of one more update record: an append the crash interrupted.
  const std::string record = wal::EncodeUpdated("a", 4, {MapChange::ForCell(0, 0, 1)});
  Write(segment, clean + record.substr(0, record.size() / 2));

  ASSERT_TRUE(Reopen().ok());
  EXPECT_THAT(durable_->recovery().torn_tail,
              HasSubstr(segment + ": offset " + std::to_string(clean.size())));
  EXPECT_EQ((*store_->Get("a"))->version, 3u);
  EXPECT_EQ(Read(segment).size(), clean.size());  // truncated on disk
  ASSERT_TRUE(store_->Update("a", {MapChange::ForCell(0, 0, 1)}, {}).ok());
  ASSERT_TRUE(Reopen().ok());
  EXPECT_TRUE(durable_->recovery().torn_tail.empty());
  EXPECT_EQ((*store_->Get("a"))->version, 4u);
}

TEST_F(DurableStoreTest, CorruptionInTheMiddleOfTheLogStopsOpen) {
  ASSERT_TRUE(Reopen().ok());
  CreateAndUpdate();
  durable_.reset();
  const std::string segment = Files("wal-").back();
  std::string bytes = Read(segment);
  // A byte inside the first record (the creation of "a").
  bytes[wal::kLogMagic.size() + wal::kFrameHeaderBytes + 20] ^= 0x01;
  Write(segment, bytes);
  const absl::Status status = Reopen();
  EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(status.message(), HasSubstr(segment));
  EXPECT_THAT(status.message(), HasSubstr("offset 8"));
}

TEST_F(DurableStoreTest, CorruptOrTruncatedSnapshotStopsOpen) {
  ASSERT_TRUE(Reopen().ok());
  CreateAndUpdate();
  ASSERT_TRUE(durable_->Checkpoint().ok());
  durable_.reset();
  const std::string good = Read("map-a.snap");

  Write("map-a.snap", good.substr(0, good.size() - 10));
  absl::Status status = Reopen();
  EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(status.message(), HasSubstr("map-a.snap"));
  EXPECT_THAT(status.message(), HasSubstr("cut short"));

  std::string flipped = good;
  flipped[flipped.size() - 5] ^= 0x01;
  Write("map-a.snap", flipped);
  status = Reopen();
  EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(status.message(), HasSubstr("map-a.snap"));
  EXPECT_THAT(status.message(), HasSubstr("CRC32C"));

  Write("map-a.snap", good);
  EXPECT_TRUE(Reopen().ok());
}

TEST_F(DurableStoreTest, MissingSegmentStopsOpen) {
  // Records 1-2 in the first segment, record 4 in the next: 3 is missing.
  fs::create_directories(dir_);
  std::string first(wal::kLogMagic);
  first += *wal::EncodeCreated("a", 1, *Grid::Create(4, 4));
  first += wal::EncodeUpdated("a", 2, {MapChange::ForCell(0, 0, 1)});
  std::string third(wal::kLogMagic);
  third += wal::EncodeUpdated("a", 4, {MapChange::ForCell(0, 0, 3)});
  Write("wal-00000000000000000001.log", first);
  Write("wal-00000000000000000004.log", third);
  const absl::Status status = Reopen();
  EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(status.message(), HasSubstr("wal-00000000000000000004.log starts at record 4"));
}

TEST_F(DurableStoreTest, SecondOpenOfTheSameDirectoryIsRefused) {
  ASSERT_TRUE(Reopen().ok());
  MapStore other(kMaxCells);
  DurableStore::Options options;
  options.dir = dir_.string();
  absl::StatusOr<std::unique_ptr<DurableStore>> second = DurableStore::Open(options, other);
  EXPECT_EQ(second.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(second.status().message(), HasSubstr("in use"));
}

TEST_F(DurableStoreTest, ConcurrentWritersAllSurvive) {
  ASSERT_TRUE(Reopen().ok());
  constexpr int kWriters = 8;
  constexpr int kUpdates = 40;
  for (int w = 0; w < kWriters; ++w) {
    ASSERT_TRUE(store_->Create(absl::StrCat("w", w), *Grid::Create(8, 8), false).ok());
  }
  std::vector<std::thread> threads;
  for (int w = 0; w < kWriters; ++w) {
    threads.emplace_back([this, w] {
      for (int i = 0; i < kUpdates; ++i) {
        // Half the writers share map w0, so one map's records interleave
        // with the others' and with themselves.
        const std::string name = w % 2 == 0 ? "w0" : absl::StrCat("w", w);
        ASSERT_TRUE(store_->Update(name, {MapChange::ForCell(i % 8, w, i)}, {}).ok());
      }
    });
  }
  for (std::thread& t : threads) t.join();
  const DurableStore::Stats stats = durable_->stats();
  EXPECT_EQ(stats.records, kWriters + kWriters * kUpdates);
  EXPECT_LE(stats.syncs, stats.records);
  ASSERT_TRUE(Reopen().ok());
  EXPECT_EQ((*store_->Get("w0"))->version, 1u + 4 * kUpdates);
  EXPECT_EQ((*store_->Get("w1"))->version, 1u + kUpdates);
  EXPECT_EQ((*store_->Get("w0"))->grid->cost((kUpdates - 1) % 8, 2), kUpdates - 1);
}

}  // namespace
}  // namespace pathd::server
