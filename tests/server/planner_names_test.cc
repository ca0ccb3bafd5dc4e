// The wire planner table (proto/planner_names.h) against the core registry:
// every wire planner names a registered planner and every registered planner
// has a wire value, so a planner added on one side only fails here.
#include "proto/planner_names.h"

#include <algorithm>
#include <string>
#include <vector>

#include "core/search/registry.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/convert.h"

namespace pathd {
namespace {

TEST(PlannerNames, WireNamesAndRegistryNamesAreTheSameSet) {
  std::vector<std::string> wire;
  for (const WirePlanner& p : WirePlanners()) wire.push_back(p.name);
  std::sort(wire.begin(), wire.end());
  EXPECT_THAT(wire, ::testing::ElementsAreArray(PlannerRegistry::Default().Names()));
}

TEST(PlannerNames, NamesRoundTripAndFollowTheEnumSuffix) {
  ASSERT_FALSE(WirePlanners().empty());
  for (const WirePlanner& p : WirePlanners()) {
    EXPECT_EQ(WirePlannerFromName(p.name), p.wire) << p.name;
    EXPECT_EQ(WirePlannerName(p.wire), p.name);
  }
  EXPECT_EQ(WirePlannerName(v1::PLANNER_WEIGHTED_ASTAR), "weighted_astar");
  EXPECT_EQ(WirePlannerName(v1::PLANNER_DSTAR_LITE), "dstar_lite");
  EXPECT_EQ(WirePlannerName(v1::PLANNER_UNSPECIFIED), std::nullopt);
  EXPECT_EQ(WirePlannerName(9999), std::nullopt);
  EXPECT_EQ(WirePlannerFromName("PLANNER_ASTAR"), std::nullopt);
  EXPECT_EQ(WirePlannerFromName(""), std::nullopt);
}

TEST(PlannerNames, UnspecifiedMeansAStarOnTheServer) {
  EXPECT_EQ(server::PlannerName(v1::PLANNER_UNSPECIFIED).value(), "astar");
  EXPECT_FALSE(server::PlannerName(9999).ok());
}

}  // namespace
}  // namespace pathd
