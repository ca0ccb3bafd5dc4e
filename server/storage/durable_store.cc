// DurableStore: log segments, group commit, snapshots and recovery.
#include "server/storage/durable_store.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/status_macros.h"
#include "server/storage/wal_format.h"
#include "spdlog/spdlog.h"

namespace pathd::server {
namespace {

namespace fs = std::filesystem;

// char arrays: they convert to both std:: and Debian's absl::string_view.
constexpr char kSegmentPrefix[] = "wal-";
constexpr char kSegmentSuffix[] = ".log";
constexpr char kSnapshotPrefix[] = "map-";
constexpr char kSnapshotSuffix[] = ".snap";
constexpr char kTempSuffix[] = ".tmp";

std::string SegmentName(uint64_t first_sequence) {
  return absl::StrFormat("%s%020d%s", kSegmentPrefix, first_sequence, kSegmentSuffix);
}

std::string SnapshotName(std::string_view map) {
  return absl::StrCat(kSnapshotPrefix, std::string(map), kSnapshotSuffix);
}

absl::Status IoError(std::string_view what, const std::string& path) {
  return absl::InternalError(
      absl::StrFormat("%s %s: %s", what, path, std::strerror(errno)));
}

absl::StatusOr<std::string> ReadWholeFile(const std::string& path) {
  const int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return IoError("cannot open", path);
  std::string bytes;
  char buffer[1 << 16];
  for (;;) {
    const ssize_t n = read(fd, buffer, sizeof(buffer));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      absl::Status error = IoError("cannot read", path);
      close(fd);
      return error;
    }
    if (n == 0) break;
    bytes.append(buffer, static_cast<size_t>(n));
  }
  close(fd);
  return bytes;
}

absl::Status WriteAll(int fd, std::string_view data, const std::string& path) {
  while (!data.empty()) {
    const ssize_t n = write(fd, data.data(), data.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return IoError("cannot write", path);
    data.remove_prefix(static_cast<size_t>(n));
  }
  return absl::OkStatus();
}

// The first sequence number a segment file name holds; 0 for other names.
uint64_t SegmentFirst(const std::string& file) {
  if (!absl::StartsWith(file, kSegmentPrefix) || !absl::EndsWith(file, kSegmentSuffix)) {
    return 0;
  }
  const absl::string_view digits = absl::string_view(file).substr(
      sizeof(kSegmentPrefix) - 1,
      file.size() - (sizeof(kSegmentPrefix) - 1) - (sizeof(kSegmentSuffix) - 1));
  uint64_t first = 0;
  if (digits.size() != 20 || !absl::SimpleAtoi(digits, &first)) return 0;
  return first;
}

}  // namespace

DurableStore::DurableStore(Options options, MapStore& store)
    : options_(std::move(options)), store_(store) {}

DurableStore::~DurableStore() {
  {
    absl::MutexLock lock(&mu_);
    stopping_ = true;
  }
  if (snapshot_thread_.joinable()) snapshot_thread_.join();
  store_.SetJournal(nullptr);
  absl::MutexLock lock(&mu_);
  spdlog::info("--data_dir {}: {} record(s) in {} sync(s), {} snapshot(s) written, {} "
               "segment(s) deleted",
               options_.dir, stats_.records, stats_.syncs, stats_.snapshots_written,
               stats_.segments_deleted);
  if (segment_fd_ >= 0) close(segment_fd_);
  if (dir_fd_ >= 0) close(dir_fd_);
  // Closing the descriptor releases the flock.
  if (lock_fd_ >= 0) close(lock_fd_);
}

std::string DurableStore::Path(std::string_view file) const {
  return (fs::path(options_.dir) / std::string(file)).string();
}

absl::StatusOr<std::unique_ptr<DurableStore>> DurableStore::Open(Options options,
                                                                 MapStore& store) {
  if (store.size() != 0) {
    return absl::FailedPreconditionError("--data_dir must be opened on an empty store");
  }
  std::error_code ec;
  fs::create_directories(options.dir, ec);
  if (ec) {
    return absl::InternalError(absl::StrFormat("cannot create --data_dir %s: %s",
                                               options.dir, ec.message()));
  }
  std::unique_ptr<DurableStore> durable(new DurableStore(std::move(options), store));
  const std::string& dir = durable->options_.dir;
  durable->dir_fd_ = open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (durable->dir_fd_ < 0) return IoError("cannot open --data_dir", dir);
  const std::string lock_path = durable->Path("LOCK");
  durable->lock_fd_ = open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (durable->lock_fd_ < 0) return IoError("cannot open", lock_path);
  if (flock(durable->lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    if (errno == EWOULDBLOCK) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "--data_dir %s is in use by another process (%s is locked)", dir, lock_path));
    }
    return IoError("cannot lock", lock_path);
  }
  PATHD_RETURN_IF_ERROR(durable->Recover());
  store.SetJournal(durable.get());
  DurableStore* self = durable.get();
  durable->snapshot_thread_ = std::thread([self] { self->SnapshotLoop(); });
  return durable;
}

