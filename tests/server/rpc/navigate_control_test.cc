// Control sessions (docs/service.md, "Control sessions") over a real gRPC
// channel to a PathdServer: every command checked against the limits and the
// dynamic window the test sent, robots simulated by the test's own
// integrator (written apart from core/local) until they reach the goal
// without touching a wall (exact disc-to-square distances), two robots
// heading at each other kept apart by ORCA across sessions, reported and
// stale neighbours, closed sessions, repairs after a map change. No timing
// assertion: sleeps only exceed the thresholds under test.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "tests/testing/in_process_server.h"

namespace pathd::server {
namespace {

using ::testing::HasSubstr;

constexpr double kRes = 0.1;  // metres per cell in every map here
constexpr double kEps = 1e-6;

// The robot in the test's own model: a unicycle (or an omnidirectional
// base), world frame, metres.
struct Sim {
  double x = 0, y = 0, yaw = 0;
  double v = 0, vy = 0, w = 0;

  // Holds (v, vy, w) for `dt`: exact arcs for the unicycle, fine sub-steps
  // for the sideways part.
  void Step(double cv, double cvy, double cw, double dt) {
    const int n = 50;
    const double h = dt / n;
    for (int i = 0; i < n; ++i) {
      const double mid = yaw + cw * h / 2;
      x += (cv * std::cos(mid) - cvy * std::sin(mid)) * h;
      y += (cv * std::sin(mid) + cvy * std::cos(mid)) * h;
      yaw += cw * h;
    }
    v = cv;
    vy = cvy;
    w = cw;
  }
};

struct Limits {
  double max_v = 0.5, max_w = 1.5, acc_v = 1.0, acc_w = 3.0, max_vy = 0.0, acc_vy = 1.0;
  bool holonomic = false;
};

// One control session, lock-step: each state is answered before the next.
class ControlClient {
 public:
  explicit ControlClient(v1::PlannerService::Stub& stub) {
    context_.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(120));
    stream_ = stub.Navigate(&context_);
  }

  v1::NavigateResponse Open(const std::string& map, double sx, double sy, double gx,
                            double gy, v1::LocalPlanner planner, const Limits& limits,
                            double radius, double stale_after = 0, double forget_after = 0) {
    v1::NavigateRequest request;
    request.set_seq(1);
    v1::NavigateOpen* open = request.mutable_open();
    open->set_map(map);
    open->mutable_start()->mutable_world()->set_x(sx);
    open->mutable_start()->mutable_world()->set_y(sy);
    open->mutable_goal()->mutable_world()->set_x(gx);
    open->mutable_goal()->mutable_world()->set_y(gy);
    open->mutable_options()->set_robot_radius_m(radius);
    // Nav2-style inflation costs keep the global path off the corners, where
    // DWA's checker (radius + margins) would refuse to follow it.
    if (inflation_costs) open->mutable_options()->set_inflation_radius_m(radius + 0.3);
    for (const auto& [name, value] : local_options) {
      (*open->mutable_control()->mutable_local_options())[name] = value;
    }
    v1::ControlOptions* control = open->mutable_control();
    control->set_local_planner(planner);
    control->mutable_limits()->set_max_v(limits.max_v);
    control->mutable_limits()->set_max_w(limits.max_w);
    control->mutable_limits()->set_acc_v(limits.acc_v);
    control->mutable_limits()->set_acc_w(limits.acc_w);
    control->mutable_limits()->set_holonomic(limits.holonomic);
    if (limits.holonomic) {
      control->mutable_limits()->set_max_vy(limits.max_vy);
      control->mutable_limits()->set_acc_vy(limits.acc_vy);
    }
    control->set_control_period(0.1);
    control->set_stale_after(stale_after);
    control->set_forget_after(forget_after);
    return Exchange(request);
  }

