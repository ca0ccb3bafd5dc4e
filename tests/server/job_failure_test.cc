// A job that throws inside the worker pool (issue 15: std::bad_alloc in a
// Navigate job under an address-space cap) must still answer its call,
// release what it held and let the server shut down. The failure is injected
// with WorkerPool::FailNextJobsForTesting on a real PathdServer; the answers,
// the metrics and the shutdown are checked. Waits are hang guards only.
#include <chrono>
#include <future>
#include <memory>
#include <string>
#include <thread>

#include <curl/curl.h>
#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>

#include "absl/strings/str_cat.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "server/server.h"

namespace pathd::server {
namespace {

using ::testing::HasSubstr;

constexpr auto kHangGuard = std::chrono::seconds(60);

std::chrono::system_clock::time_point Deadline() {
  return std::chrono::system_clock::now() + kHangGuard;
}

size_t AppendToString(char* data, size_t size, size_t count, void* out) {
  static_cast<std::string*>(out)->append(data, size * count);
  return size * count;
}

std::string Scrape(int port) {
  std::unique_ptr<CURL, decltype(&curl_easy_cleanup)> curl(curl_easy_init(),
                                                           &curl_easy_cleanup);
  const std::string url = absl::StrCat("http://127.0.0.1:", port, "/metrics");
  std::string body;
  curl_easy_setopt(curl.get(), CURLOPT_URL, url.c_str());
  curl_easy_setopt(curl.get(), CURLOPT_WRITEFUNCTION, &AppendToString);
  curl_easy_setopt(curl.get(), CURLOPT_WRITEDATA, &body);
  curl_easy_setopt(curl.get(), CURLOPT_TIMEOUT_MS, 30000L);
  EXPECT_EQ(curl_easy_perform(curl.get()), CURLE_OK);
  return body;
}

v1::Position CellPosition(int x, int y) {
  v1::Position p;
  p.mutable_cell()->set_x(x);
  p.mutable_cell()->set_y(y);
  return p;
}

TEST(JobFailureTest, ThrowingJobsAnswerReleaseAndShutdownCompletes) {
  ServerOptions options;
  options.address = "127.0.0.1:0";
  options.metrics_address = "127.0.0.1:0";
  options.threads = 1;
  options.shutdown_grace = absl::Seconds(2);
  auto server = std::make_unique<PathdServer>(options);
  ASSERT_TRUE(server->Start().ok());
  auto channel =
      grpc::CreateChannel(server->listen_address(), grpc::InsecureChannelCredentials());
  auto maps = v1::MapService::NewStub(channel);
  auto planner = v1::PlannerService::NewStub(channel);
  {
    v1::CreateMapRequest request;
    request.set_name("open");
    request.mutable_raw()->set_width(32);
    request.mutable_raw()->set_height(32);
    request.mutable_raw()->set_cells(std::string(32 * 32, '\0'));
    v1::CreateMapResponse response;
    grpc::ClientContext context;
    context.set_deadline(Deadline());
    ASSERT_TRUE(maps->CreateMap(&context, request, &response).ok());
  }
  WorkerPool& pool = *server->worker_pool_for_testing();

  // A Plan whose job throws is answered RESOURCE_EXHAUSTED (before the fix it
  // was never answered: the client waited for its deadline).
  pool.FailNextJobsForTesting(1);
  {
    v1::PlanRequest request;
    request.set_map("open");
    *request.mutable_start() = CellPosition(0, 0);
    *request.mutable_goal() = CellPosition(31, 31);
    v1::PlanResponse response;
    grpc::ClientContext context;
    context.set_deadline(Deadline());
    const grpc::Status status = planner->Plan(&context, request, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED)
        << status.error_message();
    EXPECT_THAT(status.error_message(), HasSubstr("out of memory"));
  }

  // A Navigate message whose job throws ends the session with
  // RESOURCE_EXHAUSTED and the session is no longer counted.
  pool.FailNextJobsForTesting(1);
  {
    grpc::ClientContext context;
    context.set_deadline(Deadline());
    auto stream = planner->Navigate(&context);
    v1::NavigateRequest open;
    open.set_seq(1);
    open.mutable_open()->set_map("open");
    *open.mutable_open()->mutable_start() = CellPosition(0, 0);
    *open.mutable_open()->mutable_goal() = CellPosition(31, 31);
    ASSERT_TRUE(stream->Write(open));
    v1::NavigateResponse response;
    EXPECT_FALSE(stream->Read(&response));
    const grpc::Status status = stream->Finish();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED)
        << status.error_message();
  }
  // OnDone (which unregisters) may run just after the client saw the end.
  const auto guard = std::chrono::steady_clock::now() + kHangGuard;
  while (server->navigation_sessions().count() != 0 &&
         std::chrono::steady_clock::now() < guard) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(server->navigation_sessions().count(), 0);
  EXPECT_EQ(pool.job_failures(), 2);

  // Counted in the metrics: the failures and the answers' codes.
  const std::string metrics = Scrape(server->metrics_port());
  EXPECT_THAT(metrics, HasSubstr("pathd_worker_job_failures_total 2"));
  EXPECT_THAT(metrics,
              HasSubstr(R"(pathd_requests_total{code="RESOURCE_EXHAUSTED",rpc="Navigate"} 1)"));
  EXPECT_THAT(metrics,
              HasSubstr(R"(pathd_requests_total{code="RESOURCE_EXHAUSTED",rpc="Plan"} 1)"));

  // The server still serves, and shuts down (before the fix, an unanswered
  // call held grpc::Server::Shutdown forever).
  {
    v1::PlanRequest request;
    request.set_map("open");
    *request.mutable_start() = CellPosition(0, 0);
    *request.mutable_goal() = CellPosition(31, 31);
    v1::PlanResponse response;
    grpc::ClientContext context;
    context.set_deadline(Deadline());
    EXPECT_TRUE(planner->Plan(&context, request, &response).ok());
  }
  channel.reset();
  maps.reset();
  planner.reset();
  std::future<void> shut_down =
      std::async(std::launch::async, [&server] { server->Shutdown(); });
  if (shut_down.wait_for(kHangGuard) != std::future_status::ready) {
    ADD_FAILURE() << "Shutdown did not return";
    std::_Exit(1);  // the hung server cannot be destroyed
  }
}

}  // namespace
}  // namespace pathd::server
