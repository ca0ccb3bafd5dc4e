// Prometheus metrics of a real PathdServer: requests over gRPC on
// 127.0.0.1:0, then GET /metrics over HTTP (libcurl) on the metrics port and
// the samples checked by name and labels. Nothing asserts on timing.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <thread>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <curl/curl.h>
#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "server/metrics.h"
#include "server/server.h"
#include "tests/testing/in_process_server.h"
#include "tests/testing/requests.h"

namespace pathd::server {
namespace {

using ::testing::Contains;
using ::testing::HasSubstr;
using ::testing::Key;
using ::testing::Not;

size_t AppendToString(char* data, size_t size, size_t count, void* out) {
  static_cast<std::string*>(out)->append(data, size * count);
  return size * count;
}

// GET http://127.0.0.1:`port`/metrics; the body, or "" with a test failure.
std::string Scrape(int port, long timeout_ms = 30000) {
  std::unique_ptr<CURL, decltype(&curl_easy_cleanup)> curl(curl_easy_init(),
                                                           &curl_easy_cleanup);
  EXPECT_NE(curl, nullptr);
  if (curl == nullptr) return "";
  const std::string url = absl::StrCat("http://127.0.0.1:", port, "/metrics");
  std::string body;
  curl_easy_setopt(curl.get(), CURLOPT_URL, url.c_str());
  curl_easy_setopt(curl.get(), CURLOPT_WRITEFUNCTION, &AppendToString);
  curl_easy_setopt(curl.get(), CURLOPT_WRITEDATA, &body);
  curl_easy_setopt(curl.get(), CURLOPT_TIMEOUT_MS, timeout_ms);
  const CURLcode code = curl_easy_perform(curl.get());
  EXPECT_EQ(code, CURLE_OK) << curl_easy_strerror(code);
  long http_status = 0;
  curl_easy_getinfo(curl.get(), CURLINFO_RESPONSE_CODE, &http_status);
  EXPECT_EQ(http_status, 200);
  return body;
}

// Samples of a text exposition by their printed series name,
// e.g. `pathd_requests_total{code="OK",rpc="Plan"}` (prometheus-cpp prints
// labels sorted by name).
std::map<std::string, double> ParseSamples(const std::string& text) {
  std::map<std::string, double> samples;
  for (absl::string_view line : absl::StrSplit(text, '\n', absl::SkipEmpty())) {
    if (line[0] == '#') continue;
    const size_t space = line.rfind(' ');
    double value = 0.0;
    EXPECT_TRUE(absl::SimpleAtod(line.substr(space + 1), &value)) << line;
    samples[std::string(line.substr(0, space))] = value;
  }
  return samples;
}

class MetricsTest : public ::testing::Test {
 protected:
  void StartServer(absl::Duration slow_threshold = absl::Seconds(1)) {
    ServerOptions options = testing::TestServerOptions();
    options.metrics_address = "127.0.0.1:0";
    options.slow_request_threshold = slow_threshold;
    server_ = std::make_unique<testing::InProcessServer>(options);
    const absl::Status started = server_->Start();
    ASSERT_TRUE(started.ok()) << started;
    ASSERT_GT(server_->metrics_port(), 0);
    maps_ = &server_->maps();
    planner_ = &server_->planner();
  }

  static void Prepare(grpc::ClientContext& context) { testing::SetDeadline(context); }

  // An all-free w x h map.
  grpc::Status CreateFree(const std::string& name, int w, int h) {
    return server_->CreateFreeMap(name, w, h);
  }

  grpc::Status Plan(const std::string& map, v1::Planner planner) {
    const v1::PlanRequest request = testing::PlanBetween(map, 0, 0, 7, 5, planner);
    v1::PlanResponse response;
    grpc::ClientContext context;
    Prepare(context);
    return planner_->Plan(&context, request, &response);
  }

  std::map<std::string, double> Samples() {
    return ParseSamples(Scrape(server_->metrics_port()));
  }