  v1::NavigateResponse Send(const Sim& sim, double stamp,
                            const std::vector<v1::MovingObstacleReport>& obstacles = {}) {
    v1::NavigateRequest request;
    request.set_seq(++seq_);
    v1::RobotState* state = request.mutable_state();
    state->mutable_pose()->mutable_world_pose()->set_x(sim.x);
    state->mutable_pose()->mutable_world_pose()->set_y(sim.y);
    state->mutable_pose()->mutable_world_pose()->set_yaw(sim.yaw);
    state->set_v(sim.v);
    state->set_vy(sim.vy);
    state->set_w(sim.w);
    state->set_stamp(stamp);
    for (const auto& o : obstacles) *state->add_obstacles() = o;
    v1::NavigateResponse response = Exchange(request);
    EXPECT_EQ(response.seq(), seq_);
    return response;
  }

  v1::NavigateResponse Exchange(const v1::NavigateRequest& request) {
    v1::NavigateResponse response;
    EXPECT_TRUE(stream_->Write(request));
    EXPECT_TRUE(stream_->Read(&response)) << stream_->Finish().error_message();
    return response;
  }

  // Set before Open: options of the local planner, and whether the path
  // keeps off the walls by inflation costs.
  std::map<std::string, double> local_options;
  bool inflation_costs = true;

  grpc::Status Close() {
    stream_->WritesDone();
    v1::NavigateResponse ignored;
    while (stream_->Read(&ignored)) {
    }
    return stream_->Finish();
  }

  // Sends one request and returns the status the server ends the call with.
  grpc::Status SendExpectingEnd(const v1::NavigateRequest& request) {
    stream_->Write(request);
    v1::NavigateResponse ignored;
    while (stream_->Read(&ignored)) {
    }
    return stream_->Finish();
  }

 private:
  grpc::ClientContext context_;
  std::unique_ptr<grpc::ClientReaderWriter<v1::NavigateRequest, v1::NavigateResponse>>
      stream_;
  uint64_t seq_ = 1;
};

// The command against the limits and the window reachable in one period
// from the reported velocity.
void ExpectAdmissible(const v1::VelocityCommand& c, const Sim& before, const Limits& l) {
  const double period = 0.1;
  EXPECT_LE(c.v(), l.max_v + kEps);
  EXPECT_GE(c.v(), 0.0 - kEps);  // min_v 0: no reversing
  EXPECT_LE(std::fabs(c.w()), l.max_w + kEps);
  EXPECT_LE(std::fabs(c.v() - before.v), l.acc_v * period + kEps)
      << "v " << before.v << " -> " << c.v();
  EXPECT_LE(std::fabs(c.w() - before.w), l.acc_w * period + kEps)
      << "w " << before.w << " -> " << c.w();
  if (l.holonomic) {
    EXPECT_LE(std::fabs(c.vy()), l.max_vy + kEps);
    EXPECT_LE(std::fabs(c.vy() - before.vy), l.acc_vy * period + kEps);
  } else {
    EXPECT_EQ(c.vy(), 0.0);
  }
}

// Distance from (x, y) to the nearest lethal cell's square, metres.
double Clearance(const std::vector<std::string>& rows, double x, double y) {
  double best = 1e9;
  for (size_t r = 0; r < rows.size(); ++r) {
    for (size_t col = 0; col < rows[r].size(); ++col) {
      if (rows[r][col] != '#') continue;
      const double x0 = col * kRes, x1 = (col + 1) * kRes;
      const double y0 = r * kRes, y1 = (r + 1) * kRes;
      const double dx = std::max({x0 - x, 0.0, x - x1});
      const double dy = std::max({y0 - y, 0.0, y - y1});
      best = std::min(best, std::hypot(dx, dy));
    }
  }
  return best;
}

class ControlTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ServerOptions options = testing::TestServerOptions();
    options.threads = 2;
    server_ = std::make_unique<testing::InProcessServer>(options);
    ASSERT_TRUE(server_->Start().ok());
  }
  void TearDown() override { server_->Shutdown(); }

  std::unique_ptr<testing::InProcessServer> server_;
};

