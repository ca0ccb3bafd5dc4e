// pathctl simulate's server-free parts: the scenario file (every error names
// its key), the motion model against a numerical integration, the limit
// check, and the referee's collision, contact, arrival and deadlock rules on
// hand-made runs.
#include "client/pathctl/simulate.h"

#include <cmath>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace pathd::pathctl {
namespace {

using ::testing::HasSubstr;

constexpr char kScenario[] = R"(
map: room
step: 0.01
control_period: 0.1
duration: 30
defaults:
  radius: 0.3
  local_planner: dwa
  max_v: 0.8
  options: {horizon: 1.0}
robots:
  - {name: a, start: [1, 2, 0.5], goal: [5, 2]}
  - {start: [5, 2], goal: [1, 2], radius: 0.2, drive: omni, local_planner: firas}
obstacles:
  - {start: [3, 0], velocity: [0, 0.5], radius: 0.4}
)";

TEST(ParseScenarioTest, ReadsEveryKeyAndAppliesDefaults) {
  absl::StatusOr<SimScenario> s = ParseScenario(kScenario, "s.yaml");
  ASSERT_TRUE(s.ok()) << s.status();
  EXPECT_EQ(s->map, "room");
  EXPECT_DOUBLE_EQ(s->step, 0.01);
  ASSERT_EQ(s->robots.size(), 2u);
  const SimRobotSpec& a = s->robots[0];
  EXPECT_EQ(a.name, "a");
  EXPECT_DOUBLE_EQ(a.start_yaw, 0.5);
  EXPECT_DOUBLE_EQ(a.radius, 0.3);
  EXPECT_EQ(a.local_planner, v1::LOCAL_PLANNER_DWA);
  EXPECT_DOUBLE_EQ(a.limits.max_v(), 0.8);
  EXPECT_DOUBLE_EQ(a.limits.max_w(), 1.5);  // the documented default
  EXPECT_DOUBLE_EQ(a.local_options.at("horizon"), 1.0);
  const SimRobotSpec& b = s->robots[1];
  EXPECT_EQ(b.name, "r1");
  EXPECT_DOUBLE_EQ(b.radius, 0.2);
  EXPECT_TRUE(b.limits.holonomic());
  EXPECT_DOUBLE_EQ(b.limits.max_vy(), 0.8);  // max_v when holonomic
  EXPECT_EQ(b.local_planner, v1::LOCAL_PLANNER_FIRAS);
  ASSERT_EQ(s->obstacles.size(), 1u);
  EXPECT_DOUBLE_EQ(s->obstacles[0].vy, 0.5);
}