  std::unique_ptr<testing::InProcessServer> server_;
  v1::MapService::Stub* maps_ = nullptr;
  v1::PlannerService::Stub* planner_ = nullptr;
};

TEST_F(MetricsTest, CountsRequestsByRpcAndCodeAndReadsServerState) {
  StartServer();
  ASSERT_TRUE(CreateFree("a", 8, 6).ok());
  ASSERT_TRUE(CreateFree("b", 4, 4).ok());
  ASSERT_TRUE(Plan("a", v1::PLANNER_ASTAR).ok());
  ASSERT_TRUE(Plan("a", v1::PLANNER_ASTAR).ok());
  // The same goal twice: the shortest path map is built once, then reused.
  ASSERT_TRUE(Plan("a", v1::PLANNER_SPM).ok());
  ASSERT_TRUE(Plan("a", v1::PLANNER_SPM).ok());
  // Rejected before any planner is known.
  EXPECT_EQ(Plan("a", static_cast<v1::Planner>(999)).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
  {
    v1::GetMapRequest request;
    request.set_name("missing");
    v1::GetMapResponse response;
    grpc::ClientContext context;
    Prepare(context);
    EXPECT_EQ(maps_->GetMap(&context, request, &response).error_code(),
              grpc::StatusCode::NOT_FOUND);
  }
  {
    v1::UpdateMapRequest request;
    request.set_name("a");
    v1::CellChange* change = request.add_changes();
    change->mutable_cell()->set_x(3);
    change->mutable_cell()->set_y(3);
    change->set_cost(254);
    v1::UpdateMapResponse response;
    grpc::ClientContext context;
    Prepare(context);
    ASSERT_TRUE(maps_->UpdateMap(&context, request, &response).ok());
  }
  // An open WatchMap stream: its first event (the whole map) means the
  // server has registered it.
  grpc::ClientContext watch_context;
  v1::WatchMapRequest watch_request;
  watch_request.set_name("b");
  std::unique_ptr<grpc::ClientReader<v1::MapEvent>> watch =
      maps_->WatchMap(&watch_context, watch_request);
  v1::MapEvent event;
  ASSERT_TRUE(watch->Read(&event));

  const std::map<std::string, double> s = Samples();
  EXPECT_EQ(s.at(R"(pathd_requests_total{code="OK",rpc="CreateMap"})"), 2);
  EXPECT_EQ(s.at(R"(pathd_requests_total{code="OK",rpc="Plan"})"), 4);
  EXPECT_EQ(s.at(R"(pathd_requests_total{code="INVALID_ARGUMENT",rpc="Plan"})"), 1);
  EXPECT_EQ(s.at(R"(pathd_requests_total{code="NOT_FOUND",rpc="GetMap"})"), 1);
  EXPECT_EQ(s.at(R"(pathd_requests_total{code="OK",rpc="UpdateMap"})"), 1);
  EXPECT_THAT(s, Not(Contains(Key(HasSubstr(R"(code="OK",rpc="GetMap")")))));

  // Every Plan in the RPC histogram; only those with a planner per planner.
  EXPECT_EQ(s.at(R"(pathd_request_duration_seconds_count{rpc="Plan"})"), 5);
  EXPECT_EQ(s.at(R"(pathd_request_duration_seconds_bucket{rpc="Plan",le="+Inf"})"), 5);
  EXPECT_EQ(s.at(R"(pathd_plan_duration_seconds_count{planner="astar"})"), 2);
  EXPECT_EQ(s.at(R"(pathd_plan_duration_seconds_count{planner="spm"})"), 2);
  EXPECT_EQ(s.at(R"(pathd_plan_duration_seconds_bucket{planner="spm",le="60"})"), 2);
  EXPECT_THAT(s, Not(Contains(Key(HasSubstr(R"(planner="-")")))));
  // Nothing took a second.
  EXPECT_THAT(s, Not(Contains(Key(HasSubstr("pathd_slow_requests_total{")))));

  EXPECT_EQ(s.at("pathd_maps"), 2);
  EXPECT_EQ(s.at(R"(pathd_map_version{map="a"})"), 2);
  EXPECT_EQ(s.at(R"(pathd_map_version{map="b"})"), 1);
  EXPECT_EQ(s.at(R"(pathd_cache_misses_total{cache="spm"})"), 1);
  EXPECT_EQ(s.at(R"(pathd_cache_hits_total{cache="spm"})"), 1);
  EXPECT_EQ(s.at(R"(pathd_cache_entries{cache="spm"})"), 1);
  EXPECT_GT(s.at(R"(pathd_cache_bytes{cache="spm"})"), 0);
  EXPECT_EQ(s.at(R"(pathd_cache_budget_bytes{cache="spm"})"),
            static_cast<double>(server_->options().cache_bytes / 2));
  EXPECT_EQ(s.at(R"(pathd_cache_hits_total{cache="inflation"})"), 0);
  // Shaped grids advanced from an older version's and shaped in full.
  EXPECT_EQ(s.at(R"(pathd_cache_repairs_total{cache="inflation"})"), 0);
  EXPECT_EQ(s.at(R"(pathd_cache_rebuilds_total{cache="inflation"})"), 0);
  EXPECT_EQ(s.at("pathd_worker_threads"), 2);
  EXPECT_EQ(s.at(R"(pathd_queue_capacity{priority="interactive"})"), 64);
  EXPECT_EQ(s.at(R"(pathd_queue_capacity{priority="batch"})"),
            static_cast<double>(server_->options().batch_queue_depth));
  EXPECT_EQ(s.at(R"(pathd_queued_jobs{priority="interactive"})"), 0);
  EXPECT_EQ(s.at(R"(pathd_queued_jobs{priority="batch"})"), 0);
  // Four plans ran on the workers.
  EXPECT_GT(s.at("pathd_worker_busy_seconds_total"), 0);
  EXPECT_EQ(s.at("pathd_map_watchers"), 1);
  EXPECT_EQ(s.at("pathd_navigate_sessions"), 0);
  // No control session ran: an empty latency histogram, no robots.
  EXPECT_EQ(s.at("pathd_control_cycle_seconds_count"), 0);
  EXPECT_EQ(s.at(R"(pathd_control_cycle_seconds_bucket{le="+Inf"})"), 0);

  watch_context.TryCancel();
  v1::MapEvent ignored;
  while (watch->Read(&ignored)) {
  }
  EXPECT_EQ(watch->Finish().error_code(), grpc::StatusCode::CANCELLED);
}

TEST_F(MetricsTest, MapVersionSeriesAreBoundedAndMapsCountsAll) {
  StartServer();
  const int maps = static_cast<int>(ServerMetrics::kMaxMapSeries) + 5;
  for (int i = 0; i < maps; ++i) {
    ASSERT_TRUE(CreateFree(absl::StrFormat("m%03d", i), 1, 1).ok());
  }
  const std::map<std::string, double> s = Samples();
  EXPECT_EQ(s.at("pathd_maps"), maps);
  int series = 0;
  for (const auto& [name, value] : s) {
    if (name.starts_with("pathd_map_version{")) ++series;
  }
  EXPECT_EQ(series, static_cast<int>(ServerMetrics::kMaxMapSeries));
  // The first ones by name are kept.
  EXPECT_THAT(s, Contains(Key(R"(pathd_map_version{map="m000"})")));
  EXPECT_THAT(s, Contains(Key(R"(pathd_map_version{map="m099"})")));
  EXPECT_THAT(s, Not(Contains(Key(R"(pathd_map_version{map="m100"})"))));
}

TEST_F(MetricsTest, SlowRequestsCountedButNotStreams) {
  // Every request is at least a nanosecond old when it answers.
  StartServer(absl::Nanoseconds(1));
  ASSERT_TRUE(CreateFree("a", 8, 6).ok());
  ASSERT_TRUE(Plan("a", v1::PLANNER_DIJKSTRA).ok());
  {
    grpc::ClientContext context;
    Prepare(context);
    v1::WatchMapRequest request;
    request.set_name("a");
    std::unique_ptr<grpc::ClientReader<v1::MapEvent>> watch =
        maps_->WatchMap(&context, request);
    v1::MapEvent event;
    ASSERT_TRUE(watch->Read(&event));
    // Deleting the map ends the stream (DELETED event, then OK).
    v1::DeleteMapRequest del;
    del.set_name("a");
    v1::DeleteMapResponse deleted;
    grpc::ClientContext delete_context;
    Prepare(delete_context);
    ASSERT_TRUE(maps_->DeleteMap(&delete_context, del, &deleted).ok());
    while (watch->Read(&event)) {
    }
    ASSERT_TRUE(watch->Finish().ok());
  }
  // The stream's own line is written when it answers, before the client sees
  // the end; the next scrape therefore counts it.
  const std::map<std::string, double> s = Samples();
  EXPECT_EQ(s.at(R"(pathd_slow_requests_total{rpc="CreateMap"})"), 1);
  EXPECT_EQ(s.at(R"(pathd_slow_requests_total{rpc="Plan"})"), 1);
  EXPECT_EQ(s.at(R"(pathd_slow_requests_total{rpc="DeleteMap"})"), 1);
  EXPECT_EQ(s.at(R"(pathd_requests_total{code="OK",rpc="WatchMap"})"), 1);
  EXPECT_THAT(s, Not(Contains(Key(R"(pathd_slow_requests_total{rpc="WatchMap"})"))));
}

TEST_F(MetricsTest, MetricsAddressInUseFailsStart) {
  StartServer();
  ServerOptions options;
  options.address = "127.0.0.1:0";
  options.threads = 1;
  options.metrics_address = absl::StrCat("127.0.0.1:", server_->metrics_port());
  PathdServer second(options);
  const absl::Status started = second.Start();
  EXPECT_EQ(started.code(), absl::StatusCode::kUnavailable) << started;
  EXPECT_THAT(started.message(), HasSubstr(options.metrics_address));
  EXPECT_EQ(second.port(), 0);
  // The first server's metrics are still served and still counted.
  ASSERT_TRUE(CreateFree("a", 2, 2).ok());
  EXPECT_EQ(Samples().at(R"(pathd_requests_total{code="OK",rpc="CreateMap"})"), 1);
}

// Issue 15: two sockets that sent half a "GET /metrics" and then nothing held
// both of the exposer's threads until civetweb's 30 s request timeout, so
// every scrape meanwhile timed out. Now more sockets than that stall and a
// scrape is still answered at once; its timeout (15 s, a hang guard) is half
// of what the stalled sockets would have held it before the fix.
TEST_F(MetricsTest, ScrapeAnsweredWhileSocketsHoldPartialRequests) {
  StartServer();
  constexpr int kStalled = 6;
  std::vector<int> stalled;
  for (int i = 0; i < kStalled; ++i) {
    const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    ASSERT_GE(fd, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<uint16_t>(server_->metrics_port()));
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)), 0);
    const std::string partial = "GET /metrics HTTP/1.1\r\nHost: x\r\n";
    ASSERT_EQ(send(fd, partial.data(), partial.size(), MSG_NOSIGNAL),
              static_cast<ssize_t>(partial.size()));
    stalled.push_back(fd);
  }
  // Give the server time to hand every stalled socket a thread (a scrape
  // landing first would pass without the fix too); not an assertion.
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  for (int round = 0; round < 3; ++round) {
    const std::string body = Scrape(server_->metrics_port(), /*timeout_ms=*/15000);
    EXPECT_THAT(body, HasSubstr("pathd_worker_threads")) << "round " << round;
  }
  for (const int fd : stalled) close(fd);
}

TEST_F(MetricsTest, NoMetricsAddressServesNoMetrics) {
  ServerOptions options;
  options.address = "127.0.0.1:0";
  options.threads = 1;
  PathdServer server(options);
  ASSERT_TRUE(server.Start().ok());
  EXPECT_EQ(server.metrics_port(), 0);
}

}  // namespace
}  // namespace pathd::server
