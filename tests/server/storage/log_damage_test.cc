// The log-damage table: each field (length, CRC, payload) of the first,
// a middle and the last record of the newest segment damaged in turn. The
// rule (docs/durability.md): a bad record is a torn tail, cut away after the
// segment is copied to FILE.corrupt, only when no valid record follows it;
// otherwise start-up stops with DATA_LOSS naming the file and offset and
// changes nothing. Regression test for "a corrupt length field early in the
// active log is taken for a torn tail".
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/map_store.h"
#include "server/storage/durable_store.h"
#include "server/storage/wal_format.h"

namespace pathd::server {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

constexpr int64_t kMaxCells = 1 << 20;
constexpr int kRecords = 21;  // a create and 20 updates of map "m"

std::string Read(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void Write(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << bytes;
}

// Every file of `dir` with its bytes.
std::map<std::string, std::string> Contents(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::directory_iterator(dir)) {
    files[entry.path().filename().string()] = Read(entry.path());
  }
  return files;
}

enum class Field { kLength, kCrc, kPayload };

class LogDamageTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pathd_log_damage_" + std::to_string(getpid()));
    fs::remove_all(dir_);
  }
  void TearDown() override {
    durable_.reset();
    fs::remove_all(dir_);
  }

  absl::Status Open() {
    durable_.reset();
    store_ = std::make_unique<MapStore>(kMaxCells);
    DurableStore::Options options;
    options.dir = dir_.string();
    options.snapshot_interval = absl::ZeroDuration();
    auto opened = DurableStore::Open(options, *store_);
    if (!opened.ok()) return opened.status();
    durable_ = *std::move(opened);
    return absl::OkStatus();
  }

  // A fresh directory whose only segment holds kRecords records; their
  // frame offsets in *offsets. Returns the segment's file name.
  std::string MakeLog(std::vector<size_t>* offsets) {
    fs::remove_all(dir_);
    EXPECT_TRUE(Open().ok());
    EXPECT_TRUE(store_->Create("m", *Grid::Create(16, 16), false).ok());
    for (int i = 1; i < kRecords; ++i) {
      EXPECT_TRUE(store_->Update("m", {MapChange::ForCell(i % 16, i / 16, 100 + i)}, {}).ok());
    }
    durable_.reset();
    std::string segment;
    for (const auto& entry : fs::directory_iterator(dir_)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("wal-", 0) == 0) segment = name;
    }
    const std::string bytes = Read(dir_ / segment);
    auto scan = wal::ParseLogSegment(bytes);
    EXPECT_TRUE(scan.ok());
    offsets->clear();
    for (const auto& entry : scan->entries) offsets->push_back(entry.offset);
    EXPECT_EQ(offsets->size(), static_cast<size_t>(kRecords));
    return segment;
  }

  fs::path dir_;
  std::unique_ptr<MapStore> store_;
  std::unique_ptr<DurableStore> durable_;
};