// 40 x 30 cells (4 x 3 m) with a 0.4 x 0.8 m block in the middle the path
// bends around.
std::vector<std::string> BlockRoom() {
  std::vector<std::string> rows(30, std::string(40, '.'));
  for (int r = 11; r < 19; ++r) {
    for (int c = 18; c < 22; ++c) rows[r][c] = '#';
  }
  return rows;
}

class ControlPlannerTest : public ControlTest,
                           public ::testing::WithParamInterface<v1::LocalPlanner> {};

TEST_P(ControlPlannerTest, FollowsThePathWithinItsLimitsToTheGoal) {
  const std::vector<std::string> rows = BlockRoom();
  ASSERT_TRUE(server_->CreateMapFromRows("room", rows, kRes).ok());
  const Limits limits;
  const double radius = 0.15;
  ControlClient client(server_->planner());
  const v1::NavigateResponse opened =
      client.Open("room", 0.35, 1.45, 3.65, 1.45, GetParam(), limits, radius);
  ASSERT_EQ(opened.event(), v1::NAVIGATE_EVENT_OPENED);
  ASSERT_TRUE(opened.plan().found()) << opened.plan().reason();

  Sim sim{0.35, 1.45, 0.0};
  bool reached = false;
  std::vector<std::pair<int, int>> carried;
  for (int step = 0; step < 1000 && !reached; ++step) {
    const v1::NavigateResponse answer = client.Send(sim, step * 0.1);
    ASSERT_EQ(answer.event(), v1::NAVIGATE_EVENT_CONTROL);
    ASSERT_TRUE(answer.has_command());
    const v1::VelocityCommand& c = answer.command();
    // The first answer carries the path; later ones only a path that is
    // not the rest of the one carried before (the robot moving along it
    // replans, but that changes nothing the client needs).
    if (step == 0) EXPECT_TRUE(answer.has_plan());
    if (answer.has_plan()) {
      std::vector<std::pair<int, int>> path;
      for (const v1::Cell& cell : answer.plan().path()) path.emplace_back(cell.x(), cell.y());
      if (step > 0) {
        EXPECT_FALSE(path.size() <= carried.size() &&
                     std::equal(path.begin(), path.end(), carried.end() - path.size()))
            << "step " << step << ": the rest of the path carried again";
      }
      carried = std::move(path);
    }
    EXPECT_DOUBLE_EQ(c.stamp(), step * 0.1);
    EXPECT_EQ(c.neighbours(), 0);
    ASSERT_NE(c.outcome(), v1::LOCAL_OUTCOME_NO_PATH) << c.reason();
    ASSERT_NE(c.outcome(), v1::LOCAL_OUTCOME_BLOCKED) << c.reason();
    ASSERT_GE(c.trajectory_size(), 1);
    EXPECT_NEAR(c.trajectory(0).x(), sim.x, 1e-9);
    EXPECT_NEAR(c.trajectory(0).y(), sim.y, 1e-9);
    ExpectAdmissible(c, sim, limits);
    if (c.outcome() == v1::LOCAL_OUTCOME_GOAL_REACHED) {
      reached = true;
      break;
    }
    sim.Step(c.v(), c.vy(), c.w(), 0.1);
    ASSERT_GT(Clearance(rows, sim.x, sim.y), radius) << "step " << step;
  }
  EXPECT_TRUE(reached);
  EXPECT_LT(std::hypot(sim.x - 3.65, sim.y - 1.45), 0.1 + 1e-6);
  EXPECT_TRUE(client.Close().ok());
}

INSTANTIATE_TEST_SUITE_P(Planners, ControlPlannerTest,
                         ::testing::Values(v1::LOCAL_PLANNER_ORCA, v1::LOCAL_PLANNER_DWA),
                         [](const auto& info) {
                           return info.param == v1::LOCAL_PLANNER_ORCA ? "orca" : "dwa";
                         });

