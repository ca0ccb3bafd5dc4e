// --data_dir: the MapStore's journal. Every Create/Update/Delete is appended
// to a log segment and fdatasync'ed before the call returns (writers waiting
// together share one sync); snapshots of changed maps let old segments go;
// start-up rebuilds the maps from the snapshots and the log. File formats in
// server/storage/wal_format.h; what is promised, and the checkpoint's crash
// points, in docs/durability.md.
#ifndef PATHD_SERVER_STORAGE_DURABLE_STORE_H_
#define PATHD_SERVER_STORAGE_DURABLE_STORE_H_

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "server/map_store.h"

namespace pathd::server {

// The steps of DurableStore::Checkpoint, in order. A crash after any of them
// leaves a directory that recovers to exactly the acknowledged state
// (docs/durability.md lists what each leaves behind).
enum class CheckpointStep {
  // A new segment starts at sequence S; every record before S is synced.
  kRotated = 1,
  // A snapshot's temporary file is written and synced, not yet renamed.
  kSnapshotTempWritten,
  // One map-<name>.snap is renamed into place (once per changed map).
  kSnapshotRenamed,
  // The directory is synced: every new snapshot is durable.
  kSnapshotsSynced,
  // CHECKPOINT (S and the snapshot list) is renamed into place and synced.
  kMarkerWritten,
  // One deleted map's snapshot is unlinked (once per such map).
  kStaleSnapshotRemoved,
  // One segment before S is unlinked (once per segment).
  kSegmentRemoved,
  // The directory is synced; the checkpoint is complete.
  kDone,
};

// Thread-safe. Files in the directory:
//   LOCK                    flock'ed while a pathd uses the directory
//   wal-<first seq>.log     log segments (20-digit sequence numbers)
//   map-<name>.snap         the latest snapshot of one map
//   CHECKPOINT              where replay starts and which snapshots hold the
//                           state before it (absent until the first checkpoint)
//   *.tmp                   a snapshot or CHECKPOINT being written (removed at
//                           start-up)
//   *.corrupt[.N]           a copy of a segment kept before cutting its
//                           damaged tail (never removed by pathd)
class DurableStore final : public MapJournal {
 public:
  struct Options {
    std::string dir;
    // Once the active segment holds this many bytes a new one starts and the
    // maps changed since their last snapshot are snapshotted, after which
    // the old segments are deleted.
    int64_t snapshot_log_bytes = int64_t{64} << 20;
    // The same after this long when the active segment holds any record;
    // zero = only by size.
    absl::Duration snapshot_interval = absl::Minutes(10);
    // Test hook: called after each step of every checkpoint (the crash-point
    // tests _exit() in it). When unset, the environment variable
    // PATHD_TEST_CHECKPOINT_EXIT="STEP:N" makes the process _exit(86) after
    // step STEP (the CheckpointStep number) of the N-th checkpoint, for the
    // end-to-end crash test.
    std::function<void(CheckpointStep)> checkpoint_hook = nullptr;
  };

  // Counters since Open, for logs and benchmarks.
  struct Stats {
    int64_t records = 0;
    // fdatasync calls that made records durable (group commits).
    int64_t syncs = 0;
    int64_t snapshots_written = 0;
    int64_t segments_deleted = 0;
  };

  // What start-up found.
  struct Recovery {
    int maps = 0;
    int snapshots = 0;
    int segments = 0;
    int64_t records_replayed = 0;
    // "FILE: offset N: problem ..." when the newest segment ended in a bad
    // record with nothing valid after it, which was cut away; empty otherwise.
    std::string torn_tail;
    // Where the segment was copied before the cut ("FILE.corrupt").
    std::string torn_tail_copy;
    // Segments and deleted maps' snapshots that the CHECKPOINT file shows
    // were left by a checkpoint a crash interrupted, removed at start-up.
    int leftovers_removed = 0;
  };

  // Creates `options.dir` if needed, locks it, rebuilds its maps into
  // `store` (which must be empty), starts a new log segment and becomes the
  // store's journal. Errors: DATA_LOSS naming the file (and offset) for a
  // corrupt or truncated snapshot, corruption before the last record of the
  // log, a missing segment, or records that do not follow from each other;
  // FAILED_PRECONDITION when another process holds the directory;
  // RESOURCE_EXHAUSTED when a recovered map exceeds the store's max_cells;
  // INTERNAL for I/O errors. A torn final record (a bad record of the newest
  // segment with nothing valid after it) is cut away after copying the
  // segment to FILE.corrupt, and reported with a warning (and in recovery());
  // INTERNAL when that copy cannot be made.
  static absl::StatusOr<std::unique_ptr<DurableStore>> Open(Options options,
                                                             MapStore& store);

  // Runs the completions still queued, stops the snapshot and completion
  // threads and detaches from the store. Precondition: no writer is inside
  // the store.
  ~DurableStore() override;
  DurableStore(const DurableStore&) = delete;
  DurableStore& operator=(const DurableStore&) = delete;

  // Starts a new segment at S, snapshots every map changed since its last
  // snapshot, records S and the snapshot list in CHECKPOINT, then removes
  // the snapshots of maps deleted before S and the segments before S (the
  // steps of CheckpointStep, in that order). The background thread calls it;
  // exposed for tests.
  absl::Status Checkpoint();

