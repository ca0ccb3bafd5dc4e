// The --data_dir byte formats: CRC32C, frames, log segments (torn and
// corrupt tails, corruption in the middle), snapshots and replay.
#include "server/storage/wal_format.h"

#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace pathd::server::wal {
namespace {

using ::testing::HasSubstr;

Grid MakeGrid(int w, int h, uint8_t fill) {
  Grid grid = *Grid::Create(w, h, fill);
  grid.set_resolution(0.5);
  grid.set_origin(GridOrigin{1.0, -2.0, 0.25});
  return grid;
}

// A segment with: create "m" (4 x 3) v1, update v2, update v3.
std::string ThreeRecordSegment(std::vector<size_t>* record_offsets = nullptr) {
  std::string segment(kLogMagic);
  auto add = [&](const std::string& framed) {
    if (record_offsets != nullptr) record_offsets->push_back(segment.size());
    segment += framed;
  };
  add(*EncodeCreated("m", 1, MakeGrid(4, 3, 0)));
  add(EncodeUpdated("m", 2, {MapChange::ForRect(0, 0, 1, 1, 254)}));
  add(EncodeUpdated("m", 3, {MapChange::ForCell(3, 2, 7)}));
  return segment;
}

TEST(Crc32cTest, MatchesTheStandardCheckValue) {
  // The CRC-32C check value (RFC 3720 / the Castagnoli catalogue entry).
  EXPECT_EQ(Crc32c("123456789"), 0xe3069283u);
  EXPECT_EQ(Crc32c(""), 0u);
}

TEST(LogSegmentTest, ReadsEveryRecordOfACleanSegment) {
  std::vector<size_t> offsets;
  const std::string segment = ThreeRecordSegment(&offsets);
  absl::StatusOr<LogScan> scan = ParseLogSegment(segment);
  ASSERT_TRUE(scan.ok()) << scan.status();
  ASSERT_EQ(scan->entries.size(), 3u);
  EXPECT_TRUE(scan->torn_tail.empty());
  EXPECT_EQ(scan->valid_bytes, segment.size());
  EXPECT_EQ(scan->entries[1].offset, offsets[1]);
  EXPECT_EQ(scan->entries[0].record.created().name(), "m");
  EXPECT_EQ(scan->entries[2].record.updated().version(), 3u);
  EXPECT_EQ(scan->entries[2].record.updated().fills(0).cost(), 7u);
}

TEST(LogSegmentTest, EveryCutOfTheLastRecordIsATornTail) {
  std::vector<size_t> offsets;
  const std::string segment = ThreeRecordSegment(&offsets);
  for (size_t cut = offsets[2] + 1; cut < segment.size(); ++cut) {
    absl::StatusOr<LogScan> scan = ParseLogSegment(segment.substr(0, cut));
    ASSERT_TRUE(scan.ok()) << "cut at " << cut << ": " << scan.status();
    EXPECT_EQ(scan->entries.size(), 2u) << cut;
    EXPECT_EQ(scan->valid_bytes, offsets[2]) << cut;
    EXPECT_THAT(scan->torn_tail, HasSubstr("cut short")) << cut;
  }
}

TEST(LogSegmentTest, CorruptFinalRecordIsATornTail) {
  std::vector<size_t> offsets;
  std::string segment = ThreeRecordSegment(&offsets);
  segment.back() ^= 0x40;
  absl::StatusOr<LogScan> scan = ParseLogSegment(segment);
  ASSERT_TRUE(scan.ok()) << scan.status();
  EXPECT_EQ(scan->entries.size(), 2u);
  EXPECT_EQ(scan->valid_bytes, offsets[2]);
  EXPECT_THAT(scan->torn_tail, HasSubstr("CRC32C"));
}

TEST(LogSegmentTest, ZeroFilledTailIsATornTail) {
  // What a file system can leave when the size reached the disk before data.
  const std::string clean = ThreeRecordSegment();
  absl::StatusOr<LogScan> scan = ParseLogSegment(clean + std::string(100, '\0'));
  ASSERT_TRUE(scan.ok()) << scan.status();
  EXPECT_EQ(scan->entries.size(), 3u);
  EXPECT_EQ(scan->valid_bytes, clean.size());
  EXPECT_THAT(scan->torn_tail, HasSubstr("length is 0"));
}

TEST(LogSegmentTest, CorruptionInTheMiddleIsAnErrorNamingTheOffset) {
  std::vector<size_t> offsets;
  std::string segment = ThreeRecordSegment(&offsets);
  segment[offsets[1] + kFrameHeaderBytes + 2] ^= 0x01;
  absl::StatusOr<LogScan> scan = ParseLogSegment(segment);
  ASSERT_EQ(scan.status().code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(scan.status().message(),
              HasSubstr(absl::StrCat("offset ", offsets[1], ": ")));
  EXPECT_THAT(scan.status().message(), HasSubstr("CRC32C"));
}

TEST(LogSegmentTest, BadMagicIsAnError) {
  std::string segment = ThreeRecordSegment();
  segment[0] = 'X';
  EXPECT_EQ(ParseLogSegment(segment).status().code(), absl::StatusCode::kDataLoss);
  EXPECT_EQ(ParseLogSegment("nope").status().code(), absl::StatusCode::kDataLoss);
}

TEST(LogSegmentTest, TornMagicIsAnEmptySegment) {
  absl::StatusOr<LogScan> scan = ParseLogSegment(kLogMagic.substr(0, 3));
  ASSERT_TRUE(scan.ok()) << scan.status();
  EXPECT_TRUE(scan->entries.empty());
  EXPECT_EQ(scan->valid_bytes, 0u);
  EXPECT_FALSE(scan->torn_tail.empty());
}

TEST(LogSegmentTest, ValidCrcOverGarbageIsAnError) {
  std::string segment(kLogMagic);
  AppendFrame("\xff\xff\xff", &segment);  // not a protobuf message
  EXPECT_EQ(ParseLogSegment(segment).status().code(), absl::StatusCode::kDataLoss);
}

TEST(SnapshotTest, RoundTrips) {
  const Grid grid = MakeGrid(5, 2, 9);
  absl::StatusOr<std::string> file = EncodeSnapshot(42, "map_a", 7, grid);
  ASSERT_TRUE(file.ok());
  absl::StatusOr<storage::v1::MapSnapshotRecord> snapshot = ParseSnapshot(*file);
  ASSERT_TRUE(snapshot.ok()) << snapshot.status();
  EXPECT_EQ(snapshot->sequence(), 42u);
  EXPECT_EQ(snapshot->map().version(), 7u);
  absl::StatusOr<Grid> back = GridFromImage(snapshot->map());
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back->cells(), grid.cells());
  EXPECT_EQ(back->resolution(), 0.5);
  EXPECT_EQ(back->origin().yaw, 0.25);
}

TEST(SnapshotTest, EveryTruncationAndFlippedByteIsDetected) {
  const std::string file = *EncodeSnapshot(3, "m", 2, MakeGrid(3, 3, 1));
  for (size_t cut = 0; cut < file.size(); ++cut) {
    EXPECT_EQ(ParseSnapshot(file.substr(0, cut)).status().code(),
              absl::StatusCode::kDataLoss)
        << "cut at " << cut;
  }
  for (size_t i = 0; i < file.size(); ++i) {
    std::string flipped = file;
    flipped[i] ^= 0x10;
    EXPECT_FALSE(ParseSnapshot(flipped).ok()) << "byte " << i;
  }
  EXPECT_THAT(ParseSnapshot(file + "x").status().message(), HasSubstr("after"));
}

TEST(GridFromImageTest, RefusesInconsistentImages) {
  storage::v1::MapImage image;
  image.set_name("m");
  image.set_width(2);
  image.set_height(2);
  image.set_resolution(1.0);
  image.set_cells("abc");
  EXPECT_THAT(GridFromImage(image).status().message(), HasSubstr("holds 3 cells"));
  image.set_cells("abcd");
  EXPECT_TRUE(GridFromImage(image).ok());
  image.set_resolution(0.0);
  EXPECT_FALSE(GridFromImage(image).ok());
  image.set_resolution(1.0);
  image.set_name("../etc");
  EXPECT_FALSE(GridFromImage(image).ok());
}

absl::Status ApplyAll(Replayer& replayer, const std::string& segment, uint64_t first) {
  absl::StatusOr<LogScan> scan = ParseLogSegment(segment);
  if (!scan.ok()) return scan.status();
  for (size_t i = 0; i < scan->entries.size(); ++i) {
    if (absl::Status s = replayer.Apply(first + i, scan->entries[i].record); !s.ok()) {
      return s;
    }
  }
  return absl::OkStatus();
}

TEST(ReplayerTest, RebuildsTheMapAndItsVersion) {
  Replayer replayer;
  ASSERT_TRUE(ApplyAll(replayer, ThreeRecordSegment(), 1).ok());
  const Replayer::NameState& m = replayer.names().at("m");
  ASSERT_TRUE(m.has_map);
  EXPECT_EQ(m.map.version, 3u);
  EXPECT_EQ(m.last_sequence, 3u);
  EXPECT_EQ(m.map.grid.cost(1, 1), 254);
  EXPECT_EQ(m.map.grid.cost(2, 1), 0);
  EXPECT_EQ(m.map.grid.cost(3, 2), 7);
}

TEST(ReplayerTest, SkipsWhatTheSnapshotIncludes) {
  Replayer replayer;
  // A snapshot taken after record 2 (version 2), holding a marker cell.
  Grid at_two = MakeGrid(4, 3, 0);
  at_two.set_cost(0, 0, 254);
  at_two.set_cost(1, 1, 254);
  at_two.set_cost(2, 2, 99);
  ASSERT_TRUE(replayer.AddSnapshot(*ParseSnapshot(*EncodeSnapshot(2, "m", 2, at_two))).ok());
  ASSERT_TRUE(ApplyAll(replayer, ThreeRecordSegment(), 1).ok());
  const Replayer::NameState& m = replayer.names().at("m");
  EXPECT_EQ(m.map.version, 3u);
  EXPECT_EQ(m.map.grid.cost(2, 2), 99);  // from the snapshot, not replaced
  EXPECT_EQ(m.map.grid.cost(3, 2), 7);   // record 3 applied on top
}

TEST(ReplayerTest, RefusesRecordsThatDoNotFollow) {
  Replayer replayer;
  storage::v1::LogRecord update;
  update.mutable_updated()->set_name("m");
  update.mutable_updated()->set_version(2);
  EXPECT_THAT(replayer.Apply(1, update).message(), HasSubstr("does not exist"));

  ASSERT_TRUE(ApplyAll(replayer, ThreeRecordSegment(), 1).ok());
  update.mutable_updated()->set_version(5);  // 4 is missing
  EXPECT_THAT(replayer.Apply(4, update).message(),
              HasSubstr("version 5, but the map is at version 3"));

  storage::v1::LogRecord off_map;
  off_map.mutable_updated()->set_name("m");
  off_map.mutable_updated()->set_version(4);
  storage::v1::CellFill* fill = off_map.mutable_updated()->add_fills();
  fill->set_x_max(4);  // the map is 4 wide
  EXPECT_THAT(replayer.Apply(4, off_map).message(), HasSubstr("not a valid change"));
}

TEST(ReplayerTest, DeleteAndRecreateStartsAgainAtVersionOne) {
  Replayer replayer;
  ASSERT_TRUE(ApplyAll(replayer, ThreeRecordSegment(), 1).ok());
  std::string more(kLogMagic);
  more += EncodeDeleted("m", 3);
  more += *EncodeCreated("m", 1, MakeGrid(2, 2, 5));
  ASSERT_TRUE(ApplyAll(replayer, more, 4).ok());
  const Replayer::NameState& m = replayer.names().at("m");
  EXPECT_EQ(m.map.version, 1u);
  EXPECT_EQ(m.map.grid.width(), 2);

  std::string bad(kLogMagic);
  bad += EncodeDeleted("m", 9);
  EXPECT_EQ(ApplyAll(replayer, bad, 6).code(), absl::StatusCode::kDataLoss);
}

}  // namespace
}  // namespace pathd::server::wal