TEST_F(ControlTest, UnreachableGoalIsNoPathAndStops) {
  std::vector<std::string> rows(20, std::string(40, '.'));
  for (int r = 0; r < 20; ++r) rows[r][20] = '#';  // a wall across the room
  ASSERT_TRUE(server_->CreateMapFromRows("split", rows, kRes).ok());
  ControlClient client(server_->planner());
  const v1::NavigateResponse opened =
      client.Open("split", 0.5, 1.0, 3.5, 1.0, v1::LOCAL_PLANNER_ORCA, Limits{}, 0.15);
  EXPECT_FALSE(opened.plan().found());
  Sim sim{0.5, 1.0, 0.0, 0.0, 0.0, 0.0};
  const v1::NavigateResponse answer = client.Send(sim, 1.0);
  EXPECT_EQ(answer.command().outcome(), v1::LOCAL_OUTCOME_NO_PATH);
  EXPECT_EQ(answer.command().v(), 0.0);
  EXPECT_EQ(answer.command().w(), 0.0);
  EXPECT_THAT(answer.command().reason(), HasSubstr("no global path"));
  EXPECT_TRUE(client.Close().ok());
}

TEST_F(ControlTest, TwoRobotsHeadOnPassApart) {
  ASSERT_TRUE(server_
                  ->CreateRawMap("hall10", 80, 40, std::string(80 * 40, '\0'), kRes)
                  .ok());
  const Limits limits;
  const double ra = 0.2, rb = 0.25;
  ControlClient a(server_->planner());
  ControlClient b(server_->planner());
  ASSERT_TRUE(
      a.Open("hall10", 1.05, 2.05, 7.05, 2.05, v1::LOCAL_PLANNER_ORCA, limits, ra).plan().found());
  ASSERT_TRUE(
      b.Open("hall10", 7.05, 2.05, 1.05, 2.05, v1::LOCAL_PLANNER_ORCA, limits, rb).plan().found());
  Sim sa{1.05, 2.05, 0.0};
  Sim sb{7.05, 2.05, M_PI};
  bool a_done = false, b_done = false, saw_each_other = false;
  double closest = 1e9;
  for (int step = 0; step < 1500 && !(a_done && b_done); ++step) {
    const v1::NavigateResponse ca = a.Send(sa, step * 0.1);
    const v1::NavigateResponse cb = b.Send(sb, step * 0.1);
    ExpectAdmissible(ca.command(), sa, limits);
    ExpectAdmissible(cb.command(), sb, limits);
    // Each sees the other within ORCA's neighbour range (3 m by default;
    // 2.5 m leaves room for the extrapolation), and never more than it.
    const double gap = std::hypot(sa.x - sb.x, sa.y - sb.y);
    EXPECT_LE(ca.command().neighbours(), 1);
    EXPECT_LE(cb.command().neighbours(), 1);
    if (step > 0 && gap < 2.5) {
      EXPECT_EQ(ca.command().neighbours(), 1) << "step " << step;
      EXPECT_EQ(cb.command().neighbours(), 1) << "step " << step;
      saw_each_other = true;
    }
    a_done = a_done || ca.command().outcome() == v1::LOCAL_OUTCOME_GOAL_REACHED;
    b_done = b_done || cb.command().outcome() == v1::LOCAL_OUTCOME_GOAL_REACHED;
    if (!a_done) sa.Step(ca.command().v(), 0, ca.command().w(), 0.1);
    if (!b_done) sb.Step(cb.command().v(), 0, cb.command().w(), 0.1);
    const double d = std::hypot(sa.x - sb.x, sa.y - sb.y);
    closest = std::min(closest, d);
    ASSERT_GT(d, ra + rb) << "step " << step;
  }
  EXPECT_TRUE(saw_each_other);
  EXPECT_TRUE(a_done);
  EXPECT_TRUE(b_done);
  // Within the goal tolerance (0.1 m) of the goal cells' centres.
  EXPECT_LT(std::hypot(sa.x - 7.05, sa.y - 2.05), 0.1 + 1e-6);
  EXPECT_LT(std::hypot(sb.x - 1.05, sb.y - 2.05), 0.1 + 1e-6);
  // They did meet: the run tested the avoidance, not two distant robots.
  EXPECT_LT(closest, 2.0 * (ra + rb));
  EXPECT_TRUE(a.Close().ok());
  EXPECT_TRUE(b.Close().ok());
}