TEST_F(LogDamageTest, OnlyADamagedLastRecordIsCutAndNothingGoesWithoutACopy) {
  struct Position {
    const char* name;
    int record;
  };
  const Position positions[] = {{"first", 0}, {"middle", kRecords / 2}, {"last", kRecords - 1}};
  const Field fields[] = {Field::kLength, Field::kCrc, Field::kPayload};
  const char* field_names[] = {"length", "CRC", "payload"};
  for (const Position& position : positions) {
    for (const Field field : fields) {
      const std::string where = std::string(position.name) + " record, " +
                                field_names[static_cast<int>(field)] + " field";
      SCOPED_TRACE(where);
      std::vector<size_t> offsets;
      const std::string segment = MakeLog(&offsets);
      const size_t at = offsets[position.record];
      std::string bytes = Read(dir_ / segment);
      switch (field) {
        case Field::kLength:
          bytes[at + 3] = 0x7f;  // the length's high byte: ~2 GB claimed
          break;
        case Field::kCrc:
          bytes[at + 5] ^= 0x10;
          break;
        case Field::kPayload:
          bytes[at + wal::kFrameHeaderBytes + 3] ^= 0x01;
          break;
      }
      Write(dir_ / segment, bytes);
      const auto before = Contents(dir_);

      const absl::Status opened = Open();
      if (position.record != kRecords - 1) {
        // A valid record follows: corruption, never a torn tail.
        EXPECT_EQ(opened.code(), absl::StatusCode::kDataLoss) << opened;
        EXPECT_THAT(opened.message(), HasSubstr(segment));
        EXPECT_THAT(opened.message(), HasSubstr("offset " + std::to_string(at)));
        EXPECT_THAT(opened.message(), HasSubstr("valid record follows"));
        // Nothing deleted, truncated or compacted.
        EXPECT_EQ(Contents(dir_), before);
        continue;
      }
      ASSERT_TRUE(opened.ok()) << opened;
      const DurableStore::Recovery& recovery = durable_->recovery();
      EXPECT_THAT(recovery.torn_tail, HasSubstr(segment + ": offset " + std::to_string(at)));
      // Says what is known, not "never acknowledged".
      EXPECT_THAT(recovery.torn_tail,
                  HasSubstr(field == Field::kLength ? "incomplete" : "fails its check"));
      EXPECT_THAT(recovery.torn_tail, HasSubstr("change is lost"));
      const fs::path copy = dir_ / (segment + ".corrupt");
      EXPECT_EQ(recovery.torn_tail_copy, copy.string());
      EXPECT_EQ(Read(copy), bytes);
      auto m = store_->Get("m");
      ASSERT_TRUE(m.ok());
      EXPECT_EQ((*m)->version, static_cast<uint64_t>(kRecords - 1));
      // The copy outlives compaction and later starts.
      ASSERT_TRUE(durable_->Checkpoint().ok());
      ASSERT_TRUE(Open().ok());
      EXPECT_EQ(Read(copy), bytes);
      EXPECT_EQ((*store_->Get("m"))->version, static_cast<uint64_t>(kRecords - 1));
    }
  }
}

// The report's case: the high byte of the second record's length set to 0x7f
// in a 21-record log must not bring the map back at version 1.
TEST_F(LogDamageTest, CorruptLengthOfSecondRecordIsDataLossNotATornTail) {
  std::vector<size_t> offsets;
  const std::string segment = MakeLog(&offsets);
  std::string bytes = Read(dir_ / segment);
  bytes[offsets[1] + 3] = 0x7f;
  Write(dir_ / segment, bytes);
  const absl::Status opened = Open();
  EXPECT_EQ(opened.code(), absl::StatusCode::kDataLoss) << opened;
  EXPECT_EQ(Read(dir_ / segment), bytes);
}

// A crash's torn append: a prefix of a record, or one followed by zeros.
TEST_F(LogDamageTest, TornAppendIsCutWithACopy) {
  const std::string record = wal::EncodeUpdated("m", kRecords + 1, {MapChange::ForCell(0, 0, 1)});
  for (const std::string& tail :
       {record.substr(0, 5), record.substr(0, record.size() - 1),
        record.substr(0, 12) + std::string(record.size(), '\0')}) {
    // A fresh directory each time: the start-up compaction of the previous
    // round may already have replaced the segment by snapshots.
    std::vector<size_t> offsets;
    const std::string segment = MakeLog(&offsets);
    const std::string clean = Read(dir_ / segment);
    Write(dir_ / segment, clean + tail);
    ASSERT_TRUE(Open().ok());
    EXPECT_EQ((*store_->Get("m"))->version, static_cast<uint64_t>(kRecords));
    EXPECT_EQ(Read(dir_ / (segment + ".corrupt")), clean + tail);
    durable_.reset();
  }
}

}  // namespace
}  // namespace pathd::server
