// PlannerService admission and shutdown paths that need a pool the test can
// hold still: queue full, a job dropped at shutdown, a client that cancels or
// whose deadline passes while its job waits. The service runs on a real gRPC
// server; the test owns the pool and blocks its only worker, so every outcome
// is decided by ordering, never by timing.
#include <atomic>
#include <chrono>
#include <future>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>
#include <grpcpp/security/server_credentials.h>
#include <grpcpp/server.h>
#include <grpcpp/server_builder.h>

#include "absl/synchronization/notification.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "core/map/inflation.h"
#include "server/incremental_cache.h"
#include "server/map_store.h"
#include "server/rpc/planner_service.h"
#include "server/server.h"
#include "tests/testing/in_process_server.h"
#include "server/worker_pool.h"
#include "spdlog/spdlog.h"

namespace pathd::server {
namespace {

using ::testing::HasSubstr;

class PlanAdmissionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    spdlog::set_level(spdlog::level::debug);  // exercise the request log line
    ASSERT_TRUE(store_.Create("open", *Grid::Create(32, 32), false).ok());
    pool_ = std::make_unique<WorkerPool>(WorkerPool::Options{1, 1});
    sessions_ = std::make_unique<NavigationSessions>(store_, *pool_, inflation_,
                                                     NavigationSessions::Options{});
    service_ = std::make_unique<PlannerServiceImpl>(store_, *pool_, inflation_, cache_,
                                                    *sessions_,
                                                    PlannerServiceImpl::Options{});
    absl::StatusOr<testing::LoopbackServer> loopback =
        testing::ServeOnLoopback(service_.get());
    ASSERT_TRUE(loopback.ok()) << loopback.status();
    server_ = std::move(loopback->server);
    stub_ = v1::PlannerService::NewStub(loopback->channel);
  }

  void TearDown() override {
    Release();
    // The order PathdServer uses: stop gRPC, then the pool, then wait.
    server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(10));
    pool_->Shutdown(WorkerPool::ShutdownMode::kDrop);
    server_->Wait();
    spdlog::set_level(spdlog::level::info);
  }

  // Occupies the only worker until Release().
  void BlockWorker() {
    absl::Notification started;
    ASSERT_TRUE(pool_->Submit(MakeJob([this, &started](SearchScratch&) {
                        started.Notify();
                        release_.WaitForNotification();
                      }))
                    .ok());
    started.WaitForNotification();
  }
  void Release() {
    if (!release_.HasBeenNotified()) release_.Notify();
  }
  void WaitUntilQueued(size_t n) {
    while (pool_->queued() < n) std::this_thread::yield();
  }
  // The worker has taken every queued job, so the next call finds room.
  void WaitUntilQueueEmpty() {
    while (pool_->queued() > 0) std::this_thread::yield();
  }

  static v1::PlanRequest Request() {
    v1::PlanRequest request;
    request.set_map("open");
    request.mutable_start()->mutable_cell()->set_x(0);
    request.mutable_start()->mutable_cell()->set_y(0);
    request.mutable_goal()->mutable_cell()->set_x(31);
    request.mutable_goal()->mutable_cell()->set_y(31);
    return request;
  }

  // An in-flight async Plan call.
  struct AsyncCall {
    grpc::ClientContext context;
    v1::PlanRequest request = Request();
    v1::PlanResponse response;
    std::promise<grpc::Status> done;
  };
  std::unique_ptr<AsyncCall> StartPlan(std::chrono::seconds timeout) {
    auto call = std::make_unique<AsyncCall>();
    call->context.set_deadline(std::chrono::system_clock::now() + timeout);
    AsyncCall* raw = call.get();
    stub_->async()->Plan(&raw->context, &raw->request, &raw->response,
                         [raw](grpc::Status s) { raw->done.set_value(std::move(s)); });
    return call;
  }

  MapStore store_{1 << 20};
  InflationCache inflation_{4};
  IncrementalCache cache_{inflation_, size_t{1} << 20};
  std::unique_ptr<WorkerPool> pool_;
  std::unique_ptr<NavigationSessions> sessions_;
  std::unique_ptr<PlannerServiceImpl> service_;
  std::unique_ptr<grpc::Server> server_;
  std::unique_ptr<v1::PlannerService::Stub> stub_;
  absl::Notification release_;
};

TEST_F(PlanAdmissionTest, PlansRunOnceTheWorkerIsFree) {
  BlockWorker();
  auto call = StartPlan(std::chrono::seconds(60));
  WaitUntilQueued(1);
  Release();
  const grpc::Status status = call->done.get_future().get();
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_TRUE(call->response.found());
}