TEST_F(ControlTest, ReportedObstaclesCountForOneMessage) {
  ASSERT_TRUE(server_->CreateRawMap("yard", 60, 60, std::string(3600, '\0'), kRes).ok());
  ControlClient client(server_->planner());
  client.Open("yard", 1.0, 1.0, 5.0, 5.0, v1::LOCAL_PLANNER_ORCA, Limits{}, 0.2);
  Sim sim{1.0, 1.0, 0.0};
  v1::MovingObstacleReport person;
  person.mutable_position()->mutable_world()->set_x(1.8);
  person.mutable_position()->mutable_world()->set_y(1.2);
  person.set_vx(-0.3);
  person.set_radius(0.3);
  v1::MovingObstacleReport cart = person;
  cart.mutable_position()->mutable_world()->set_y(0.6);
  EXPECT_EQ(client.Send(sim, 0.0, {person, cart}).command().neighbours(), 2);
  EXPECT_EQ(client.Send(sim, 0.1).command().neighbours(), 0);
  EXPECT_EQ(client.Send(sim, 0.2, {person}).command().neighbours(), 1);
  EXPECT_TRUE(client.Close().ok());
}

// 60 x 30 cells (6 x 3 m) with walls round the edge and a block across the
// middle from x = 1.5 to 4.5 m: a lower passage rows 1..`lower_top`, an
// upper one rows 20..28.
std::vector<std::string> TwoPassages(int lower_top) {
  std::vector<std::string> rows(30, std::string(60, '.'));
  for (int c = 0; c < 60; ++c) rows[0][c] = rows[29][c] = '#';
  for (int r = 0; r < 30; ++r) rows[r][0] = rows[r][59] = '#';
  for (int r = lower_top + 1; r < 20; ++r) {
    for (int c = 15; c < 45; ++c) rows[r][c] = '#';
  }
  return rows;
}

struct DetourRun {
  bool reached = false;
  v1::LocalOutcome last = v1::LOCAL_OUTCOME_UNSPECIFIED;
  bool took_upper = false;  // a carried path went through the upper passage
};

// One robot (radius `radius`, no inflation costs) from (0.55, 0.55) to
// (5.45, 0.55), `blocker` (if any) reported still in the lower passage with
// every state, for at most `steps` periods; never touching a wall or the
// blocker (checked here, apart from the server).
DetourRun RunDetour(v1::PlannerService::Stub& stub, const std::string& map,
                    const std::vector<std::string>& rows, double radius,
                    const std::optional<v1::MovingObstacleReport>& blocker,
                    std::optional<double> detour_range, int steps) {
  DetourRun run;
  ControlClient client(stub);
  client.inflation_costs = false;
  if (detour_range.has_value()) client.local_options["detour_range"] = *detour_range;
  const Limits limits;
  const v1::NavigateResponse opened =
      client.Open(map, 0.55, 0.55, 5.45, 0.55, v1::LOCAL_PLANNER_ORCA, limits, radius);
  EXPECT_TRUE(opened.plan().found()) << opened.plan().reason();
  const auto upper = [](const v1::PlanResponse& plan) {
    return std::any_of(plan.path().begin(), plan.path().end(),
                       [](const v1::Cell& c) { return c.y() >= 20; });
  };
  // The premise: the first path takes the lower passage.
  EXPECT_FALSE(upper(opened.plan()));
  Sim sim{0.55, 0.55, 0.0};
  std::vector<v1::MovingObstacleReport> reports;
  if (blocker.has_value()) reports.push_back(*blocker);
  for (int step = 0; step < steps && !run.reached; ++step) {
    const v1::NavigateResponse answer = client.Send(sim, step * 0.1, reports);
    const v1::VelocityCommand& c = answer.command();
    ExpectAdmissible(c, sim, limits);
    if (answer.has_plan() && upper(answer.plan())) run.took_upper = true;
    run.last = c.outcome();
    if (c.outcome() == v1::LOCAL_OUTCOME_GOAL_REACHED) {
      run.reached = true;
      break;
    }
    sim.Step(c.v(), c.vy(), c.w(), 0.1);
    EXPECT_GT(Clearance(rows, sim.x, sim.y), radius) << "step " << step;
    if (blocker.has_value()) {
      const double gap = std::hypot(sim.x - blocker->position().world().x(),
                                    sim.y - blocker->position().world().y()) -
                         radius - blocker->radius();
      EXPECT_GT(gap, 0.0) << "step " << step;
    }
  }
  EXPECT_TRUE(client.Close().ok());
  return run;
}

