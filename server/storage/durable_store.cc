// DurableStore: log segments, group commit, snapshots and recovery.
#include "server/storage/durable_store.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iterator>
#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "core/status_macros.h"
#include "server/storage/data_files.h"
#include "server/storage/wal_format.h"
#include "spdlog/spdlog.h"

namespace pathd::server {
namespace {

namespace fs = std::filesystem;
using namespace data_files;  // NOLINT(build/namespaces): this file's vocabulary

constexpr int kTestExitCode = 86;

}  // namespace

DurableStore::DurableStore(Options options, MapStore& store)
    : options_(std::move(options)), store_(store) {}

DurableStore::~DurableStore() {
  {
    absl::MutexLock lock(&mu_);
    stopping_ = true;
  }
  if (snapshot_thread_.joinable()) snapshot_thread_.join();
  // Drains what is queued before returning.
  if (completion_thread_.joinable()) completion_thread_.join();
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
  if (const char* spec = std::getenv("PATHD_TEST_CHECKPOINT_EXIT");
      spec != nullptr && !durable->options_.checkpoint_hook) {
    std::pair<std::string, std::string> parts = absl::StrSplit(spec, ':');
    if (!absl::SimpleAtoi(parts.first, &durable->exit_step_) ||
        !absl::SimpleAtoi(parts.second, &durable->exit_checkpoint_)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "PATHD_TEST_CHECKPOINT_EXIT is '%s'; expected STEP:N (two numbers)", spec));
    }
  }
  PATHD_RETURN_IF_ERROR(durable->Recover());
  store.SetJournal(durable.get());
  DurableStore* self = durable.get();
  durable->snapshot_thread_ = std::thread([self] { self->SnapshotLoop(); });
  durable->completion_thread_ = std::thread([self] { self->CompletionLoop(); });
  return durable;
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
    if (status.ok()) {
      segment_bytes_ += static_cast<int64_t>(batch.size());
    } else if (ftruncate(segment_fd_, static_cast<off_t>(segment_bytes_)) == 0) {
      // The failed batch was never acknowledged nor published (the store
      // publishes a version only once it is durable): take back whatever
      // part of it reached the file, so no later start replays it.
      fdatasync(segment_fd_);
    }
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

void DurableStore::OnDurable(uint64_t sequence, std::function<void(absl::Status)> done) {
  absl::MutexLock lock(&mu_);
  // Sequence numbers are handed out under mu_ and callers queue right after
  // appending, but two callers may cross: keep the queue sorted.
  auto at = completions_.end();
  while (at != completions_.begin() && std::prev(at)->sequence > sequence) --at;
  completions_.insert(at, Completion{sequence, std::move(done)});
}

void DurableStore::CompletionLoop() {
  for (;;) {
    std::vector<Completion> batch;
    {
      absl::MutexLock lock(&mu_);
      mu_.Await(absl::Condition(this, &DurableStore::CompletionsDue));
      if (completions_.empty()) return;  // stopping, and drained
      batch.swap(completions_);
    }
    // One sync for the whole batch (and any writer waiting meanwhile); on a
    // failure the records synced before it still succeed.
    const absl::Status status = WaitDurable(batch.back().sequence);
    uint64_t durable = 0;
    {
      absl::MutexLock lock(&mu_);
      durable = durable_sequence_;
    }
    for (Completion& completion : batch) {
      completion.done(completion.sequence <= durable ? absl::OkStatus() : status);
    }
  }
}

absl::Status DurableStore::WriteFileAtomically(const std::string& file,
                                               std::string_view bytes,
                                               const std::function<void()>& after_sync) {
  const std::string path = Path(file);
  const std::string temp = path + kTempSuffix;
  const int fd = open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return IoError("cannot create", temp);
  absl::Status status = WriteAll(fd, bytes, temp);
  if (status.ok() && fsync(fd) != 0) status = IoError("cannot sync", temp);
  close(fd);
  if (status.ok() && after_sync) after_sync();
  if (status.ok() && rename(temp.c_str(), path.c_str()) != 0) {
    status = IoError("cannot rename to " + path + ":", temp);
  }
  if (!status.ok()) unlink(temp.c_str());
  return status;
}

absl::Status DurableStore::WriteSnapshotFile(const MapSnapshot& snapshot,
                                             uint64_t sequence) {
  PATHD_ASSIGN_OR_RETURN(
      const std::string bytes,
      wal::EncodeSnapshot(sequence, snapshot.name, snapshot.version, *snapshot.grid));
  return WriteFileAtomically(SnapshotName(snapshot.name), bytes,
                             [this] { Step(CheckpointStep::kSnapshotTempWritten); });
}