absl::Status DurableStore::Recover() {
  std::vector<std::string> snapshot_files;
  std::vector<uint64_t> segments;
  std::error_code ec;
  for (fs::directory_iterator it(options_.dir, ec), end; !ec && it != end;
       it.increment(ec)) {
    const std::string file = it->path().filename().string();
    if (absl::EndsWith(file, kTempSuffix)) {
      // A snapshot whose writer died before the rename: never part of the state.
      fs::remove(it->path(), ec);
      ec.clear();
    } else if (absl::StartsWith(file, kSnapshotPrefix) &&
               absl::EndsWith(file, kSnapshotSuffix)) {
      snapshot_files.push_back(file);
    } else if (const uint64_t first = SegmentFirst(file); first != 0) {
      segments.push_back(first);
    }
  }
  if (ec) {
    return absl::InternalError(absl::StrFormat("cannot list --data_dir %s: %s",
                                               options_.dir, ec.message()));
  }
  std::sort(snapshot_files.begin(), snapshot_files.end());
  std::sort(segments.begin(), segments.end());

  wal::Replayer replayer;
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
    if (SnapshotName(snapshot->map().name()) != file) {
      return absl::DataLossError(absl::StrFormat("snapshot %s holds map '%s'", path,
                                                 snapshot->map().name()));
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
      recovery_.torn_tail =
          absl::StrFormat("%s: offset %d: %s", path, scan->valid_bytes, scan->torn_tail);
      spdlog::warn("log segment {}: offset {}: {}; cutting the log there (a write the "
                   "crash interrupted, never acknowledged)",
                   path, scan->valid_bytes, scan->torn_tail);
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
  if (next == 0) next = newest_snapshot + 1;
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

absl::Status DurableStore::StartSegment(uint64_t first_sequence) {
  const std::string path = Path(SegmentName(first_sequence));
  const int fd = open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) return IoError("cannot create", path);
  absl::Status status = WriteAll(fd, wal::kLogMagic, path);
  if (status.ok() && fdatasync(fd) != 0) status = IoError("cannot sync", path);
  if (status.ok()) status = SyncDir();
  if (!status.ok()) {
    close(fd);
    return status;
  }
  const bool had_segment = segment_fd_ >= 0;
  if (had_segment) close(segment_fd_);
  segment_fd_ = fd;
  segment_path_ = path;
  segment_bytes_ = static_cast<int64_t>(wal::kLogMagic.size());
  absl::MutexLock lock(&mu_);
  if (had_segment) sealed_segments_.push_back(segment_first_);
  segment_first_ = first_sequence;
  return absl::OkStatus();
}

absl::Status DurableStore::SyncDir() {
  if (fsync(dir_fd_) != 0) return IoError("cannot sync", options_.dir);
  return absl::OkStatus();
}

absl::Status DurableStore::LeadSync(bool rotate) {
  leader_ = true;
  std::string batch;
  batch.swap(pending_);
  const uint64_t last = next_sequence_ - 1;
  const int64_t records = static_cast<int64_t>(last - durable_sequence_);
  mu_.Unlock();
  const std::string& path = segment_path_;
  absl::Status status;
  if (!batch.empty()) {
    status = WriteAll(segment_fd_, batch, path);
    if (status.ok() && fdatasync(segment_fd_) != 0) status = IoError("cannot sync", path);
    segment_bytes_ += static_cast<int64_t>(batch.size());
  }
  bool rotated = false;
  if (status.ok() && segment_bytes_ > static_cast<int64_t>(wal::kLogMagic.size()) &&
      (rotate || segment_bytes_ >= options_.snapshot_log_bytes)) {
    status = StartSegment(last + 1);
    rotated = status.ok();
  }
  mu_.Lock();
  leader_ = false;
  if (!status.ok()) {
    failed_ = status;
    spdlog::error("--data_dir {}: {}; map changes are refused from now on",
                  options_.dir, std::string(status.message()));
    return status;
  }
  durable_sequence_ = last;
  if (!batch.empty()) {
    ++stats_.syncs;
    stats_.records += records;
  }
  if (rotated && !rotate) checkpoint_wanted_ = true;
  return absl::OkStatus();
}

absl::Status DurableStore::Writable() {
  absl::MutexLock lock(&mu_);
  if (failed_.ok()) return absl::OkStatus();
  return absl::UnavailableError(absl::StrFormat(
      "map changes are refused since writing --data_dir failed (%s); restart pathd "
      "once the disk is fixed",
      failed_.message()));
}

absl::StatusOr<std::string> DurableStore::EncodeCreate(std::string_view name,
                                                       uint64_t version,
                                                       const Grid& grid) {
  return wal::EncodeCreated(name, version, grid);
}

std::string DurableStore::EncodeUpdate(std::string_view name, uint64_t version,
                                       absl::Span<const MapChange> changes) {
  return wal::EncodeUpdated(name, version, changes);
}

std::string DurableStore::EncodeDelete(std::string_view name, uint64_t last_version) {
  return wal::EncodeDeleted(name, last_version);
}

uint64_t DurableStore::Append(std::string_view name, std::string record,
                              std::shared_ptr<const MapSnapshot> current) {
  absl::MutexLock lock(&mu_);
  const uint64_t sequence = next_sequence_++;
  if (pending_.empty()) {
    pending_ = std::move(record);  // a whole map: no second copy
  } else {
    pending_.append(record);
  }
  auto it = names_.find(name);
  if (it == names_.end()) it = names_.emplace(std::string(name), NameState{}).first;
  it->second.current = std::move(current);
  it->second.last_sequence = sequence;
  return sequence;
}

absl::Status DurableStore::WaitDurable(uint64_t sequence) {
  absl::MutexLock lock(&mu_);
  while (durable_sequence_ < sequence) {
    if (!failed_.ok()) return failed_;
    if (leader_) {
      // The leader's sync may not cover this record (appended after it took
      // the batch); then this writer leads the next one.
      mu_.Await(absl::Condition(this, &DurableStore::NoLeader));
      continue;
    }
    // Errors land in failed_, checked above.
    LeadSync(/*rotate=*/false).IgnoreError();
  }
  return absl::OkStatus();
}

absl::Status DurableStore::WriteSnapshotFile(const MapSnapshot& snapshot,
                                             uint64_t sequence) {
  PATHD_ASSIGN_OR_RETURN(
      const std::string bytes,
      wal::EncodeSnapshot(sequence, snapshot.name, snapshot.version, *snapshot.grid));
  const std::string path = Path(SnapshotName(snapshot.name));
  const std::string temp = path + kTempSuffix;
  const int fd = open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return IoError("cannot create", temp);
  absl::Status status = WriteAll(fd, bytes, temp);
  if (status.ok() && fsync(fd) != 0) status = IoError("cannot sync", temp);
  close(fd);
  if (status.ok() && rename(temp.c_str(), path.c_str()) != 0) {
    status = IoError("cannot rename to " + path + ":", temp);
  }
  if (!status.ok()) unlink(temp.c_str());
  return status;
}

absl::Status DurableStore::Checkpoint() {
  absl::MutexLock checkpoint_lock(&checkpoint_mu_);
  struct Work {
    std::string name;
    std::shared_ptr<const MapSnapshot> current;
    uint64_t sequence = 0;
  };
  std::vector<Work> work;
  std::vector<uint64_t> covered_segments;
  uint64_t newest = 0;
  {
    absl::MutexLock lock(&mu_);
    checkpoint_wanted_ = false;
    mu_.Await(absl::Condition(this, &DurableStore::NoLeader));
    if (!failed_.ok()) return failed_;
    // Every record so far goes to the segments about to be dropped; the
    // snapshots below include them all.
    PATHD_RETURN_IF_ERROR(LeadSync(/*rotate=*/true));
    covered_segments = sealed_segments_;
    for (const auto& [name, state] : names_) {
      if (state.last_sequence <= state.snapshot_sequence) continue;
      work.push_back(Work{name, state.current, state.last_sequence});
      newest = std::max(newest, state.last_sequence);
    }
  }
  // A snapshot must not hold a change the log may still lose.
  PATHD_RETURN_IF_ERROR(WaitDurable(newest));
  int written = 0;
  for (const Work& w : work) {
    if (w.current != nullptr) {
      PATHD_RETURN_IF_ERROR(WriteSnapshotFile(*w.current, w.sequence));
      ++written;
    } else {
      const std::string path = Path(SnapshotName(w.name));
      if (unlink(path.c_str()) != 0 && errno != ENOENT) {
        return IoError("cannot remove", path);
      }
    }
  }
  PATHD_RETURN_IF_ERROR(SyncDir());
  {
    absl::MutexLock lock(&mu_);
    for (const Work& w : work) {
      auto it = names_.find(w.name);
      it->second.snapshot_sequence = w.current != nullptr ? w.sequence : 0;
      // Deleted, its file gone, and not re-created since: nothing to track.
      if (it->second.current == nullptr && it->second.last_sequence == w.sequence) {
        names_.erase(it);
      }
    }
    stats_.snapshots_written += written;
  }
  for (const uint64_t first : covered_segments) {
    const std::string path = Path(SegmentName(first));
    if (unlink(path.c_str()) != 0 && errno != ENOENT) return IoError("cannot remove", path);
  }
  PATHD_RETURN_IF_ERROR(SyncDir());
  absl::MutexLock lock(&mu_);
  sealed_segments_.erase(sealed_segments_.begin(),
                         sealed_segments_.begin() +
                             static_cast<std::ptrdiff_t>(covered_segments.size()));
  stats_.segments_deleted += static_cast<int64_t>(covered_segments.size());
  spdlog::debug("--data_dir {}: checkpoint wrote {} snapshot(s), deleted {} segment(s)",
                options_.dir, written, covered_segments.size());
  return absl::OkStatus();
}

void DurableStore::SnapshotLoop() {
  for (;;) {
    bool run = false;
    {
      absl::MutexLock lock(&mu_);
      const absl::Condition wake(this, &DurableStore::SnapshotDue);
      const bool woken = options_.snapshot_interval > absl::ZeroDuration()
                             ? mu_.AwaitWithTimeout(wake, options_.snapshot_interval)
                             : (mu_.Await(wake), true);
      if (stopping_) return;
      // On the timer, only when the active segment holds records.
      run = woken || next_sequence_ > segment_first_;
    }
    if (!run) continue;
    if (absl::Status status = Checkpoint(); !status.ok()) {
      spdlog::warn("--data_dir {}: snapshot failed (the log keeps every change; "
                   "retrying later): {}",
                   options_.dir, std::string(status.message()));
    }
  }
}

DurableStore::Stats DurableStore::stats() const {
  absl::MutexLock lock(&mu_);
  return stats_;
}

}  // namespace pathd::server
