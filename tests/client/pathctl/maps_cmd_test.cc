// pathctl's maps commands against an in-process fake MapService: what
// `maps set` / `maps rect` put on the wire, and what never reaches it
// (inverted rectangle corners, map names the server would refuse, flags
// the command does not read).
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/synchronization/mutex.h"
#include "client/pathctl/command.h"
#include "grpcpp/server.h"
#include "grpcpp/server_builder.h"
#include "gtest/gtest.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "tests/client/pathctl/command_fixture.h"

namespace pathd::pathctl {
namespace {

// Records every UpdateMap and answers version 2.
class FakeMaps final : public v1::MapService::Service {
 public:
  grpc::Status UpdateMap(grpc::ServerContext*, const v1::UpdateMapRequest* request,
                         v1::UpdateMapResponse* response) override {
    absl::MutexLock lock(&mu_);
    updates_.push_back(*request);
    response->set_version(2);
    response->set_cells_changed(1);
    return grpc::Status::OK;
  }

  std::vector<v1::UpdateMapRequest> updates() {
    absl::MutexLock lock(&mu_);
    return updates_;
  }

 private:
  absl::Mutex mu_;
  std::vector<v1::UpdateMapRequest> updates_ ABSL_GUARDED_BY(mu_);
};

using MapsCmdTest = CommandTest<FakeMaps>;

TEST_F(MapsCmdTest, RectSendsTheCornersAsGiven) {
  ASSERT_EQ(Ctl({"maps", "rect", "room", "1", "2", "3", "4", "lethal"}), kExitOk)
      << err_.str();
  const std::vector<v1::UpdateMapRequest> updates = fake_.updates();
  ASSERT_EQ(updates.size(), 1u);
  const v1::CellChange& change = updates[0].changes(0);
  EXPECT_EQ(change.rect().x_min(), 1);
  EXPECT_EQ(change.rect().y_min(), 2);
  EXPECT_EQ(change.rect().x_max(), 3);
  EXPECT_EQ(change.rect().y_max(), 4);
  EXPECT_EQ(change.cost(), 254u);
  EXPECT_EQ(out_.str(), "map room now at version 2 (1 cell changed)\n");
}

// Regression: inverted corners were swapped silently, though the API
// refuses them; now pathctl refuses them with the server's message.
TEST_F(MapsCmdTest, RectRefusesInvertedCornersWithoutACall) {
  EXPECT_EQ(Ctl({"maps", "rect", "room", "3", "2", "1", "4", "lethal"}), kExitError);
  EXPECT_EQ(err_.str(),
            "error: INVALID_ARGUMENT: change 0: rect (3, 2)-(1, 4) has min > max\n");
  EXPECT_EQ(Ctl({"maps", "rect", "room", "1", "4", "3", "2", "0"}), kExitError);
  EXPECT_TRUE(fake_.updates().empty());
}

TEST_F(MapsCmdTest, SetSendsTheExpectedVersion) {
  options_.maps.expected_version = 7;
  options_.given_flags = {"expected_version"};
  ASSERT_EQ(Ctl({"maps", "set", "room", "5", "6", "free"}), kExitOk) << err_.str();
  ASSERT_EQ(fake_.updates().size(), 1u);
  EXPECT_EQ(fake_.updates()[0].expected_version(), 7u);
  EXPECT_EQ(fake_.updates()[0].name(), "room");
}

TEST_F(MapsCmdTest, BadNamesAndForeignFlagsNeverReachTheServer) {
  EXPECT_EQ(Ctl({"maps", "set", std::string(100 * 1024, 'm'), "0", "0", "1"}), kExitError);
  EXPECT_TRUE(absl::StartsWith(err_.str(), "error: INVALID_ARGUMENT: map name is 102400"))
      << err_.str();
  EXPECT_EQ(Ctl({"maps", "set", "bad name", "0", "0", "1"}), kExitError);
  options_.given_flags = {"planner"};
  EXPECT_EQ(Ctl({"maps", "set", "room", "0", "0", "1"}), kExitUsage);
  EXPECT_TRUE(absl::StartsWith(err_.str(), "error: --planner does not apply to maps set"))
      << err_.str();
  EXPECT_TRUE(fake_.updates().empty());
}

}  // namespace
}  // namespace pathd::pathctl