void DurableStore::Step(CheckpointStep step) {
  if (options_.checkpoint_hook) {
    options_.checkpoint_hook(step);
  } else if (exit_step_ == static_cast<int>(step) &&
             exit_checkpoint_ == checkpoints_started_) {
    // What a kill -9 at this point leaves (the page cache survives either).
    spdlog::warn("PATHD_TEST_CHECKPOINT_EXIT: exiting after step {} of checkpoint {}",
                 exit_step_, exit_checkpoint_);
    spdlog::default_logger()->flush();
    _exit(kTestExitCode);
  }
}

absl::Status DurableStore::Checkpoint() {
  absl::MutexLock checkpoint_lock(&checkpoint_mu_);
  ++checkpoints_started_;
  // Every name as it was just before `start`, the first record of the new
  // segment. A map changed (or deleted) after `start` keeps its older state
  // here: the log from `start` on holds those changes.
  struct Work {
    std::string name;
    std::shared_ptr<const MapSnapshot> current;
    uint64_t last_sequence = 0;
    uint64_t snapshot_sequence = 0;
  };
  std::vector<Work> work;
  std::vector<uint64_t> covered_segments;
  uint64_t start = 0;
  {
    absl::MutexLock lock(&mu_);
    checkpoint_wanted_ = false;
    mu_.Await(absl::Condition(this, &DurableStore::NoLeader));
    if (!failed_.ok()) return failed_;
    // Captured in the critical section in which LeadSync picks the last
    // record of the old segment, so `work` is exactly the state it ends with.
    start = next_sequence_;
    work.reserve(names_.size());
    for (const auto& [name, state] : names_) {
      work.push_back(Work{name, state.current, state.last_sequence, state.snapshot_sequence});
    }
    PATHD_RETURN_IF_ERROR(LeadSync(/*rotate=*/true));
    // Every sealed segment ends before `start`, and is synced.
    covered_segments = sealed_segments_;
  }
  Step(CheckpointStep::kRotated);

  storage::v1::CheckpointRecord checkpoint;
  checkpoint.set_first_sequence(start);
  std::vector<const Work*> written;
  std::vector<const Work*> stale;
  for (const Work& w : work) {
    if (w.current == nullptr) {
      // Deleted before `start`: its file goes once CHECKPOINT no longer lists it.
      if (w.snapshot_sequence != 0) stale.push_back(&w);
      continue;
    }
    uint64_t sequence = w.snapshot_sequence;
    if (w.last_sequence > w.snapshot_sequence) {
      PATHD_RETURN_IF_ERROR(WriteSnapshotFile(*w.current, w.last_sequence));
      Step(CheckpointStep::kSnapshotRenamed);
      written.push_back(&w);
      sequence = w.last_sequence;
    }
    storage::v1::SnapshotRef* ref = checkpoint.add_snapshots();
    ref->set_name(w.name);
    ref->set_sequence(sequence);
  }
  PATHD_RETURN_IF_ERROR(SyncDir());
  Step(CheckpointStep::kSnapshotsSynced);
  PATHD_RETURN_IF_ERROR(
      WriteFileAtomically(kCheckpointFile, wal::EncodeCheckpoint(checkpoint), {}));
  PATHD_RETURN_IF_ERROR(SyncDir());
  Step(CheckpointStep::kMarkerWritten);
  {
    absl::MutexLock lock(&mu_);
    for (const Work* w : written) names_[w->name].snapshot_sequence = w->last_sequence;
    stats_.snapshots_written += static_cast<int64_t>(written.size());
  }
  for (const Work* w : stale) {
    const std::string path = Path(SnapshotName(w->name));
    if (unlink(path.c_str()) != 0 && errno != ENOENT) return IoError("cannot remove", path);
    Step(CheckpointStep::kStaleSnapshotRemoved);
  }
  {
    absl::MutexLock lock(&mu_);
    for (const Work& w : work) {
      if (w.current != nullptr) continue;
      auto it = names_.find(w.name);
      if (it == names_.end()) continue;
      it->second.snapshot_sequence = 0;
      // Deleted, its file gone, and not re-created since: nothing to track.
      if (it->second.current == nullptr && it->second.last_sequence == w.last_sequence) {
        names_.erase(it);
      }
    }
  }
  for (const uint64_t first : covered_segments) {
    const std::string path = Path(SegmentName(first));
    if (unlink(path.c_str()) != 0 && errno != ENOENT) return IoError("cannot remove", path);
    Step(CheckpointStep::kSegmentRemoved);
  }
  PATHD_RETURN_IF_ERROR(SyncDir());
  Step(CheckpointStep::kDone);
  absl::MutexLock lock(&mu_);
  sealed_segments_.erase(sealed_segments_.begin(),
                         sealed_segments_.begin() +
                             static_cast<std::ptrdiff_t>(covered_segments.size()));
  stats_.segments_deleted += static_cast<int64_t>(covered_segments.size());
  spdlog::debug("--data_dir {}: checkpoint at record {} wrote {} snapshot(s), removed {} "
                "deleted map(s) and {} segment(s)",
                options_.dir, start, written.size(), stale.size(), covered_segments.size());
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
