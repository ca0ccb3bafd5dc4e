// Crash points of DurableStore::Checkpoint: a child process runs a workload
// of creates, updates, replaces and deletes, then dies (_exit, which leaves
// the files as a kill -9 would) right after step k of a checkpoint; the
// parent recovers the directory, which must hold exactly the acknowledged
// maps. Regression test for "a crash during the checkpoint after a DeleteMap
// leaves a data dir pathd refuses to open".
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <memory>
#include <string>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/map_store.h"
#include "server/storage/durable_store.h"

namespace pathd::server {
namespace {

namespace fs = std::filesystem;

constexpr int64_t kMaxCells = 1 << 20;
// Child exit codes.
constexpr int kDiedAtStep = 0;
constexpr int kStepNotReached = 3;
constexpr int kWorkloadFailed = 4;

// Runs in the child. Checkpoint 1 makes snapshots of a, b, w and x;
// checkpoint 2 (the one crashed) must then write a, b, w, y, remove x's
// snapshot (x deleted) and drop the segments before it.
int RunWorkload(const fs::path& dir, CheckpointStep step, int occurrence) {
  MapStore store(kMaxCells);
  DurableStore::Options options;
  options.dir = dir.string();
  options.snapshot_interval = absl::ZeroDuration();
  int checkpoints = 0;
  int seen = 0;
  options.checkpoint_hook = [&](CheckpointStep at) {
    if (at == CheckpointStep::kRotated) ++checkpoints;
    if (checkpoints == 2 && at == step && ++seen == occurrence) _exit(kDiedAtStep);
  };
  auto durable = DurableStore::Open(options, store);
  if (!durable.ok()) return kWorkloadFailed;
  auto ok = [](const auto& result) { return result.ok(); };
  bool good = ok(store.Create("a", *Grid::Create(8, 8), false)) &&
              ok(store.Update("a", {MapChange::ForCell(1, 1, 254)}, {})) &&
              ok(store.Create("x", *Grid::Create(4, 4), false)) &&
              ok(store.Update("x", {MapChange::ForCell(0, 0, 7)}, {})) &&
              ok(store.Create("b", *Grid::Create(4, 4, 1), false)) &&
              ok(store.Create("w", *Grid::Create(2, 2), false)) &&
              (*durable)->Checkpoint().ok() &&
              ok(store.Update("a", {MapChange::ForCell(2, 2, 9)}, {})) &&
              ok(store.Delete("x")) &&
              ok(store.Create("y", *Grid::Create(3, 3), false)) &&
              ok(store.Create("b", *Grid::Create(5, 5, 2), /*replace=*/true)) &&
              ok(store.Update("b", {MapChange::ForCell(4, 4, 3)}, {})) &&
              ok(store.Create("z", *Grid::Create(2, 2), false)) && ok(store.Delete("z")) &&
              ok(store.Delete("w")) && ok(store.Create("w", *Grid::Create(6, 6, 4), false));
  if (!good) return kWorkloadFailed;
  if (!(*durable)->Checkpoint().ok()) return kWorkloadFailed;
  return kStepNotReached;
}

class CheckpointCrashTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pathd_checkpoint_crash_" + std::to_string(getpid()));
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Forks the workload dying after `occurrence` of `step`; the child's exit code.
  int CrashAt(CheckpointStep step, int occurrence) {
    fs::remove_all(dir_);
    const pid_t child = fork();
    if (child == 0) _exit(RunWorkload(dir_, step, occurrence));
    int status = 0;
    waitpid(child, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  // The acknowledged state, from a store recovered from dir_. The first
  // start (`again` false) then updates "a" to version 4 and checkpoints; the
  // second expects that too.
  void ExpectAcknowledgedState(const std::string& where, bool again) {
    SCOPED_TRACE(where);
    MapStore store(kMaxCells);
    DurableStore::Options options;
    options.dir = dir_.string();
    options.snapshot_interval = absl::ZeroDuration();
    auto durable = DurableStore::Open(options, store);
    ASSERT_TRUE(durable.ok()) << durable.status();
    EXPECT_EQ(store.size(), 4u);
    auto a = store.Get("a");
    ASSERT_TRUE(a.ok());
    EXPECT_EQ((*a)->version, again ? 4u : 3u);
    EXPECT_EQ((*a)->grid->cost(1, 1), 254);
    EXPECT_EQ((*a)->grid->cost(2, 2), 9);
    auto b = store.Get("b");
    ASSERT_TRUE(b.ok());
    EXPECT_EQ((*b)->version, 3u);
    EXPECT_EQ((*b)->grid->width(), 5);
    EXPECT_EQ((*b)->grid->cost(4, 4), 3);
    EXPECT_EQ((*b)->grid->cost(0, 0), 2);
    auto w = store.Get("w");
    ASSERT_TRUE(w.ok());
    EXPECT_EQ((*w)->version, 1u);
    EXPECT_EQ((*w)->grid->width(), 6);
    auto y = store.Get("y");
    ASSERT_TRUE(y.ok());
    EXPECT_EQ((*y)->version, 1u);
    EXPECT_EQ(store.Get("x").status().code(), absl::StatusCode::kNotFound);
    EXPECT_EQ(store.Get("z").status().code(), absl::StatusCode::kNotFound);
    if (again) {
      EXPECT_EQ((*a)->grid->cost(3, 3), 5);
      EXPECT_EQ((*durable)->recovery().leftovers_removed, 0);
      return;
    }
    // Writable again, and what is written next survives too.
    EXPECT_TRUE(store.Update("a", {MapChange::ForCell(3, 3, 5)}, uint64_t{3}).ok());
    EXPECT_TRUE((*durable)->Checkpoint().ok());
  }

  fs::path dir_;
};

TEST_F(CheckpointCrashTest, EveryCrashPointRecoversTheAcknowledgedState) {
  const CheckpointStep steps[] = {
      CheckpointStep::kRotated,        CheckpointStep::kSnapshotTempWritten,
      CheckpointStep::kSnapshotRenamed, CheckpointStep::kSnapshotsSynced,
      CheckpointStep::kMarkerWritten,  CheckpointStep::kStaleSnapshotRemoved,
      CheckpointStep::kSegmentRemoved, CheckpointStep::kDone};
  int crashes = 0;
  for (const CheckpointStep step : steps) {
    for (int occurrence = 1;; ++occurrence) {
      const std::string where = "after occurrence " + std::to_string(occurrence) +
                                " of step " + std::to_string(static_cast<int>(step));
      const int code = CrashAt(step, occurrence);
      ASSERT_NE(code, kWorkloadFailed) << where;
      if (code == kStepNotReached) {
        // Every step happens at least once in checkpoint 2.
        EXPECT_GT(occurrence, 1) << where;
        break;
      }
      ASSERT_EQ(code, kDiedAtStep) << where;
      ++crashes;
      ExpectAcknowledgedState(where, /*again=*/false);
      // Recovery's own clean-up must leave a directory that recovers again.
      ExpectAcknowledgedState(where + ", second start", /*again=*/true);
      if (HasFatalFailure()) return;
    }
  }
  // 4 snapshots written (a, b, w, y), 1 removed (x), 1+ segments.
  EXPECT_GE(crashes, 8 + 3 + 3 + 0);
}

}  // namespace
}  // namespace pathd::server
