// WorkerPool: jobs run on pool threads with per-worker scratch, interactive
// jobs before batch ones, a full queue fails fast with a retry hint, and
// shutdown drains or drops queued jobs. Synchronised with notifications only;
// nothing here depends on timing (the one sleep only sets a lower bound).
#include "server/worker_pool.h"

#include <atomic>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/status.h"
#include "absl/synchronization/blocking_counter.h"
#include "absl/synchronization/mutex.h"
#include "absl/synchronization/notification.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/grpc_status.h"

namespace pathd::server {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

// Occupies every worker until released, so later jobs stay queued.
class Blockers {
 public:
  Blockers(WorkerPool& pool, int n) : started_(n) {
    for (int i = 0; i < n; ++i) {
      EXPECT_TRUE(pool.Submit(MakeJob([this](SearchScratch&) {
                    started_.DecrementCount();
                    release_.WaitForNotification();
                    ran_.fetch_add(1);
                  }))
                      .ok());
    }
    started_.Wait();  // every worker is now inside a blocker; the queue is empty
  }
  void Release() { release_.Notify(); }
  int ran() const { return ran_.load(); }

 private:
  absl::BlockingCounter started_;
  absl::Notification release_;
  std::atomic<int> ran_{0};
};

TEST(WorkerPoolTest, RunsJobsOnPoolThreadsWithPerWorkerScratch) {
  constexpr int kThreads = 3;
  constexpr int kJobs = 200;
  WorkerPool pool({kThreads, kJobs});
  EXPECT_EQ(pool.threads(), kThreads);
  EXPECT_FALSE(WorkerPool::OnWorkerThread());

  absl::Mutex mu;
  std::set<std::thread::id> thread_ids;
  std::set<const SearchScratch*> scratches;
  std::set<std::pair<std::thread::id, const SearchScratch*>> pairs;
  std::atomic<int> off_pool{0};
  absl::BlockingCounter done(kJobs);
  for (int i = 0; i < kJobs; ++i) {
    ASSERT_TRUE(pool.Submit(MakeJob([&](SearchScratch& scratch) {
                      if (!WorkerPool::OnWorkerThread()) ++off_pool;
                      {
                        absl::MutexLock lock(&mu);
                        thread_ids.insert(std::this_thread::get_id());
                        scratches.insert(&scratch);
                        pairs.insert({std::this_thread::get_id(), &scratch});
                      }
                      done.DecrementCount();
                    }))
                    .ok());
  }
  done.Wait();
  EXPECT_EQ(off_pool.load(), 0);
  absl::MutexLock lock(&mu);
  EXPECT_EQ(thread_ids.count(std::this_thread::get_id()), 0u);
  EXPECT_LE(thread_ids.size(), static_cast<size_t>(kThreads));
  // Each thread always got the same scratch, and no two threads shared one.
  EXPECT_EQ(pairs.size(), thread_ids.size());
  EXPECT_EQ(scratches.size(), thread_ids.size());
}

TEST(WorkerPoolTest, FullQueueFailsFastWithResourceExhausted) {
  WorkerPool pool({2, 3});
  Blockers blockers(pool, 2);
  std::atomic<int> queued_ran{0};
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(pool.Submit(MakeJob([&](SearchScratch&) { ++queued_ran; })).ok());
  }
  EXPECT_EQ(pool.queued(), 3u);
  bool dropped = false;
  const absl::Status full =
      pool.Submit(MakeJob([](SearchScratch&) {}, [&] { dropped = true; }));
  EXPECT_EQ(full.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(full.message(),
              HasSubstr("interactive work queue full (3 jobs waiting, the limit "
                        "set by --queue_depth); retry in about"));
  // No job has finished yet, so the hint uses the default job time: three
  // queued jobs on two workers.
  EXPECT_EQ(RetryAfterMs(full),
            absl::ToInt64Milliseconds(WorkerPool::kDefaultJobTime * 3 / 2));
  EXPECT_FALSE(dropped);  // a rejected job is neither run nor dropped

  blockers.Release();
  pool.Shutdown(WorkerPool::ShutdownMode::kDrain);
  EXPECT_EQ(blockers.ran(), 2);
  EXPECT_EQ(queued_ran.load(), 3);
}

TEST(WorkerPoolTest, InteractiveJobsRunBeforeBatchJobsQueuedEarlier) {
  WorkerPool pool({1, 8, 8});
  Blockers blockers(pool, 1);
  absl::Mutex mu;
  std::vector<std::string> order;
  absl::BlockingCounter done(6);
  auto job = [&](std::string name) {
    return MakeJob([&, name](SearchScratch&) {
      {
        absl::MutexLock lock(&mu);
        order.push_back(name);
      }
      done.DecrementCount();
    });
  };
  using Priority = WorkerPool::Priority;
  ASSERT_TRUE(pool.Submit(job("b1"), Priority::kBatch).ok());
  ASSERT_TRUE(pool.Submit(job("b2"), Priority::kBatch).ok());
  ASSERT_TRUE(pool.Submit(job("i1")).ok());
  ASSERT_TRUE(pool.Submit(job("b3"), Priority::kBatch).ok());
  ASSERT_TRUE(pool.Submit(job("i2"), Priority::kInteractive).ok());
  ASSERT_TRUE(pool.Submit(job("i3")).ok());
  EXPECT_EQ(pool.queued(), 6u);
  EXPECT_EQ(pool.queued(Priority::kInteractive), 3u);
  EXPECT_EQ(pool.queued(Priority::kBatch), 3u);
  blockers.Release();
  done.Wait();
  absl::MutexLock lock(&mu);
  EXPECT_THAT(order, ElementsAre("i1", "i2", "i3", "b1", "b2", "b3"));
}

TEST(WorkerPoolTest, EachPriorityHasItsOwnBound) {
  using Priority = WorkerPool::Priority;
  WorkerPool pool({1, 2, 3});
  EXPECT_EQ(pool.queue_depth(), 2u);
  EXPECT_EQ(pool.queue_depth(Priority::kInteractive), 2u);
  EXPECT_EQ(pool.queue_depth(Priority::kBatch), 3u);
  Blockers blockers(pool, 1);
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(pool.Submit(MakeJob([](SearchScratch&) {}), Priority::kBatch).ok());
  }
  const absl::Status batch_full =
      pool.Submit(MakeJob([](SearchScratch&) {}), Priority::kBatch);
  EXPECT_EQ(batch_full.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(batch_full.message(),
              HasSubstr("batch work queue full (3 jobs waiting, the limit set by "
                        "--batch_queue_depth)"));
  // A full batch queue leaves the interactive one its own room.
  for (int i = 0; i < 2; ++i) {
    ASSERT_TRUE(pool.Submit(MakeJob([](SearchScratch&) {})).ok());
  }
  const absl::Status interactive_full = pool.Submit(MakeJob([](SearchScratch&) {}));
  EXPECT_EQ(interactive_full.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(interactive_full.message(), HasSubstr("--queue_depth"));
  // A refused batch job waits behind both queues, an interactive one only
  // behind its own: 5 and 2 jobs at the default job time on one worker.
  EXPECT_EQ(pool.EstimateRetryAfter(Priority::kBatch), WorkerPool::kDefaultJobTime * 5);
  EXPECT_EQ(pool.EstimateRetryAfter(Priority::kInteractive),
            WorkerPool::kDefaultJobTime * 2);
  blockers.Release();
  pool.Shutdown(WorkerPool::ShutdownMode::kDrain);
}

TEST(WorkerPoolTest, RetryHintFollowsTheJobsRunTimeAndIsClamped) {
  using Priority = WorkerPool::Priority;
  WorkerPool pool({1, 1000, 1});
  // An empty queue still asks for the minimum wait.
  EXPECT_EQ(pool.EstimateRetryAfter(Priority::kInteractive), WorkerPool::kMinRetryAfter);
  // One job that runs at least 200 ms becomes the mean (the first sample).
  absl::Notification ran;
  ASSERT_TRUE(pool.Submit(MakeJob([&](SearchScratch&) {
                    absl::SleepFor(absl::Milliseconds(200));
                    ran.Notify();
                  }))
                  .ok());
  ran.WaitForNotification();
  Blockers blockers(pool, 1);  // runs after the sleeper, so its time is in
  for (int i = 0; i < 5; ++i) {
    ASSERT_TRUE(pool.Submit(MakeJob([](SearchScratch&) {})).ok());
  }
  const absl::Duration five_jobs = pool.EstimateRetryAfter(Priority::kInteractive);
  EXPECT_GE(five_jobs, absl::Milliseconds(5 * 200));
  // Past the ceiling the hint stays at the ceiling.
  for (int i = 0; i < 995; ++i) {
    ASSERT_TRUE(pool.Submit(MakeJob([](SearchScratch&) {})).ok());
  }
  EXPECT_EQ(pool.EstimateRetryAfter(Priority::kInteractive), WorkerPool::kMaxRetryAfter);
  blockers.Release();
  pool.Shutdown(WorkerPool::ShutdownMode::kDrain);
}

TEST(WorkerPoolTest, ShutdownDropDropsBothQueues) {
  WorkerPool pool({1, 4, 4});
  Blockers blockers(pool, 1);
  std::atomic<int> ran{0};
  absl::BlockingCounter dropped(4);
  for (const auto priority :
       {WorkerPool::Priority::kInteractive, WorkerPool::Priority::kBatch}) {
    for (int i = 0; i < 2; ++i) {
      ASSERT_TRUE(pool.Submit(MakeJob([&](SearchScratch&) { ++ran; },
                                      [&] { dropped.DecrementCount(); }),
                              priority)
                      .ok());
    }
  }
  std::thread stopper([&] { pool.Shutdown(WorkerPool::ShutdownMode::kDrop); });
  dropped.Wait();
  blockers.Release();
  stopper.join();
  EXPECT_EQ(ran.load(), 0);
}

TEST(WorkerPoolTest, ShutdownDropTellsQueuedJobsAndLetsRunningOnesFinish) {
  WorkerPool pool({2, 8});
  Blockers blockers(pool, 2);
  std::atomic<int> ran{0};
  absl::BlockingCounter dropped(3);
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(pool.Submit(MakeJob([&](SearchScratch&) { ++ran; },
                                    [&] { dropped.DecrementCount(); }))
                    .ok());
  }
  // Shutdown joins the workers, so it runs on its own thread while this one
  // releases the blockers once the drops have happened.
  std::thread stopper([&] { pool.Shutdown(WorkerPool::ShutdownMode::kDrop); });
  dropped.Wait();
  blockers.Release();
  stopper.join();
  EXPECT_EQ(ran.load(), 0);
  EXPECT_EQ(blockers.ran(), 2);

  const absl::Status after = pool.Submit(MakeJob([](SearchScratch&) {}));
  EXPECT_EQ(after.code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(after.message(), HasSubstr("shutting down"));
  pool.Shutdown(WorkerPool::ShutdownMode::kDrop);  // idempotent
}

TEST(WorkerPoolTest, ShutdownDrainRunsQueuedJobs) {
  WorkerPool pool({1, 16});
  Blockers blockers(pool, 1);
  std::atomic<int> ran{0};
  std::atomic<int> dropped{0};
  for (int i = 0; i < 10; ++i) {
    ASSERT_TRUE(
        pool.Submit(MakeJob([&](SearchScratch&) { ++ran; }, [&] { ++dropped; })).ok());
  }
  std::thread stopper([&] { pool.Shutdown(WorkerPool::ShutdownMode::kDrain); });
  blockers.Release();
  stopper.join();
  EXPECT_EQ(ran.load(), 10);
  EXPECT_EQ(dropped.load(), 0);
}

TEST(WorkerPoolTest, DestructorDropsQueuedJobs) {
  std::atomic<int> dropped{0};
  auto pool = std::make_unique<WorkerPool>(WorkerPool::Options{1, 4});
  {
    Blockers blockers(*pool, 1);
    for (int i = 0; i < 4; ++i) {
      ASSERT_TRUE(
          pool->Submit(MakeJob([](SearchScratch&) {}, [&] { ++dropped; })).ok());
    }
    std::thread destroyer([&] { pool.reset(); });
    while (dropped.load() < 4) std::this_thread::yield();
    blockers.Release();
    destroyer.join();
  }
  EXPECT_EQ(dropped.load(), 4);
}

TEST(WorkerPoolTest, ZeroThreadsMeansHardwareConcurrency) {
  WorkerPool pool({0, 1});
  EXPECT_GE(pool.threads(), 1);
  EXPECT_EQ(pool.queue_depth(), 1u);
}

TEST(WorkerPoolTest, AThrowingJobDoesNotKillTheWorker) {
  WorkerPool pool({1, 4});
  absl::Notification second_ran;
  ASSERT_TRUE(pool.Submit(MakeJob([](SearchScratch&) {
                    throw std::runtime_error("boom");
                  }))
                  .ok());
  ASSERT_TRUE(pool.Submit(MakeJob([&](SearchScratch&) { second_ran.Notify(); })).ok());
  second_ran.WaitForNotification();
}

TEST(WorkerPoolTest, CountsBusyWorkersAndTheirTime) {
  WorkerPool pool({3, 4});
  EXPECT_EQ(pool.busy(), 0);
  EXPECT_EQ(pool.busy_time(), absl::ZeroDuration());
  {
    Blockers blockers(pool, 2);
    EXPECT_EQ(pool.busy(), 2);
    blockers.Release();
    pool.Shutdown(WorkerPool::ShutdownMode::kDrain);
    EXPECT_EQ(blockers.ran(), 2);
  }
  EXPECT_EQ(pool.busy(), 0);
  // Both jobs ran for some time before they were released.
  EXPECT_GT(pool.busy_time(), absl::ZeroDuration());
}

}  // namespace
}  // namespace pathd::server
