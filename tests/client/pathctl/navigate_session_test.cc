// Tests of the pathctl navigate driver against an in-process fake
// PlannerService whose Navigate answers every message with a straight path
// and can push unasked paths: the driver's waits, follow, expect-push, JSON
// output and error reporting, independent of the real server's planning.
#include "client/pathctl/navigate_session.h"

#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/match.h"
#include "absl/strings/str_split.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "client/client.h"
#include "client/pathctl/navigate_script.h"
#include "google/protobuf/util/json_util.h"
#include "grpcpp/server.h"
#include "grpcpp/server_builder.h"
#include "gtest/gtest.h"
#include "pathd/v1/planner_service.grpc.pb.h"

namespace pathd::pathctl {
namespace {

// Observations with this cost are refused, ending the stream like a real
// server's INVALID_ARGUMENT.
constexpr uint32_t kRefusedCost = 77;

class FakePlanner final : public v1::PlannerService::Service {
 public:
  // Answer every observation with an extra MAP_CHANGED push, as the server
  // does for sessions whose path another client's update changed.
  bool push_after_observe = false;
  // Report "no path" instead of a straight line.
  bool no_path = false;

  std::vector<std::pair<int, int>> poses() {
    absl::MutexLock lock(&mu_);
    return poses_;
  }

  grpc::Status Navigate(
      grpc::ServerContext* /*context*/,
      grpc::ServerReaderWriter<v1::NavigateResponse, v1::NavigateRequest>* stream)
      override {
    v1::NavigateRequest request;
    v1::Cell robot, goal;
    while (stream->Read(&request)) {
      v1::NavigateResponse response;
      response.set_seq(request.seq());
      response.set_session_id(7);
      switch (request.kind_case()) {
        case v1::NavigateRequest::kOpen:
          robot = request.open().start().cell();
          goal = request.open().goal().cell();
          response.set_event(v1::NAVIGATE_EVENT_OPENED);
          break;
        case v1::NavigateRequest::kPose: {
          robot = request.pose().cell();
          absl::MutexLock lock(&mu_);
          poses_.emplace_back(robot.x(), robot.y());
          response.set_event(v1::NAVIGATE_EVENT_MOVED);
          break;
        }
        case v1::NavigateRequest::kObserve:
          if (request.observe().changes(0).cost() == kRefusedCost) {
            return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                                "observation cost 77 refused");
          }
          response.set_event(v1::NAVIGATE_EVENT_OBSERVED);
          response.set_applied_version(2);
          break;
        default:
          return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, "empty message");
      }
      FillPath(robot, goal, response.mutable_plan());
      stream->Write(response);
      if (request.has_observe() && push_after_observe) {
        response.set_seq(0);
        response.set_event(v1::NAVIGATE_EVENT_MAP_CHANGED);
        response.set_applied_version(0);
        stream->Write(response);
      }
    }
    return grpc::Status::OK;
  }

 private:
  // One step towards the goal per cell, diagonally first.
  void FillPath(v1::Cell at, const v1::Cell& goal, v1::PlanResponse* plan) const {
    plan->set_map_version(1);
    if (no_path) {
      plan->set_outcome(v1::PLAN_OUTCOME_NO_PATH);
      return;
    }
    plan->set_found(true);
    plan->set_outcome(v1::PLAN_OUTCOME_FOUND);
    *plan->add_path() = at;
    while (at.x() != goal.x() || at.y() != goal.y()) {
      at.set_x(at.x() + (goal.x() > at.x()) - (goal.x() < at.x()));
      at.set_y(at.y() + (goal.y() > at.y()) - (goal.y() < at.y()));
      *plan->add_path() = at;
    }
    plan->set_cost(plan->path_size() - 1);
  }

  absl::Mutex mu_;
  std::vector<std::pair<int, int>> poses_ ABSL_GUARDED_BY(mu_);
};

class NavigateSessionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    grpc::ServerBuilder builder;
    builder.RegisterService(&fake_);
    server_ = builder.BuildAndStart();
    ASSERT_NE(server_, nullptr);
    // Generous: only a broken driver or fake ever waits this long.
    client_ = std::make_unique<client::PathdClient>(
        server_->InProcessChannel(grpc::ChannelArguments()), absl::Seconds(30));
  }

  void TearDown() override { server_->Shutdown(); }

  static v1::NavigateOpen Open(int sx, int sy, int gx, int gy) {
    v1::NavigateOpen open;
    open.set_map("room");
    open.mutable_start()->mutable_cell()->set_x(sx);
    open.mutable_start()->mutable_cell()->set_y(sy);
    open.mutable_goal()->mutable_cell()->set_x(gx);
    open.mutable_goal()->mutable_cell()->set_y(gy);
    return open;
  }

  static std::vector<ScriptStep> Script(const std::string& text) {
    auto steps = ParseNavigateScript(text, "test.nav");
    EXPECT_TRUE(steps.ok()) << steps.status();
    return steps.ok() ? *steps : std::vector<ScriptStep>{};
  }

  absl::Status Run(const v1::NavigateOpen& open, const std::string& script,
                   bool json = false) {
    out_.str("");
    return RunNavigateSession(*client_, open, Script(script), json, out_);
  }

  FakePlanner fake_;
  std::unique_ptr<grpc::Server> server_;
  std::unique_ptr<client::PathdClient> client_;
  std::ostringstream out_;
};