TEST_F(PlanAdmissionTest, FullQueueIsResourceExhausted) {
  BlockWorker();
  auto queued = StartPlan(std::chrono::seconds(60));
  WaitUntilQueued(1);  // depth 1: the queue is now full

  v1::PlanResponse response;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  const grpc::Status full = stub_->Plan(&context, Request(), &response);
  EXPECT_EQ(full.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(full.error_message(),
            "interactive work queue full (1 jobs waiting, the limit set by "
            "--queue_depth); retry in about 50 ms (trailing metadata "
            "retry-after-ms)");
  // No job has finished, so the hint is the default job time for the one
  // queued job on the one worker.
  const auto& trailers = context.GetServerTrailingMetadata();
  const auto hint = trailers.find("retry-after-ms");
  ASSERT_NE(hint, trailers.end());
  EXPECT_EQ(std::string(hint->second.data(), hint->second.size()), "50");

  Release();
  EXPECT_TRUE(queued->done.get_future().get().ok());
}

TEST_F(PlanAdmissionTest, QueuedJobDroppedAtShutdownAnswersUnavailable) {
  BlockWorker();
  auto queued = StartPlan(std::chrono::seconds(60));
  WaitUntilQueued(1);
  // Shutdown joins the blocked worker, so it runs aside; the drop answers the
  // queued call before the join.
  std::thread stopper([this] { pool_->Shutdown(WorkerPool::ShutdownMode::kDrop); });
  const grpc::Status status = queued->done.get_future().get();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_THAT(status.error_message(), HasSubstr("shutting down"));
  Release();
  stopper.join();

  v1::PlanResponse response;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  EXPECT_EQ(stub_->Plan(&context, Request(), &response).error_code(),
            grpc::StatusCode::UNAVAILABLE);
}

TEST_F(PlanAdmissionTest, CancelledWhileQueuedIsAnsweredAndDoesNotCrash) {
  BlockWorker();
  auto queued = StartPlan(std::chrono::seconds(60));
  WaitUntilQueued(1);
  queued->context.TryCancel();
  EXPECT_EQ(queued->done.get_future().get().error_code(), grpc::StatusCode::CANCELLED);
  // The job now runs after its reactor may already be done; the shared call
  // state must keep it safe.
  Release();
  WaitUntilQueueEmpty();
  // A later call still works, proving the worker survived.
  v1::PlanResponse response;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  EXPECT_TRUE(stub_->Plan(&context, Request(), &response).ok());
}

TEST_F(PlanAdmissionTest, DeadlinePassedWhileQueuedIsDeadlineExceeded) {
  BlockWorker();
  auto queued = StartPlan(std::chrono::seconds(1));
  WaitUntilQueued(1);
  // Whoever notices first (client or server) the answer is DEADLINE_EXCEEDED;
  // the worker stays blocked until the client has it.
  EXPECT_EQ(queued->done.get_future().get().error_code(),
            grpc::StatusCode::DEADLINE_EXCEEDED);
  Release();
  WaitUntilQueueEmpty();
  v1::PlanResponse response;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  EXPECT_TRUE(stub_->Plan(&context, Request(), &response).ok());
}

TEST_F(PlanAdmissionTest, PathLongerThanTheLimitIsResourceExhausted) {
  PlannerServiceImpl::Options options;
  options.max_path_points = 31;  // the diagonal of the 32 x 32 map has 32
  PlannerServiceImpl limited(store_, *pool_, inflation_, cache_, *sessions_, options);
  absl::StatusOr<testing::LoopbackServer> loopback = testing::ServeOnLoopback(&limited);
  ASSERT_TRUE(loopback.ok()) << loopback.status();
  std::unique_ptr<grpc::Server>& server = loopback->server;
  auto stub = v1::PlannerService::NewStub(loopback->channel);

  v1::PlanResponse response;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  const grpc::Status status = stub->Plan(&context, Request(), &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(status.error_message(),
            "the path has 32 points, more than the limit of 31 (--max_path_points)");
  EXPECT_EQ(response.path_size(), 0);

  // One cell shorter fits.
  v1::PlanRequest shorter = Request();
  shorter.mutable_goal()->mutable_cell()->set_x(30);
  shorter.mutable_goal()->mutable_cell()->set_y(30);
  grpc::ClientContext again;
  again.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  ASSERT_TRUE(stub->Plan(&again, shorter, &response).ok());
  EXPECT_EQ(response.path_size(), 31);
  server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(10));
}

}  // namespace
}  // namespace pathd::server

namespace pathd::server {
namespace {

// Shutting the whole daemon down with plans queued and running must answer
// every call (OK if it finished, otherwise CANCELLED / UNAVAILABLE) and
// return; whichever state each call is in when shutdown starts.
TEST(PathdServerShutdownTest, AnswersEveryInFlightPlan) {
  constexpr int kCalls = 6;
  ServerOptions options;
  options.threads = 1;
  options.queue_depth = kCalls;
  options.shutdown_grace = absl::ZeroDuration();
  testing::InProcessServer server(options);
  ASSERT_TRUE(server.Start().ok());
  ASSERT_TRUE(server.store().Create("big", *Grid::Create(400, 400), false).ok());
  v1::PlannerService::Stub* stub = &server.planner();
  struct Call {
    grpc::ClientContext context;
    v1::PlanRequest request;
    v1::PlanResponse response;
    std::promise<grpc::Status> done;
  };
  std::vector<std::unique_ptr<Call>> calls;
  for (int i = 0; i < kCalls; ++i) {
    auto call = std::make_unique<Call>();
    call->context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(120));
    call->request.set_map("big");
    call->request.set_planner(v1::PLANNER_DIJKSTRA);
    call->request.mutable_start()->mutable_cell()->set_x(0);
    call->request.mutable_start()->mutable_cell()->set_y(0);
    call->request.mutable_goal()->mutable_cell()->set_x(399);
    call->request.mutable_goal()->mutable_cell()->set_y(399 - i);
    Call* raw = call.get();
    stub->async()->Plan(&raw->context, &raw->request, &raw->response,
                        [raw](grpc::Status s) { raw->done.set_value(std::move(s)); });
    calls.push_back(std::move(call));
  }
  server.Shutdown();
  for (auto& call : calls) {
    const grpc::Status status = call->done.get_future().get();
    EXPECT_THAT(status.error_code(),
                ::testing::AnyOf(grpc::StatusCode::OK, grpc::StatusCode::CANCELLED,
                                 grpc::StatusCode::UNAVAILABLE))
        << status.error_message();
  }
}

}  // namespace
}  // namespace pathd::server