TEST_F(ControlTest, AStalledRobotDetoursAroundWhatStandsInItsWay) {
  // A cart 0.6 m across stands in the middle of the 0.9 m lower passage:
  // no way past for a robot 0.3 m across. The map does not know the cart,
  // so the global path goes through it.
  const std::vector<std::string> rows = TwoPassages(9);
  ASSERT_TRUE(server_->CreateMapFromRows("passages", rows, kRes).ok());
  v1::MovingObstacleReport cart;
  cart.mutable_position()->mutable_world()->set_x(3.0);
  cart.mutable_position()->mutable_world()->set_y(0.55);
  cart.set_radius(0.3);
  // Without detours the robot stops in front of the cart for good.
  const DetourRun stuck = RunDetour(server_->planner(), "passages", rows, 0.15, cart,
                                    /*detour_range=*/0.0, 600);
  EXPECT_FALSE(stuck.reached);
  EXPECT_FALSE(stuck.took_upper);
  EXPECT_EQ(stuck.last, v1::LOCAL_OUTCOME_LOCAL_MINIMUM);
  // With them (the default) it stalls, asks for a path around the cart,
  // and arrives by the upper passage.
  const DetourRun detoured = RunDetour(server_->planner(), "passages", rows, 0.15, cart,
                                       std::nullopt, 1500);
  EXPECT_TRUE(detoured.took_upper);
  EXPECT_TRUE(detoured.reached);
}

TEST_F(ControlTest, AGapTheDiscDoesNotFitIsLeftForAnotherWay) {
  // The lower passage is 3 cells (0.3 m) high. The planning grid blocks
  // cells whose centres are within the robot's radius (1.7 cells) of a
  // wall cell's centre, so its middle row stays open: the global path goes
  // through a gap the robot's disc (0.34 m) cannot enter.
  const std::vector<std::string> rows = TwoPassages(3);
  ASSERT_TRUE(server_->CreateMapFromRows("slot", rows, kRes).ok());
  const DetourRun stuck =
      RunDetour(server_->planner(), "slot", rows, 0.17, std::nullopt, 0.0, 600);
  EXPECT_FALSE(stuck.reached);
  EXPECT_EQ(stuck.last, v1::LOCAL_OUTCOME_LOCAL_MINIMUM);
  const DetourRun detoured =
      RunDetour(server_->planner(), "slot", rows, 0.17, std::nullopt, std::nullopt, 1500);
  EXPECT_TRUE(detoured.took_upper);
  EXPECT_TRUE(detoured.reached);
}

