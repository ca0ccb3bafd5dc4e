// pathctl plan and batch as library calls: the Plan request built from the
// plan flags (planner, via points, cost options) against an in-process fake
// PlannerService, and the batch file parser's line errors.
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/synchronization/mutex.h"
#include "client/pathctl/batch_cmd.h"
#include "client/pathctl/command.h"
#include "grpcpp/server.h"
#include "grpcpp/server_builder.h"
#include "gtest/gtest.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "tests/client/pathctl/command_fixture.h"

namespace pathd::pathctl {
namespace {

// Answers every Plan with a two-cell path and keeps the requests.
class FakePlanner final : public v1::PlannerService::Service {
 public:
  grpc::Status Plan(grpc::ServerContext*, const v1::PlanRequest* request,
                    v1::PlanResponse* response) override {
    {
      absl::MutexLock lock(&mu_);
      requests_.push_back(*request);
    }
    response->set_found(true);
    response->set_outcome(v1::PLAN_OUTCOME_FOUND);
    response->set_planner("dijkstra");
    *response->add_path() = request->start().cell();
    *response->add_path() = request->goal().cell();
    response->set_cost(1.5);
    response->set_length(1.5);
    return grpc::Status::OK;
  }

  std::vector<v1::PlanRequest> requests() {
    absl::MutexLock lock(&mu_);
    return requests_;
  }

 private:
  absl::Mutex mu_;
  std::vector<v1::PlanRequest> requests_ ABSL_GUARDED_BY(mu_);
};

using PlanCmdTest = CommandTest<FakePlanner>;

TEST_F(PlanCmdTest, BuildsTheRequestFromItsFlags) {
  options_.plan.planner = "dijkstra";
  options_.plan.via = "5,6;7,8";
  options_.cost.connectivity = 4;
  options_.cost.robot_radius_cells = 1.5;
  options_.given_flags = {"planner", "via", "connectivity", "robot_radius_cells"};
  ASSERT_EQ(Ctl({"plan", "room", "1", "2", "3", "4"}), kExitOk) << err_.str();
  const std::vector<v1::PlanRequest> requests = fake_.requests();
  ASSERT_EQ(requests.size(), 1u);
  const v1::PlanRequest& r = requests[0];
  EXPECT_EQ(r.map(), "room");
  EXPECT_EQ(r.planner(), v1::PLANNER_DIJKSTRA);
  EXPECT_EQ(r.start().cell().x(), 1);
  EXPECT_EQ(r.goal().cell().y(), 4);
  ASSERT_EQ(r.via_size(), 2);
  EXPECT_EQ(r.via(1).cell().x(), 7);
  EXPECT_EQ(r.options().connectivity(), v1::CONNECTIVITY_FOUR);
  EXPECT_EQ(r.options().robot_radius_cells(), 1.5);
  EXPECT_TRUE(absl::StartsWith(out_.str(), "found:       yes\n")) << out_.str();
  EXPECT_TRUE(absl::StrContains(out_.str(), "path (2 cells): (1,2) (3,4)")) << out_.str();
}

TEST_F(PlanCmdTest, BadOptionsAreUsageErrorsBeforeTheCall) {
  options_.plan.planner = "warp";
  EXPECT_EQ(Ctl({"plan", "room", "1", "2", "3", "4"}), kExitUsage);
  EXPECT_TRUE(absl::StrContains(err_.str(), "unknown planner 'warp'")) << err_.str();
  options_.plan.planner = "";
  options_.plan.via = "5;6";
  EXPECT_EQ(Ctl({"plan", "room", "1", "2", "3", "4"}), kExitUsage);
  EXPECT_TRUE(absl::StrContains(err_.str(), "--via point 1: '5' is not X,Y")) << err_.str();
  EXPECT_TRUE(fake_.requests().empty());
}

TEST(ParseBatchFileTest, NamesTheLineOfABadMapName) {
  absl::StatusOr<std::vector<BatchItem>> items =
      ParseBatchFile("# comment\nq1 room 0 0 1 1\nq2 a/b 0 0 1 1\n", "f.txt", false);
  ASSERT_FALSE(items.ok());
  EXPECT_TRUE(absl::StartsWith(items.status().message(),
                               "f.txt:3: map name 'a/b' has character 0x2f"))
      << items.status();
  items = ParseBatchFile("q1 room 0 0 1 1 astar\n", "f.txt", false);
  ASSERT_TRUE(items.ok()) << items.status();
  EXPECT_EQ((*items)[0].request.planner(), v1::PLANNER_ASTAR);
}

}  // namespace
}  // namespace pathd::pathctl
