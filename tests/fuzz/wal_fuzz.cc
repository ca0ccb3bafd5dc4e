// Fuzz target: the --data_dir file readers (server/storage/wal_format.h). Every input
// is read as a log segment and as a snapshot file, as start-up reads them.
// Besides "no crash, no UB": a segment that parses reports offsets inside the
// input in increasing order and a valid prefix no longer than the input,
// and its records replay into a Replayer either cleanly or with DATA_LOSS
// (never another code, never a crash); a snapshot that parses has a grid
// GridFromImage accepts, and the Replayer takes it as a starting point.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "absl/status/status.h"
#include "server/storage/wal_format.h"
#include "tests/fuzz/fuzz_check.h"

namespace pathd::server::wal {
namespace {

void CheckLog(std::string_view bytes) {
  absl::StatusOr<LogScan> scan = ParseLogSegment(bytes);
  if (!scan.ok()) {
    PATHD_FUZZ_CHECK(scan.status().code() == absl::StatusCode::kDataLoss,
                     "segment errors are DATA_LOSS");
    return;
  }
  PATHD_FUZZ_CHECK(scan->valid_bytes <= bytes.size(), "valid prefix");
  uint64_t previous = 0;
  for (const LogEntry& entry : scan->entries) {
    PATHD_FUZZ_CHECK(entry.offset >= kLogMagic.size() && entry.offset < scan->valid_bytes,
                     "record offset inside the valid prefix");
    PATHD_FUZZ_CHECK(entry.offset > previous || previous == 0, "offsets increase");
    previous = entry.offset;
  }
  // The prefix alone parses to the same records and no torn tail.
  absl::StatusOr<LogScan> prefix = ParseLogSegment(bytes.substr(0, scan->valid_bytes));
  PATHD_FUZZ_CHECK(prefix.ok(), "the valid prefix parses");
  PATHD_FUZZ_CHECK(prefix->entries.size() == scan->entries.size(), "same records");
  Replayer replayer;
  uint64_t sequence = 0;
  for (const LogEntry& entry : scan->entries) {
    const absl::Status applied = replayer.Apply(++sequence, entry.record);
    if (!applied.ok()) {
      PATHD_FUZZ_CHECK(applied.code() == absl::StatusCode::kDataLoss,
                       "replay errors are DATA_LOSS");
      return;
    }
  }
}

void CheckSnapshot(std::string_view bytes) {
  absl::StatusOr<storage::v1::MapSnapshotRecord> snapshot = ParseSnapshot(bytes);
  if (!snapshot.ok()) {
    PATHD_FUZZ_CHECK(snapshot.status().code() == absl::StatusCode::kDataLoss,
                     "snapshot errors are DATA_LOSS");
    return;
  }
  PATHD_FUZZ_CHECK(GridFromImage(snapshot->map()).ok(),
                   "a parsed snapshot holds a valid grid");
  Replayer replayer;
  PATHD_FUZZ_CHECK(replayer.AddSnapshot(*snapshot).ok(),
                   "a parsed snapshot starts a replay");
}

}  // namespace
}  // namespace pathd::server::wal

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  pathd::server::wal::CheckLog(bytes);
  pathd::server::wal::CheckSnapshot(bytes);
  return 0;
}