TEST_F(ControlTest, StaleRobotsStayThenGoAndClosedSessionsGoAtOnce) {
  ASSERT_TRUE(server_->CreateRawMap("yard", 60, 60, std::string(3600, '\0'), kRes).ok());
  ControlClient watcher(server_->planner());
  watcher.Open("yard", 1.0, 1.0, 5.0, 1.0, v1::LOCAL_PLANNER_ORCA, Limits{}, 0.2);
  const Sim at{1.0, 1.0, 0.0};
  {
    // Stale after 0.2 s, forgotten after 0.6 s (its own options).
    ControlClient quiet(server_->planner());
    quiet.Open("yard", 1.8, 1.0, 1.8, 5.0, v1::LOCAL_PLANNER_ORCA, Limits{}, 0.2, 0.2, 0.6);
    quiet.Send(Sim{1.8, 1.0, M_PI / 2}, 0.0);
    EXPECT_EQ(watcher.Send(at, 0.0).command().neighbours(), 1);
    std::this_thread::sleep_for(std::chrono::milliseconds(350));
    // Stale: still an obstacle (a static one).
    EXPECT_EQ(watcher.Send(at, 0.1).command().neighbours(), 1);
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    // Forgotten.
    EXPECT_EQ(watcher.Send(at, 0.2).command().neighbours(), 0);
    // It speaks again: back.
    quiet.Send(Sim{1.8, 1.0, M_PI / 2}, 1.0);
    EXPECT_EQ(watcher.Send(at, 0.3).command().neighbours(), 1);
    EXPECT_TRUE(quiet.Close().ok());
  }
  // Closed: gone at once, long before it would be stale.
  EXPECT_EQ(watcher.Send(at, 0.4).command().neighbours(), 0);
  EXPECT_TRUE(watcher.Close().ok());
}

