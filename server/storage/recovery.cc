// DurableStore start-up: rebuilds the maps from CHECKPOINT, the snapshots and
// the log segments, cutting a torn tail (after keeping a copy) and removing
// what an interrupted checkpoint left behind.
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <map>
#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/str_format.h"
#include "core/status_macros.h"
#include "server/storage/data_files.h"
#include "server/storage/durable_store.h"
#include "server/storage/wal_format.h"
#include "spdlog/spdlog.h"

namespace pathd::server {
namespace {

namespace fs = std::filesystem;
using namespace data_files;  // NOLINT(build/namespaces): this file's vocabulary

// What is known about a bad last record with nothing valid after it.
std::string TornTailMeaning(bool cut_short) {
  return cut_short
             ? "the record is incomplete, as a write interrupted by a crash leaves it "
               "(such a write was never acknowledged); if the file was cut short "
               "since, an acknowledged change is lost"
             : "the record is complete but fails its check, as a write interrupted by "
               "a power loss or damage after the write leaves it; if it was "
               "acknowledged, its change is lost";
}

}  // namespace

absl::StatusOr<std::string> DurableStore::KeepCopy(const std::string& path) {
  PATHD_ASSIGN_OR_RETURN(const std::string bytes, ReadWholeFile(path));
  std::string copy = path + kCorruptSuffix;
  for (int n = 1; fs::exists(copy); ++n) {
    copy = absl::StrFormat("%s%s.%d", path, kCorruptSuffix, n);
  }
  const int fd = open(copy.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) return IoError("cannot create", copy);
  absl::Status status = WriteAll(fd, bytes, copy);
  if (status.ok() && fsync(fd) != 0) status = IoError("cannot sync", copy);
  close(fd);
  if (status.ok()) status = SyncDir();
  if (!status.ok()) {
    unlink(copy.c_str());
    return status;
  }
  return copy;
}

absl::Status DurableStore::Recover() {
  std::vector<std::string> snapshot_files;
  std::vector<uint64_t> segments;
  bool has_checkpoint = false;
  std::error_code ec;
  for (fs::directory_iterator it(options_.dir, ec), end; !ec && it != end;
       it.increment(ec)) {
    const std::string file = it->path().filename().string();
    if (absl::EndsWith(file, kTempSuffix)) {
      // A snapshot or CHECKPOINT whose writer died before the rename: never
      // part of the state.
      fs::remove(it->path(), ec);
      ec.clear();
    } else if (absl::StartsWith(file, kSnapshotPrefix) &&
               absl::EndsWith(file, kSnapshotSuffix)) {
      snapshot_files.push_back(file);
    } else if (const uint64_t first = SegmentFirst(file); first != 0) {
      segments.push_back(first);
    } else if (file == kCheckpointFile) {
      has_checkpoint = true;
    }
  }
  if (ec) {
    return absl::InternalError(absl::StrFormat("cannot list --data_dir %s: %s",
                                               options_.dir, ec.message()));
  }
  std::sort(snapshot_files.begin(), snapshot_files.end());
  std::sort(segments.begin(), segments.end());

  // Replay starts at `start`; the snapshots `listed` hold the state before it.
  uint64_t start = 0;
  std::map<std::string, uint64_t, std::less<>> listed;
  if (has_checkpoint) {
    const std::string path = Path(kCheckpointFile);
    PATHD_ASSIGN_OR_RETURN(const std::string bytes, ReadWholeFile(path));
    absl::StatusOr<storage::v1::CheckpointRecord> checkpoint = wal::ParseCheckpoint(bytes);
    if (!checkpoint.ok()) {
      return absl::DataLossError(
          absl::StrFormat("%s: %s", path, checkpoint.status().message()));
    }
    start = checkpoint->first_sequence();
    for (const storage::v1::SnapshotRef& ref : checkpoint->snapshots()) {
      listed[ref.name()] = ref.sequence();
    }
  }

  wal::Replayer replayer;
  std::vector<std::string> leftovers;
  uint64_t newest_snapshot = 0;
  std::string newest_snapshot_file;
  for (const std::string& file : snapshot_files) {
    const std::string path = Path(file);
    PATHD_ASSIGN_OR_RETURN(const std::string bytes, ReadWholeFile(path));
    absl::StatusOr<storage::v1::MapSnapshotRecord> snapshot = wal::ParseSnapshot(bytes);
    if (!snapshot.ok()) {
      return absl::DataLossError(
          absl::StrFormat("snapshot %s: %s", path, snapshot.status().message()));
    }
    const std::string& name = snapshot->map().name();
    if (SnapshotName(name) != file) {
      return absl::DataLossError(
          absl::StrFormat("snapshot %s holds map '%s'", path, name));
    }
    if (has_checkpoint) {
      auto it = listed.find(name);
      if (it == listed.end() && snapshot->sequence() < start) {
        // The map was deleted before the checkpoint, which crashed before
        // removing this file.
        leftovers.push_back(path);
        continue;
      }
      if (it != listed.end()) {
        if (snapshot->sequence() < it->second) {
          return absl::DataLossError(absl::StrFormat(
              "snapshot %s includes record %d, but %s lists it at record %d", path,
              snapshot->sequence(), Path(kCheckpointFile), it->second));
        }
        listed.erase(it);
      }
    }
    if (absl::Status added = replayer.AddSnapshot(*snapshot); !added.ok()) {
      return absl::DataLossError(
          absl::StrFormat("snapshot %s: %s", path, added.message()));
    }
    if (snapshot->sequence() > newest_snapshot) {
      newest_snapshot = snapshot->sequence();
      newest_snapshot_file = path;
    }
    ++recovery_.snapshots;
  }
  if (!listed.empty()) {
    return absl::DataLossError(absl::StrFormat(
        "%s lists snapshot %s (record %d), which is missing", Path(kCheckpointFile),
        Path(SnapshotName(listed.begin()->first)), listed.begin()->second));
  }

  // Segments before `start` are wholly included in the snapshots: the
  // checkpoint that wrote CHECKPOINT crashed before removing them.
  const auto live_begin = std::lower_bound(segments.begin(), segments.end(), start);
  for (auto it = segments.begin(); it != live_begin; ++it) {
    leftovers.push_back(Path(SegmentName(*it)));
  }
  segments.erase(segments.begin(), live_begin);
  if (has_checkpoint && !segments.empty() && segments.front() != start) {
    return absl::DataLossError(absl::StrFormat(
        "log segment %s starts at record %d, but %s says the log continues at record "
        "%d: records are missing",
        Path(SegmentName(segments.front())), segments.front(), Path(kCheckpointFile),
        start));
  }

  // The sequence number the next record gets: one past the last record of
  // the newest segment.
  uint64_t next = 0;
  bool last_empty = false;
  for (size_t i = 0; i < segments.size(); ++i) {
    const std::string path = Path(SegmentName(segments[i]));
    if (next != 0 && segments[i] != next) {
      return absl::DataLossError(absl::StrFormat(
          "log segment %s starts at record %d, but the segment before it ends at "
          "record %d: records are missing",
          path, segments[i], next - 1));
    }
    PATHD_ASSIGN_OR_RETURN(const std::string bytes, ReadWholeFile(path));
    absl::StatusOr<wal::LogScan> scan = wal::ParseLogSegment(bytes);
    if (!scan.ok()) {
      return absl::DataLossError(
          absl::StrFormat("log segment %s: %s", path, scan.status().message()));
    }
    if (!scan->torn_tail.empty()) {
      if (i + 1 != segments.size()) {
        // Only the newest segment is ever appended to; older ones were
        // complete and synced before the next one started.
        return absl::DataLossError(absl::StrFormat(
            "log segment %s: offset %d: %s, but newer segments follow", path,
            scan->valid_bytes, scan->torn_tail));
      }
      // Nothing valid follows the bad record, so nothing after it can be
      // replayed; the segment is kept as it was before cutting it.
      absl::StatusOr<std::string> copy = KeepCopy(path);
      if (!copy.ok()) {
        return absl::InternalError(absl::StrFormat(
            "log segment %s: offset %d: %s; cannot keep a copy before cutting the "
            "log there: %s",
            path, scan->valid_bytes, scan->torn_tail, copy.status().message()));
      }
      recovery_.torn_tail = absl::StrFormat(
          "%s: offset %d: %s, with nothing valid after it: %s", path, scan->valid_bytes,
          scan->torn_tail, TornTailMeaning(scan->tail_cut_short));
      recovery_.torn_tail_copy = *copy;
      spdlog::warn("log segment {}; cutting the log there (the segment as it was is "
                   "kept in {})",
                   recovery_.torn_tail, *copy);
      if (truncate(path.c_str(), static_cast<off_t>(scan->valid_bytes)) != 0) {
        return IoError("cannot truncate", path);
      }
    }
    for (size_t k = 0; k < scan->entries.size(); ++k) {
      const uint64_t sequence = segments[i] + k;
      if (absl::Status applied = replayer.Apply(sequence, scan->entries[k].record);
          !applied.ok()) {
        return absl::DataLossError(absl::StrFormat("log segment %s: offset %d (record %d): %s",
                                                   path, scan->entries[k].offset, sequence,
                                                   applied.message()));
      }
    }
    recovery_.records_replayed += static_cast<int64_t>(scan->entries.size());
    next = segments[i] + scan->entries.size();
    last_empty = scan->entries.empty();
  }
  recovery_.segments = static_cast<int>(segments.size());
  if (next == 0) next = std::max(start, newest_snapshot + 1);
  if (newest_snapshot >= next) {
    return absl::DataLossError(absl::StrFormat(
        "snapshot %s includes record %d, but the log ends at record %d: log segments "
        "are missing",
        newest_snapshot_file, newest_snapshot, next - 1));
  }

  // Restored before taking mu_: the store calls Append (mu_) under its own
  // lock, so mu_ is never held while calling into the store.
  std::map<std::string, NameState, std::less<>> names;
  for (auto& [name, state] : replayer.mutable_names()) {
    NameState& kept = names[name];
    kept.last_sequence = state.last_sequence;
    kept.snapshot_sequence = state.snapshot_sequence;
    if (!state.has_map) continue;
    absl::StatusOr<std::shared_ptr<const MapSnapshot>> restored =
        store_.Restore(name, std::move(state.map.grid), state.map.version);
    if (!restored.ok()) {
      return absl::Status(restored.status().code(),
                          absl::StrFormat("recovering map '%s' from --data_dir %s: %s",
                                          name, options_.dir, restored.status().message()));
    }
    kept.current = *std::move(restored);
    ++recovery_.maps;
  }
  // Not part of the state CHECKPOINT describes (which is durable), so
  // removing them changes nothing a later start would recover.
  for (const std::string& path : leftovers) {
    if (unlink(path.c_str()) != 0 && errno != ENOENT) return IoError("cannot remove", path);
    ++recovery_.leftovers_removed;
  }
  if (!leftovers.empty()) PATHD_RETURN_IF_ERROR(SyncDir());
  // A segment the last run started but never appended to is reused.
  if (last_empty && segments.back() == next) {
    const std::string path = Path(SegmentName(next));
    if (unlink(path.c_str()) != 0) return IoError("cannot remove", path);
    segments.pop_back();
  }
  {
    absl::MutexLock lock(&mu_);
    names_ = std::move(names);
    sealed_segments_ = segments;
    // Older segments are compacted away right after start-up, so the next
    // start replays only what changed since.
    checkpoint_wanted_ = !sealed_segments_.empty();
    next_sequence_ = next;
    durable_sequence_ = next - 1;
    segment_first_ = next;
  }
  spdlog::info("--data_dir {}: recovered {} map(s) from {} snapshot(s) and {} log "
               "record(s) in {} segment(s)",
               options_.dir, recovery_.maps, recovery_.snapshots,
               recovery_.records_replayed, recovery_.segments);
  return StartSegment(next);
}

}  // namespace pathd::server
