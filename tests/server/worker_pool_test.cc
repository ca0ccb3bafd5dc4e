// WorkerPool: jobs run on pool threads with a scratch of their own (or, for
// SubmitShort, on the caller's thread when a worker is free), interactive
// jobs before batch ones, a full queue fails fast with a retry hint, and
// shutdown drains or drops queued jobs. Synchronised with notifications only;
// nothing here depends on timing (the sleeps only set lower bounds).
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

TEST(WorkerPoolTest, RunsJobsOnPoolThreadsEachWithAScratchOfItsOwn) {
  constexpr int kThreads = 3;
  constexpr int kJobs = 200;
  WorkerPool pool({kThreads, kJobs});
  EXPECT_EQ(pool.threads(), kThreads);
  EXPECT_FALSE(WorkerPool::OnWorkerThread());

  absl::Mutex mu;
  std::set<std::thread::id> thread_ids;
  std::set<const SearchScratch*> scratches;
  std::set<const SearchScratch*> in_use;
  std::atomic<int> off_pool{0};
  std::atomic<int> shared{0};
  absl::BlockingCounter done(kJobs);
  for (int i = 0; i < kJobs; ++i) {
    ASSERT_TRUE(pool.Submit(MakeJob([&](SearchScratch& scratch) {
                      if (!WorkerPool::OnWorkerThread()) ++off_pool;
                      {
                        absl::MutexLock lock(&mu);
                        thread_ids.insert(std::this_thread::get_id());
                        scratches.insert(&scratch);
                        if (!in_use.insert(&scratch).second) ++shared;
                      }
                      {
                        absl::MutexLock lock(&mu);
                        in_use.erase(&scratch);
                      }
                      done.DecrementCount();
                    }))
                    .ok());
  }
  done.Wait();
  EXPECT_EQ(off_pool.load(), 0);
  EXPECT_EQ(shared.load(), 0);  // no two running jobs ever had one scratch
  absl::MutexLock lock(&mu);
  EXPECT_EQ(thread_ids.count(std::this_thread::get_id()), 0u);
  EXPECT_LE(thread_ids.size(), static_cast<size_t>(kThreads));
  EXPECT_LE(scratches.size(), static_cast<size_t>(kThreads));
}

TEST(WorkerPoolTest, SubmitShortRunsOnTheCallingThreadWhenAWorkerIsFree) {
  WorkerPool pool({2, 4});
  std::thread::id ran_on;
  bool on_worker = false;
  ASSERT_TRUE(pool.SubmitShort(MakeJob([&](SearchScratch&) {
                    ran_on = std::this_thread::get_id();
                    on_worker = WorkerPool::OnWorkerThread();
                  }))
                  .ok());
  // It ran before SubmitShort returned, here, counted as a worker would be.
  EXPECT_EQ(ran_on, std::this_thread::get_id());
  EXPECT_TRUE(on_worker);
  EXPECT_FALSE(WorkerPool::OnWorkerThread());
  EXPECT_EQ(pool.inline_runs(), 1);
  EXPECT_GT(pool.busy_time(), absl::ZeroDuration());
}

TEST(WorkerPoolTest, SubmitShortQueuesWhenEveryWorkerIsBusy) {
  WorkerPool pool({2, 4});
  Blockers blockers(pool, 2);
  absl::Notification ran;
  std::thread::id ran_on;
  ASSERT_TRUE(pool.SubmitShort(MakeJob([&](SearchScratch&) {
                    ran_on = std::this_thread::get_id();
                    ran.Notify();
                  }))
                  .ok());
  EXPECT_FALSE(ran.HasBeenNotified());  // queued behind the blockers
  EXPECT_EQ(pool.queued(), 1u);
  blockers.Release();
  ran.WaitForNotification();
  EXPECT_NE(ran_on, std::this_thread::get_id());
  EXPECT_EQ(pool.inline_runs(), 0);
}

TEST(WorkerPoolTest, SubmitShortStopsRunningInlineOnceShortJobsRanLong) {
  WorkerPool::Options options{2, 4};
  options.inline_max_job_time = absl::Microseconds(100);
  WorkerPool pool(options);
  // The first runs here (no history yet) and takes at least 20 ms ...
  ASSERT_TRUE(pool.SubmitShort(MakeJob([](SearchScratch&) {
                    absl::SleepFor(absl::Milliseconds(20));
                  }))
                  .ok());
  EXPECT_EQ(pool.inline_runs(), 1);
  // ... so the recent mean is over the limit and the next goes to a worker.
  absl::Notification ran;
  std::thread::id ran_on;
  ASSERT_TRUE(pool.SubmitShort(MakeJob([&](SearchScratch&) {
                    ran_on = std::this_thread::get_id();
                    ran.Notify();
                  }))
                  .ok());
  ran.WaitForNotification();
  EXPECT_NE(ran_on, std::this_thread::get_id());
  EXPECT_EQ(pool.inline_runs(), 1);
}

TEST(WorkerPoolTest, SubmitShortNeverRunsInlineWhenTheLimitIsZero) {
  WorkerPool::Options options{2, 4};
  options.inline_max_job_time = absl::ZeroDuration();
  WorkerPool pool(options);
  absl::Notification ran;
  std::thread::id ran_on;
  ASSERT_TRUE(pool.SubmitShort(MakeJob([&](SearchScratch&) {
                    ran_on = std::this_thread::get_id();
                    ran.Notify();
                  }))
                  .ok());
  ran.WaitForNotification();
  EXPECT_NE(ran_on, std::this_thread::get_id());
  EXPECT_EQ(pool.inline_runs(), 0);
}

TEST(WorkerPoolTest, AnInlineJobHoldsAWorkersPlace) {
  // One thread: while a caller runs a short job itself, no worker starts
  // another (at most threads() jobs run at once, wherever they run).
  WorkerPool pool({1, 4});
  absl::Notification inline_started, release;
  std::atomic<bool> inline_running{false};
  std::thread caller([&] {
    EXPECT_TRUE(pool.SubmitShort(MakeJob([&](SearchScratch&) {
                      inline_running.store(true);
                      inline_started.Notify();
                      release.WaitForNotification();
                      inline_running.store(false);
                    }))
                    .ok());
  });
  inline_started.WaitForNotification();
  absl::Notification queued_ran;
  std::atomic<bool> overlapped{false};
  ASSERT_TRUE(pool.Submit(MakeJob([&](SearchScratch&) {
                    overlapped.store(inline_running.load());
                    queued_ran.Notify();
                  }))
                  .ok());
  // Time for a wrong pool to start the queued job (a lower bound only).
  absl::SleepFor(absl::Milliseconds(50));
  EXPECT_FALSE(queued_ran.HasBeenNotified());
  release.Notify();
  caller.join();
  queued_ran.WaitForNotification();
  EXPECT_FALSE(overlapped.load());
  EXPECT_EQ(pool.inline_runs(), 1);
}

TEST(WorkerPoolTest, SubmitShortAfterShutdownIsUnavailable) {
  WorkerPool pool({1, 4});
  pool.Shutdown(WorkerPool::ShutdownMode::kDrain);
  EXPECT_TRUE(absl::IsUnavailable(pool.SubmitShort(MakeJob([](SearchScratch&) {}))));
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