TEST(ParseScenarioTest, ErrorsNameTheKey) {
  const struct {
    std::string yaml;
    std::string message;
  } kCases[] = {
      {"robots: [{start: [0, 0], goal: [1, 1]}]", "map: missing"},
      {"map: m", "robots: missing"},
      {"map: m\nrobots: [{start: [0, 0]}]", "robots[0] (r0): goal missing"},
      {"map: m\nrobots: [{start: [0], goal: [1, 1]}]", "robots[0].start: expected [x, y]"},
      {"map: m\nrobots: [{start: [0, x], goal: [1, 1]}]", "robots[0].start[1]: 'x' is not a number"},
      {"map: m\nrobots: [{start: [0, 0], goal: [1, 1], radius: -1}]", "robots[0].radius: must be > 0"},
      {"map: m\nrobots: [{start: [0, 0], goal: [1, 1], speed: 1}]", "robots[0].speed: unknown robot key"},
      {"map: m\nrobots: [{start: [0, 0], goal: [1, 1], local_planner: rrt}]",
       "robots[0].local_planner: 'rrt' is not dwa, orca or firas"},
      {"map: m\nrobots: [{start: [0, 0], goal: [1, 1], drive: car}]", "robots[0].drive: must be diff"},
      {"map: m\nrobots: [{start: [0, 0], goal: [1, 1], min_v: 0.2}]", "robots[0].min_v: must be <= 0"},
      {"map: m\nstep: 0\nrobots: [{start: [0, 0], goal: [1, 1]}]", "step: must be > 0"},
      {"map: m\nstep: 0.2\nrobots: [{start: [0, 0], goal: [1, 1]}]",
       "control_period: 0.1 s is shorter than step 0.2 s"},
      {"map: m\nwind: 3\nrobots: [{start: [0, 0], goal: [1, 1]}]", "wind: unknown key"},
      {"map: m\nrobots: [{name: a, start: [0, 0], goal: [1, 1]}, {name: a, start: [2, 2], goal: [3, 3]}]",
       "robots[1].name: 'a' is also robots[0]'s"},
      {"map: m\nrobots: [{start: [0, 0], goal: [1, 1]}]\nobstacles: [{start: [1, 1]}]",
       "obstacles[0]: expected start"},
      {"map: [", "s.yaml: not YAML"},
  };
  for (const auto& c : kCases) {
    absl::StatusOr<SimScenario> s = ParseScenario(c.yaml, "s.yaml");
    ASSERT_FALSE(s.ok()) << c.yaml;
    EXPECT_EQ(s.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(s.status().message(), HasSubstr(c.message)) << c.yaml;
  }
}

TEST(ParseScenarioTest, MapFileIsRelativeToTheScenario) {
  absl::StatusOr<SimScenario> s = ParseScenario(
      "map: m\nmap_file: room.map\nmap_resolution: 0.1\nrobots: [{start: [0, 0], goal: [1, 1]}]",
      "examples/simulate/x.yaml");
  ASSERT_TRUE(s.ok()) << s.status();
  EXPECT_EQ(s->map_file, "examples/simulate/room.map");
  EXPECT_DOUBLE_EQ(s->map_resolution, 0.1);
}

// A numerical integration in many small steps, apart from the closed form.
SimPose Numerical(SimPose p, double v, double vy, double w, double seconds) {
  const int steps = 200000;
  const double h = seconds / steps;
  for (int i = 0; i < steps; ++i) {
    const double mid = p.yaw + 0.5 * w * h;
    p.x += (v * std::cos(mid) - vy * std::sin(mid)) * h;
    p.y += (v * std::sin(mid) + vy * std::cos(mid)) * h;
    p.yaw += w * h;
  }
  return p;
}

TEST(IntegrateBodyTest, MatchesANumericalIntegration) {
  const SimPose start{1.0, -2.0, 0.7};
  const double cases[][3] = {{0.5, 0.0, 0.0}, {0.5, 0.0, 1.2}, {-0.3, 0.0, -2.0},
                             {0.4, 0.3, 0.8}, {0.0, 0.5, -1.0}, {0.0, 0.0, 3.0}};
  for (const auto& c : cases) {
    const SimPose exact = IntegrateBody(start, c[0], c[1], c[2], 1.7);
    const SimPose num = Numerical(start, c[0], c[1], c[2], 1.7);
    EXPECT_NEAR(exact.x, num.x, 1e-6) << c[0] << " " << c[1] << " " << c[2];
    EXPECT_NEAR(exact.y, num.y, 1e-6);
    EXPECT_NEAR(std::remainder(exact.yaw - num.yaw, 2 * M_PI), 0.0, 1e-9);
  }
}

TEST(LimitViolationTest, NamesTheLimit) {
  v1::VelocityLimits limits;
  limits.set_max_v(1.0);
  limits.set_max_w(1.0);
  limits.set_acc_v(1.0);
  limits.set_acc_vy(1.0);
  limits.set_acc_w(2.0);
  EXPECT_EQ(LimitViolation(limits, 0.5, 0, 0.1, 0.45, 0, 0.0, 0.1), "");
  EXPECT_THAT(LimitViolation(limits, 1.1, 0, 0, 1.0, 0, 0, 0.1), HasSubstr("v 1.1000 m/s outside"));
  EXPECT_THAT(LimitViolation(limits, -0.1, 0, 0, 0, 0, 0, 0.1), HasSubstr("outside [0, 1]"));
  EXPECT_THAT(LimitViolation(limits, 0, 0.1, 0, 0, 0, 0, 0.1), HasSubstr("vy"));
  EXPECT_THAT(LimitViolation(limits, 0.5, 0, 0, 0.3, 0, 0, 0.1), HasSubstr("acc_v allows 0.1"));
  EXPECT_THAT(LimitViolation(limits, 0, 0, 0.5, 0, 0, 0.2, 0.1), HasSubstr("acc_w allows 0.2"));
}

Grid OpenRoom() {
  // 20 x 20 cells at 0.1 m; a blocked cell at (10, 10).
  Grid grid = *Grid::Create(20, 20);
  grid.set_resolution(0.1);
  grid.set_cost(10, 10, kLethalCost);
  return grid;
}

SimScenario TwoRobots() {
  SimScenario s;
  s.map = "room";
  s.control_period = 0.1;
  s.deadlock_window = 1.0;
  s.deadlock_distance = 0.05;
  for (int i = 0; i < 2; ++i) {
    SimRobotSpec r;
    r.name = i == 0 ? "a" : "b";
    r.radius = 0.2;
    r.goal_tolerance = 0.1;
    s.robots.push_back(r);
  }
  s.robots[0].start_x = 0.5;
  s.robots[0].start_y = 0.5;
  s.robots[0].goal_x = 1.5;
  s.robots[0].goal_y = 0.5;
  s.robots[1].start_x = 0.5;
  s.robots[1].start_y = 1.5;
  s.robots[1].goal_x = 1.5;
  s.robots[1].goal_y = 1.5;
  return s;
}

TEST(SimRefereeTest, CountsAContactOnceAndTracksTheSmallestGap) {
  const Grid grid = OpenRoom();
  const SimScenario s = TwoRobots();
  SimReferee referee(s, grid);
  referee.Observe(0.0, {{0.5, 0.5, 0}, {0.5, 1.5, 0}}, {});
  EXPECT_TRUE(referee.contacts().empty());
  // 0.38 apart: overlapping discs of 0.2 for two steps, then apart again.
  referee.Observe(0.1, {{0.5, 0.5, 0}, {0.5, 0.88, 0}}, {});
  referee.Observe(0.2, {{0.5, 0.5, 0}, {0.5, 0.89, 0}}, {});
  referee.Observe(0.3, {{0.5, 0.5, 0}, {0.5, 1.5, 0}}, {});
  ASSERT_EQ(referee.contacts().size(), 1u);
  EXPECT_THAT(referee.contacts()[0].what, HasSubstr("a and b collide"));
  EXPECT_NEAR(referee.min_separation(), -0.02, 1e-12);
  EXPECT_EQ(referee.min_separation_pair(), "a and b");
}

TEST(SimRefereeTest, SeesTheMapAndMovingObstacles) {
  const Grid grid = OpenRoom();
  SimScenario s = TwoRobots();
  s.obstacles.push_back({0.0, 0.0, 0.0, 0.0, 0.1});
  SimReferee referee(s, grid);
  // Robot a's disc reaches into cell (10, 10) = [1.0, 1.1]^2: centre 0.15
  // left of it at mid-height.
  referee.Observe(0.0, {{0.85, 1.05, 0}, {0.5, 1.5, 0}}, {{1.5, 0.2, 0}});
  ASSERT_EQ(referee.contacts().size(), 1u);
  EXPECT_THAT(referee.contacts()[0].what, HasSubstr("a touches an obstacle cell"));
  // 0.21 from the cell: clear. Then b meets the moving obstacle.
  referee.Observe(0.1, {{0.79, 1.05, 0}, {1.5, 0.45, 0}}, {{1.5, 0.2, 0}});
  ASSERT_EQ(referee.contacts().size(), 2u);
  EXPECT_THAT(referee.contacts()[1].what, HasSubstr("b hits moving obstacle 0"));
  // Leaving the map counts too.
  referee.Observe(0.2, {{-0.1, 1.0, 0}, {1.5, 1.5, 0}}, {{1.5, 0.2, 0}});
  ASSERT_EQ(referee.contacts().size(), 3u);
}

TEST(SimRefereeTest, ArrivalNeedsTheGoalAndDeadlockNeedsAWholeWindow) {
  const Grid grid = OpenRoom();
  const SimScenario s = TwoRobots();
  SimReferee referee(s, grid);
  // a claims the goal too far away: refused with a reason; then near it.
  referee.ReportGoalReached(0, 1.0, {1.2, 0.5, 0});
  EXPECT_FALSE(referee.arrived(0));
  referee.ReportGoalReached(0, 2.0, {1.45, 0.52, 0});
  EXPECT_TRUE(referee.arrived(0));
  // b stands still: not stuck before a full window has passed.
  double t = 0.0;
  for (; t < 0.95; t += 0.1) {
    referee.Observe(t, {{1.45, 0.52, 0}, {0.5, 1.5, 0}}, {});
    EXPECT_FALSE(referee.AllSettled(t)) << t;
  }
  for (; t < 1.5; t += 0.1) referee.Observe(t, {{1.45, 0.52, 0}, {0.5, 1.5, 0}}, {});
  EXPECT_TRUE(referee.AllSettled(t));
  referee.Finish(t);
  EXPECT_EQ(referee.results()[1].end, SimEnd::kDeadlocked);
  EXPECT_THAT(referee.results()[1].detail, HasSubstr("moved less than 0.05 m in the last 1 s"));
  EXPECT_EQ(referee.results()[0].end, SimEnd::kArrived);
}

TEST(SimRefereeTest, AMovingRobotTimesOutAndAnUnreachableOneSaysWhy) {
  const Grid grid = OpenRoom();
  SimScenario s = TwoRobots();
  SimReferee referee(s, grid);
  referee.SetUnreachable(1, "no global path: goal blocked");
  double x = 0.5;
  for (double t = 0; t < 2.0; t += 0.1, x += 0.02) {
    referee.Observe(t, {{x, 0.5, 0}, {0.5, 1.5, 0}}, {});
  }
  EXPECT_FALSE(referee.AllSettled(2.0));
  referee.Finish(2.0);
  EXPECT_EQ(referee.results()[0].end, SimEnd::kTimedOut);
  EXPECT_THAT(referee.results()[0].detail, HasSubstr("still moving"));
  EXPECT_EQ(referee.results()[1].end, SimEnd::kUnreachable);
  EXPECT_NEAR(referee.results()[0].distance, 0.38, 1e-9);
}

}  // namespace
}  // namespace pathd::pathctl