TEST_F(NavigateSessionTest, WithoutScriptPrintsTheFirstPathAndCloses) {
  ASSERT_TRUE(Run(Open(3, 0, 0, 0), "").ok()) << out_.str();
  EXPECT_EQ(out_.str(),
            "> open room (3,0) -> (0,0)\n"
            "[OPENED] seq 1, session 7, map version 1: found, cost 3.000000, 4 "
            "cells, 0 expansions\n"
            "  path (4 cells): (3,0) (2,0) (1,0) (0,0)\n"
            "closed: 1 answer, 0 unasked paths\n");
}

TEST_F(NavigateSessionTest, FollowDrivesAlongThePathAndStopsAtTheGoal) {
  ASSERT_TRUE(Run(Open(3, 3, 0, 1), "move 3 2\nfollow 10\n").ok()) << out_.str();
  // From (3,2) the fake's path is (2,1) (1,1) (0,1).
  const std::vector<std::pair<int, int>> expected = {
      {3, 2}, {2, 1}, {1, 1}, {0, 1}};
  EXPECT_EQ(fake_.poses(), expected);
  EXPECT_TRUE(absl::StrContains(out_.str(), "> step 3/10: pose (0,1)\n"))
      << out_.str();
  EXPECT_TRUE(
      absl::StrContains(out_.str(), "  at the goal (0,1) after 3 of 10 steps\n"))
      << out_.str();
  EXPECT_TRUE(absl::StrContains(out_.str(), "closed: 5 answers, 0 unasked paths"))
      << out_.str();
}

TEST_F(NavigateSessionTest, ExpectPushClaimsAPushedPath) {
  fake_.push_after_observe = true;
  // The first push may arrive before or during expect-push; either counts.
  ASSERT_TRUE(Run(Open(3, 0, 0, 0),
                  "block 1 1\nexpect-push 30000\nprivate free 1 1\n"
                  "expect-push 30000\n")
                  .ok())
      << out_.str();
  EXPECT_TRUE(absl::StrContains(
      out_.str(),
      "[OBSERVED] seq 2, session 7, map version 1: found, cost 3.000000, 4 "
      "cells, 0 expansions, observation applied as map version 2\n"))
      << out_.str();
  EXPECT_TRUE(absl::StrContains(out_.str(), "[MAP_CHANGED, unasked] seq 0"))
      << out_.str();
  EXPECT_TRUE(absl::StrContains(out_.str(), "closed: 3 answers, 2 unasked paths"))
      << out_.str();
}

TEST_F(NavigateSessionTest, ExpectPushFailsWithoutAPush) {
  // One push, two expectations: the second has nothing to claim.
  fake_.push_after_observe = true;
  const absl::Status status =
      Run(Open(3, 0, 0, 0), "block 1 1\nexpect-push\nexpect-push 20\n");
  EXPECT_EQ(status.code(), absl::StatusCode::kDeadlineExceeded) << status;
  EXPECT_TRUE(absl::StrContains(status.message(), "test.nav:3: expect-push"))
      << status;
}

TEST_F(NavigateSessionTest, FollowWithoutAPathFails) {
  fake_.no_path = true;
  const absl::Status status = Run(Open(3, 0, 0, 0), "follow 2\n");
  EXPECT_EQ(status.code(), absl::StatusCode::kFailedPrecondition) << status;
  EXPECT_TRUE(absl::StrContains(status.message(), "test.nav:1: follow"))
      << status;
  EXPECT_TRUE(absl::StrContains(out_.str(), "no path (NO_PATH)")) << out_.str();
}

TEST_F(NavigateSessionTest, TheServersErrorEndsTheRun) {
  const absl::Status status =
      Run(Open(3, 0, 0, 0), "cost 1 1 77\nmove 2 0\nfollow 5\n");
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << status;
  EXPECT_EQ(status.message(), "observation cost 77 refused");
  EXPECT_TRUE(fake_.poses().empty());
}

TEST_F(NavigateSessionTest, JsonPrintsOneResponsePerLine) {
  fake_.push_after_observe = true;
  ASSERT_TRUE(Run(Open(2, 0, 0, 0), "move 1 0\nblock 0 1\nexpect-push\n",
                  /*json=*/true)
                  .ok());
  const std::vector<std::string> lines =
      absl::StrSplit(out_.str(), '\n', absl::SkipEmpty());
  ASSERT_EQ(lines.size(), 4u) << out_.str();
  std::vector<v1::NavigateEvent> events;
  for (const std::string& line : lines) {
    v1::NavigateResponse response;
    ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(line, &response).ok())
        << line;
    events.push_back(response.event());
  }
  EXPECT_EQ(events, (std::vector<v1::NavigateEvent>{
                        v1::NAVIGATE_EVENT_OPENED, v1::NAVIGATE_EVENT_MOVED,
                        v1::NAVIGATE_EVENT_OBSERVED,
                        v1::NAVIGATE_EVENT_MAP_CHANGED}));
}

}  // namespace
}  // namespace pathd::pathctl
