// Refused calls must not let a caller grow the log at will (issue 15): the
// limiter's rule on a fake clock, then a real PathdServer with --auth_tokens
// refusing many token-less calls while its log is captured and its lines
// counted.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/time/clock.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "server/auth.h"
#include "server/request_log.h"
#include "server/server.h"

namespace pathd::server {
namespace {

namespace fs = std::filesystem;

TEST(LogRateLimiterTest, OneLinePerIntervalPerKeyWithTheSuppressedCount) {
  LogRateLimiter limiter(absl::Seconds(1));
  const absl::Time t0 = absl::FromUnixSeconds(1000);
  int64_t suppressed = -1;
  ASSERT_TRUE(limiter.ShouldLog("a", t0, &suppressed));
  EXPECT_EQ(suppressed, 0);
  for (int i = 0; i < 5; ++i) {
    EXPECT_FALSE(limiter.ShouldLog("a", t0 + absl::Milliseconds(100 * i), &suppressed));
  }
  // Another reason has its own budget.
  ASSERT_TRUE(limiter.ShouldLog("b", t0, &suppressed));
  EXPECT_EQ(suppressed, 0);
  // A second later "a" logs again and reports the five it held back.
  ASSERT_TRUE(limiter.ShouldLog("a", t0 + absl::Seconds(1), &suppressed));
  EXPECT_EQ(suppressed, 5);
  EXPECT_EQ(limiter.suppressed_total(), 5);
}

TEST(LogRateLimiterTest, ManyDistinctKeysShareOneBucket) {
  LogRateLimiter limiter(absl::Seconds(1), /*max_keys=*/4);
  const absl::Time t0 = absl::FromUnixSeconds(1000);
  int written = 0;
  for (int i = 0; i < 100; ++i) {
    int64_t suppressed = 0;
    if (limiter.ShouldLog(absl::StrCat("key", i), t0, &suppressed)) ++written;
  }
  // Three keys of their own plus the shared bucket.
  EXPECT_EQ(written, 4);
  EXPECT_EQ(limiter.suppressed_total(), 96);
}

// Before the fix every refused call wrote a 226-byte info line.
TEST(RefusalLogTest, ManyRefusedCallsWriteAFewLinesCountingTheRest) {
  char dir_template[] = "/tmp/pathd_refusal_log_XXXXXX";
  ASSERT_NE(mkdtemp(dir_template), nullptr);
  const fs::path dir = dir_template;
  {
    std::ofstream tokens(dir / "tokens.yaml");
    tokens << "tokens:\n  - {name: robot, role: read, token: "
              "0123456789abcdef0123456789abcdef}\n";
  }
  fs::permissions(dir / "tokens.yaml", fs::perms::owner_read | fs::perms::owner_write);

  auto log = std::make_shared<std::ostringstream>();
  auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(*log);
  auto previous = spdlog::default_logger();
  spdlog::set_default_logger(std::make_shared<spdlog::logger>("capture", sink));
  spdlog::set_level(spdlog::level::info);

  ServerOptions options;
  options.address = "127.0.0.1:0";
  options.threads = 1;
  options.auth_tokens = (dir / "tokens.yaml").string();
  options.shutdown_grace = absl::Seconds(2);
  constexpr int kCalls = 300;
  absl::Duration elapsed;
  {
    PathdServer server(options);
    ASSERT_TRUE(server.Start().ok());
    auto stub = v1::MapService::NewStub(
        grpc::CreateChannel(server.listen_address(), grpc::InsecureChannelCredentials()));
    const absl::Time start = absl::Now();
    for (int i = 0; i < kCalls; ++i) {
      grpc::ClientContext context;
      context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
      v1::ListMapsResponse response;
      const grpc::Status status = stub->ListMaps(&context, v1::ListMapsRequest(), &response);
      ASSERT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED);
    }
    elapsed = absl::Now() - start;
  }
  spdlog::set_default_logger(previous);

  int lines = 0;
  bool counted = false;
  for (absl::string_view line : absl::StrSplit(log->str(), '\n')) {
    if (!absl::StrContains(line, "refused ListMaps")) continue;
    ++lines;
    counted = counted || absl::StrContains(line, "more refusals like it not logged");
  }
  // One reason: at most one line per started second of the run (plus one for
  // the first), however many calls; every other one counted.
  const int64_t bound = 2 + absl::ToInt64Seconds(elapsed);
  std::printf("%d refused calls in %s wrote %d log line(s)\n", kCalls,
              absl::FormatDuration(elapsed).c_str(), lines);
  EXPECT_GE(lines, 1);
  EXPECT_LE(lines, bound) << log->str();
  if (lines > 1) EXPECT_TRUE(counted) << log->str();
  fs::remove_all(dir);
}

}  // namespace
}  // namespace pathd::server