  Stats stats() const;
  const Recovery& recovery() const { return recovery_; }

  // MapJournal.
  absl::Status Writable() override;
  absl::StatusOr<std::string> EncodeCreate(std::string_view name, uint64_t version,
                                           const Grid& grid) override;
  std::string EncodeUpdate(std::string_view name, uint64_t version,
                           absl::Span<const MapChange> changes) override;
  std::string EncodeDelete(std::string_view name, uint64_t last_version) override;
  uint64_t Append(std::string_view name, std::string record,
                  std::shared_ptr<const MapSnapshot> current) override;
  absl::Status WaitDurable(uint64_t sequence) override;
  // Runs `done` on the completion thread once `sequence` is durable (or the
  // log failed), so no caller thread waits for fdatasync: the thread leads
  // one group commit for every completion queued meanwhile.
  void OnDurable(uint64_t sequence, std::function<void(absl::Status)> done) override;

 private:
  // Per map name: what a checkpoint needs to know.
  struct NameState {
    // The current version; null once deleted.
    std::shared_ptr<const MapSnapshot> current;
    // The last record of this name (or the snapshot it was recovered from).
    uint64_t last_sequence = 0;
    // The record the name's snapshot file includes; 0 = no file.
    uint64_t snapshot_sequence = 0;
  };

  DurableStore(Options options, MapStore& store);

  absl::Status Recover();
  // Creates wal-<first_sequence>.log with its magic, synced, and makes it the
  // segment appends go to. Only the sync leader (or Open) calls it.
  absl::Status StartSegment(uint64_t first_sequence);
  // Writes the pending records and syncs them, starting a new segment
  // afterwards when the active one is full or `rotate` (and it holds
  // records). Called with mu_ held and no leader; mu_ is released meanwhile.
  absl::Status LeadSync(bool rotate) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  absl::Status WriteSnapshotFile(const MapSnapshot& snapshot, uint64_t sequence);
  // Writes `bytes` to FILE.tmp, syncs it and renames it to FILE (the caller
  // syncs the directory). `after_sync` runs between the sync and the rename.
  absl::Status WriteFileAtomically(const std::string& file, std::string_view bytes,
                                   const std::function<void()>& after_sync);
  // Copies `path` to the first free PATH.corrupt[.N], synced; returns it.
  absl::StatusOr<std::string> KeepCopy(const std::string& path);
  absl::Status SyncDir();
  void Step(CheckpointStep step);
  void SnapshotLoop();
  void CompletionLoop();
  bool CompletionsDue() const ABSL_SHARED_LOCKS_REQUIRED(mu_) {
    return stopping_ || !completions_.empty();
  }
  bool NoLeader() const ABSL_SHARED_LOCKS_REQUIRED(mu_) { return !leader_; }
  bool SnapshotDue() const ABSL_SHARED_LOCKS_REQUIRED(mu_) {
    return stopping_ || checkpoint_wanted_;
  }
  std::string Path(std::string_view file) const;

  const Options options_;
  MapStore& store_;
  int lock_fd_ = -1;
  int dir_fd_ = -1;
  Recovery recovery_;

  // The active segment. Written only by the sync leader (leader_ true) or
  // before the store is journaled, so not guarded by mu_.
  int segment_fd_ = -1;
  std::string segment_path_;
  int64_t segment_bytes_ = 0;

  mutable absl::Mutex mu_;
  // Framed records appended but not yet written.
  std::string pending_ ABSL_GUARDED_BY(mu_);
  uint64_t next_sequence_ ABSL_GUARDED_BY(mu_) = 1;
  // Every record up to this one is on disk.
  uint64_t durable_sequence_ ABSL_GUARDED_BY(mu_) = 0;
  // A writer is writing and syncing (the others wait for it).
  bool leader_ ABSL_GUARDED_BY(mu_) = false;
  // Set by the first failed write or sync: nothing is logged after it.
  absl::Status failed_ ABSL_GUARDED_BY(mu_);
  // First sequence of the active segment and of every older one kept.
  uint64_t segment_first_ ABSL_GUARDED_BY(mu_) = 1;
  std::vector<uint64_t> sealed_segments_ ABSL_GUARDED_BY(mu_);
  std::map<std::string, NameState, std::less<>> names_ ABSL_GUARDED_BY(mu_);
  bool checkpoint_wanted_ ABSL_GUARDED_BY(mu_) = false;
  bool stopping_ ABSL_GUARDED_BY(mu_) = false;
  Stats stats_ ABSL_GUARDED_BY(mu_);
  struct Completion {
    uint64_t sequence = 0;
    std::function<void(absl::Status)> done;
  };
  // OnDurable calls not yet run, in sequence order.
  std::vector<Completion> completions_ ABSL_GUARDED_BY(mu_);

  // One checkpoint at a time.
  absl::Mutex checkpoint_mu_ ABSL_ACQUIRED_BEFORE(mu_);
  // Checkpoints begun, and PATHD_TEST_CHECKPOINT_EXIT's STEP:N (0: unset).
  std::atomic<int> checkpoints_started_{0};
  int exit_step_ = 0;
  int exit_checkpoint_ = 0;
  std::thread snapshot_thread_;
  std::thread completion_thread_;
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_STORAGE_DURABLE_STORE_H_
