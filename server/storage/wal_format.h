// The byte formats of --data_dir: framed, CRC32C-checked records in log
// segments and snapshot files, and the replay of log records onto recovered
// maps. Pure functions over byte buffers (no I/O), so a fuzzer can drive
// them; server/storage/durable_store.h does the files.
#ifndef PATHD_SERVER_STORAGE_WAL_FORMAT_H_
#define PATHD_SERVER_STORAGE_WAL_FORMAT_H_

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/types/span.h"
#include "core/map/grid.h"
#include "pathd/storage/v1/records.pb.h"
#include "server/map_store.h"

namespace pathd::server::wal {

// First bytes of a log segment and of a snapshot file.
inline constexpr std::string_view kLogMagic = "PATHDLG1";
inline constexpr std::string_view kSnapshotMagic = "PATHDSN1";
inline constexpr std::string_view kCheckpointMagic = "PATHDCP1";
// A frame: payload length (uint32, little-endian), CRC32C of the payload
// (uint32, little-endian), then the payload, a serialised proto. A zero
// length is invalid, so a zero-filled tail never reads as a record.
inline constexpr size_t kFrameHeaderBytes = 8;
// Protobuf refuses messages of 2 GiB and more; a larger map cannot be stored.
inline constexpr size_t kMaxPayloadBytes = (size_t{1} << 31) - 1;

// CRC32C (Castagnoli, as iSCSI and ext4 use) of `data`, by ISA-L.
uint32_t Crc32c(std::string_view data);

// Appends a frame holding `payload` to *out. Precondition: 0 < size <=
// kMaxPayloadBytes.
void AppendFrame(std::string_view payload, std::string* out);

// Framed records, ready to append to a segment. RESOURCE_EXHAUSTED when the
// record would exceed kMaxPayloadBytes.
absl::StatusOr<std::string> EncodeCreated(std::string_view name, uint64_t version,
                                          const Grid& grid);
std::string EncodeUpdated(std::string_view name, uint64_t version,
                          absl::Span<const MapChange> changes);
std::string EncodeDeleted(std::string_view name, uint64_t last_version);

// A whole snapshot file (magic + one framed MapSnapshotRecord).
absl::StatusOr<std::string> EncodeSnapshot(uint64_t sequence, std::string_view name,
                                           uint64_t version, const Grid& grid);

// A whole CHECKPOINT file (magic + one framed CheckpointRecord).
std::string EncodeCheckpoint(const storage::v1::CheckpointRecord& checkpoint);

// Reads a CHECKPOINT file. DATA_LOSS naming the problem (bad magic,
// truncated, CRC mismatch, trailing bytes, unparsable record).
absl::StatusOr<storage::v1::CheckpointRecord> ParseCheckpoint(std::string_view bytes);

struct LogEntry {
  // Byte offset of the record's frame in the segment.
  uint64_t offset = 0;
  storage::v1::LogRecord record;
};

struct LogScan {
  // Every whole record, in order.
  std::vector<LogEntry> entries;
  // Bytes up to the end of the last whole record (at least the magic, unless
  // the magic itself is torn).
  uint64_t valid_bytes = 0;
  // Empty when the segment ends cleanly after a record; otherwise why the
  // bytes from valid_bytes on are not a record.
  std::string torn_tail;
  // The bad record claims more bytes than the segment holds (what a write
  // interrupted by a crash leaves), as opposed to one whose bytes are all
  // there but fail their CRC32C.
  bool tail_cut_short = false;
};

// Reads a log segment. A bad record (cut short, failing its CRC32C, or of
// length 0) is a torn tail only when no valid record starts anywhere after
// it, i.e. it runs to the end of the data: that is what a crash during an
// append leaves, and it is reported in torn_tail, not as an error. When a
// valid record follows, the bad one is corruption in the middle of the log,
// which replay must not skip: DATA_LOSS "offset N: ...". DATA_LOSS too for a
// bad magic.
absl::StatusOr<LogScan> ParseLogSegment(std::string_view bytes);

// The offset of the first valid log record (a frame whose length fits,
// whose CRC32C matches and whose payload is a LogRecord) starting in
// `bytes` at or after `from`; npos when there is none. O(bytes): a frame's
// CRC is computed only where its first payload bytes have the shape of a
// LogRecord whose length matches the frame's.
size_t FindValidRecord(std::string_view bytes, size_t from);

// Reads a snapshot file. DATA_LOSS naming the problem (bad magic, truncated,
// CRC mismatch, trailing bytes, unparsable record, inconsistent map).
absl::StatusOr<storage::v1::MapSnapshotRecord> ParseSnapshot(std::string_view bytes);

// The grid a MapImage holds; DATA_LOSS when its dimensions, cell count,
// resolution or origin are impossible.
absl::StatusOr<Grid> GridFromImage(const storage::v1::MapImage& image);

// The maps a data directory holds, rebuilt from snapshots and log records.
// Not thread-safe.
class Replayer {
 public:
  struct Map {
    Grid grid;
    uint64_t version = 0;
  };
  struct NameState {
    // Absent (deleted, or never created) when nullopt-like: has_map false.
    bool has_map = false;
    Map map;
    // Sequence of the snapshot file of this name; 0 = none.
    uint64_t snapshot_sequence = 0;
    // Sequence of the last record that touched this name (or the snapshot's).
    uint64_t last_sequence = 0;
  };

  // Takes a snapshot file's content as the starting point of its map.
  // DATA_LOSS for a second snapshot of the same name or a bad image.
  absl::Status AddSnapshot(const storage::v1::MapSnapshotRecord& snapshot);

  // Applies record `sequence` unless the map's snapshot already includes it.
  // DATA_LOSS naming the map when the record does not follow from the state
  // (an update or delete of a map that does not exist, a version that does
  // not continue the map's, a change off the map, a bad image): that means
  // records are missing or wrong, and the maps must not be served.
  absl::Status Apply(uint64_t sequence, const storage::v1::LogRecord& record);

  const std::map<std::string, NameState, std::less<>>& names() const { return names_; }
  std::map<std::string, NameState, std::less<>>& mutable_names() { return names_; }

 private:
  std::map<std::string, NameState, std::less<>> names_;
};

}  // namespace pathd::server::wal

#endif  // PATHD_SERVER_STORAGE_WAL_FORMAT_H_