TEST_F(ControlTest, MapChangeRepairsThePathAndTheAnswerCarriesIt) {
  // Two ways around a pillar; the straight one is blocked later.
  std::vector<std::string> rows(30, std::string(60, '.'));
  for (int r = 12; r < 18; ++r) rows[r][30] = '#';
  ASSERT_TRUE(server_->CreateMapFromRows("pillar", rows, kRes).ok());
  ControlClient client(server_->planner());
  const v1::NavigateResponse opened =
      client.Open("pillar", 0.55, 1.55, 5.55, 1.55, v1::LOCAL_PLANNER_ORCA, Limits{}, 0.15);
  ASSERT_TRUE(opened.plan().found());
  const Sim still{0.55, 1.55, 0.0};
  const v1::NavigateResponse first = client.Send(still, 0.0);
  ASSERT_TRUE(first.has_plan());
  const uint64_t before = first.plan().map_version();
  EXPECT_EQ(first.command().map_version(), before);
  EXPECT_FALSE(client.Send(still, 0.1).has_plan());

  // Another client walls off the whole right side but a gap at the bottom.
  v1::UpdateMapRequest update;
  update.set_name("pillar");
  for (int r = 0; r < 27; ++r) {
    v1::CellChange* change = update.add_changes();
    change->mutable_cell()->set_x(45);
    change->mutable_cell()->set_y(r);
    change->set_cost(254);
  }
  v1::UpdateMapResponse updated;
  grpc::ClientContext context;
  ASSERT_TRUE(server_->maps().UpdateMap(&context, update, &updated).ok());

  // The repair runs off the control path; answers carry it once it is done
  // (hang guard: 30 s).
  std::optional<v1::NavigateResponse> repaired;
  for (int i = 0; i < 3000 && !repaired.has_value(); ++i) {
    v1::NavigateResponse answer = client.Send(still, 1.0 + i * 0.01);
    if (answer.has_plan()) {
      repaired = answer;
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  ASSERT_TRUE(repaired.has_value());
  EXPECT_GE(repaired->plan().map_version(), updated.version());
  EXPECT_EQ(repaired->command().map_version(), repaired->plan().map_version());
  ASSERT_TRUE(repaired->plan().found());
  bool through_gap = false;
  for (const v1::Cell& c : repaired->plan().path()) {
    EXPECT_FALSE(c.x() == 45 && c.y() < 27) << c.x() << "," << c.y();
    through_gap = through_gap || (c.x() == 45 && c.y() >= 27);
  }
  EXPECT_TRUE(through_gap);
  EXPECT_TRUE(client.Close().ok());
}

TEST_F(ControlTest, BudgetedReplansContinueWhileAnswersGoOn) {
  // 200 x 200 open cells, 50 expansions per replan: the open's plan and the
  // first replans run out; every state is still answered at once (NO_PATH,
  // the robot told to stand), and the next replans continue the same D* Lite
  // search until the path is found and carried.
  ASSERT_TRUE(
      server_->CreateRawMap("wide", 200, 200, std::string(200 * 200, '\0'), kRes).ok());
  ControlClient client(server_->planner());
  v1::NavigateRequest open;
  open.set_seq(1);
  open.mutable_open()->set_map("wide");
  open.mutable_open()->mutable_start()->mutable_cell()->set_x(5);
  open.mutable_open()->mutable_start()->mutable_cell()->set_y(5);
  open.mutable_open()->mutable_goal()->mutable_cell()->set_x(190);
  open.mutable_open()->mutable_goal()->mutable_cell()->set_y(190);
  open.mutable_open()->mutable_options()->set_robot_radius_m(0.2);
  open.mutable_open()->set_replan_max_expansions(50);
  open.mutable_open()->mutable_control();
  const v1::NavigateResponse opened = client.Exchange(open);
  EXPECT_EQ(opened.plan().outcome(), v1::PLAN_OUTCOME_EXPANSION_LIMIT);
  const Sim still{0.55, 0.55, 0.0};
  int no_path = 0;
  std::optional<v1::NavigateResponse> found;
  for (int i = 0; i < 20000 && !found.has_value(); ++i) {
    v1::NavigateResponse answer = client.Send(still, i * 0.1);
    if (answer.command().outcome() == v1::LOCAL_OUTCOME_NO_PATH) {
      ++no_path;
      EXPECT_EQ(answer.command().v(), 0.0);
    } else if (answer.has_plan() && answer.plan().found()) {
      found = answer;
    }
  }
  ASSERT_TRUE(found.has_value());
  EXPECT_GT(no_path, 0);
  EXPECT_NEAR(found->plan().cost(), 185 * std::sqrt(2.0), 1e-6);
  EXPECT_TRUE(client.Close().ok());
}

TEST_F(ControlTest, StateOutsideAControlSessionIsRefused) {
  ASSERT_TRUE(server_->CreateRawMap("yard", 20, 20, std::string(400, '\0'), kRes).ok());
  ControlClient client(server_->planner());
  v1::NavigateRequest open;
  open.set_seq(1);
  open.mutable_open()->set_map("yard");
  open.mutable_open()->mutable_start()->mutable_cell()->set_x(1);
  open.mutable_open()->mutable_goal()->mutable_cell()->set_x(10);
  ASSERT_EQ(client.Exchange(open).event(), v1::NAVIGATE_EVENT_OPENED);
  v1::NavigateRequest state;
  state.set_seq(2);
  state.mutable_state()->mutable_pose()->mutable_cell()->set_x(1);
  const grpc::Status status = client.SendExpectingEnd(state);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("only for control sessions"));
}

TEST_F(ControlTest, KinematicPlannerIsRefused) {
  ASSERT_TRUE(server_->CreateRawMap("yard", 20, 20, std::string(400, '\0'), kRes).ok());
  ControlClient client(server_->planner());
  v1::NavigateRequest open;
  open.set_seq(1);
  open.mutable_open()->set_map("yard");
  open.mutable_open()->set_planner(v1::PLANNER_HYBRID_ASTAR);
  open.mutable_open()->mutable_start()->mutable_cell()->set_x(1);
  open.mutable_open()->mutable_goal()->mutable_cell()->set_x(10);
  open.mutable_open()->mutable_options()->set_robot_radius_m(0.2);
  open.mutable_open()->mutable_control();
  const grpc::Status status = client.SendExpectingEnd(open);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("open.control"));
}

}  // namespace
}  // namespace pathd::server
