// Navigate sessions over a real gRPC channel to a PathdServer on
// 127.0.0.1:0: answers to every message, paths pushed when another client
// changes the map, private observations, idle expiry, bad messages, and many
// concurrent sessions checked against Dijkstra on the version each answer
// names. Waits are generous upper bounds; nothing asserts on speed except the
// issue's "pushed within one second".
#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>

#include "absl/synchronization/mutex.h"
#include "core/search/registry.h"
#include "core/search/path_measure.h"
#include "core/map/cost_model.h"
#include "core/search/planner.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "server/server.h"
#include "tests/testing/in_process_server.h"

namespace pathd::server {
namespace {

using ::testing::HasSubstr;

v1::Position CellPosition(int x, int y) {
  v1::Position p;
  p.mutable_cell()->set_x(x);
  p.mutable_cell()->set_y(y);
  return p;
}

std::vector<Cell> PathOf(const v1::PlanResponse& plan) {
  std::vector<Cell> out;
  for (const v1::Cell& c : plan.path()) out.push_back(Cell{c.x(), c.y()});
  return out;
}

bool PathHas(const v1::PlanResponse& plan, Cell cell) {
  for (const Cell& c : PathOf(plan)) {
    if (c == cell) return true;
  }
  return false;
}

// One Navigate stream with a reader thread, so pushes can be awaited with a
// timeout while the test keeps writing.
class Session {
 public:
  explicit Session(v1::PlannerService::Stub& stub) {
    context_.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(120));
    stream_ = stub.Navigate(&context_);
    reader_ = std::thread([this] {
      v1::NavigateResponse response;
      while (stream_->Read(&response)) {
        std::lock_guard<std::mutex> lock(mu_);
        responses_.push_back(response);
        cv_.notify_all();
      }
      std::lock_guard<std::mutex> lock(mu_);
      closed_ = true;
      cv_.notify_all();
    });
  }

  ~Session() {
    if (!finished_) Finish();
  }

  bool Write(const v1::NavigateRequest& request) { return stream_->Write(request); }

  bool Open(const std::string& map, Cell start, Cell goal, uint64_t seq = 1) {
    v1::NavigateRequest request;
    request.set_seq(seq);
    *request.mutable_open()->mutable_start() = CellPosition(start.x, start.y);
    *request.mutable_open()->mutable_goal() = CellPosition(goal.x, goal.y);
    request.mutable_open()->set_map(map);
    return Write(request);
  }

  bool Move(Cell to, uint64_t seq) {
    v1::NavigateRequest request;
    request.set_seq(seq);
    *request.mutable_pose() = CellPosition(to.x, to.y);
    return Write(request);
  }

  bool Observe(Cell cell, uint32_t cost, bool session_only, uint64_t seq) {
    v1::NavigateRequest request;
    request.set_seq(seq);
    v1::CellChange* change = request.mutable_observe()->add_changes();
    change->mutable_cell()->set_x(cell.x);
    change->mutable_cell()->set_y(cell.y);
    change->set_cost(cost);
    request.mutable_observe()->set_session_only(session_only);
    return Write(request);
  }

  // The next response, or nullopt when none arrives within `timeout` or the
  // stream closed.
  std::optional<v1::NavigateResponse> Next(std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mu_);
    cv_.wait_for(lock, timeout, [this] { return !responses_.empty() || closed_; });
    if (responses_.empty()) return std::nullopt;
    v1::NavigateResponse out = std::move(responses_.front());
    responses_.pop_front();
    return out;
  }

  // Closes the client side and returns the server's status.
  grpc::Status Finish() {
    finished_ = true;
    stream_->WritesDone();
    reader_.join();
    return stream_->Finish();
  }

  // Waits for the server to end the stream (without closing our side).
  grpc::Status AwaitEnd() {
    finished_ = true;
    reader_.join();
    return stream_->Finish();
  }

 private:
  grpc::ClientContext context_;
  std::unique_ptr<grpc::ClientReaderWriter<v1::NavigateRequest, v1::NavigateResponse>>
      stream_;
  std::thread reader_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<v1::NavigateResponse> responses_;
  bool closed_ = false;
  bool finished_ = false;
};

constexpr auto kAnswerWait = std::chrono::seconds(30);

class NavigationTest : public ::testing::Test {
 protected:
  void StartServer(ServerOptions options = {}) {
    options.threads = 2;
    server_ = std::make_unique<testing::InProcessServer>(options);
    // Every version of every map, so answers can be checked against the
    // version they name.
    server_->KeepMapVersions();
    ASSERT_TRUE(server_->Start().ok());
    planner_ = &server_->planner();
    maps_ = &server_->maps();
  }

  void TearDown() override {
    if (server_ != nullptr) server_->Shutdown();
  }

  void AddMap(const std::string& name, Grid grid) {
    auto created = server_->store().Create(name, std::move(grid), false);
    ASSERT_TRUE(created.ok()) << created.status();
    server_->KeepMapVersion(name, *created);
  }

  std::shared_ptr<const Grid> Version(const std::string& name, uint64_t version) {
    return server_->MapVersion(name, version);
  }

  // Another client blocks or frees cells through UpdateMap.
  uint64_t UpdateCell(const std::string& map, Cell cell, uint32_t cost) {
    v1::UpdateMapRequest request;
    request.set_name(map);
    v1::CellChange* change = request.add_changes();
    change->mutable_cell()->set_x(cell.x);
    change->mutable_cell()->set_y(cell.y);
    change->set_cost(cost);
    v1::UpdateMapResponse response;
    grpc::ClientContext context;
    const grpc::Status status = maps_->UpdateMap(&context, request, &response);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return response.version();
  }

  // Checks an answer against Dijkstra on the version it names.
  void ExpectOptimal(const std::string& map, const v1::PlanResponse& plan, Cell goal) {
    std::shared_ptr<const Grid> grid = Version(map, plan.map_version());
    ASSERT_NE(grid, nullptr) << "unknown version " << plan.map_version();
    const Cell start{plan.start().x(), plan.start().y()};
    const PlanRequest request = PlanRequest::Between(start, goal);
    if (!Traversable(grid->cost(start), request.cost.unknown_is_free)) {
      // Something was put on the robot: no path, said in the reason.
      EXPECT_FALSE(plan.found());
      EXPECT_THAT(plan.reason(), HasSubstr("start"));
      return;
    }
    SearchScratch scratch;
    auto reference = PlannerRegistry::Default().Get("dijkstra")->Plan(
        *grid, request, StopCondition::None(), scratch);
    ASSERT_TRUE(reference.ok()) << reference.status();
    ASSERT_EQ(plan.found(), reference->found())
        << "start " << CellToString(start) << " version " << plan.map_version();
    if (!plan.found()) return;
    EXPECT_NEAR(plan.cost(), reference->cost, 1e-9 * (1.0 + reference->cost));
    const PathMeasure measured = MeasurePath(*grid, PathOf(plan), request.cost);
    EXPECT_TRUE(measured.valid);
    EXPECT_NEAR(measured.cost, plan.cost(), 1e-9 * (1.0 + plan.cost()));
  }

  std::unique_ptr<testing::InProcessServer> server_;
  v1::PlannerService::Stub* planner_ = nullptr;
  v1::MapService::Stub* maps_ = nullptr;
};

Grid OpenGrid(int width, int height) { return *Grid::Create(width, height); }

TEST_F(NavigationTest, AnswersEveryMessageInOrder) {
  StartServer();
  AddMap("room", OpenGrid(10, 5));
  Session session(*planner_);
  ASSERT_TRUE(session.Open("room", {0, 2}, {9, 2}, 7));
  auto opened = session.Next(kAnswerWait);
  ASSERT_TRUE(opened.has_value());
  EXPECT_EQ(opened->seq(), 7u);
  EXPECT_EQ(opened->event(), v1::NAVIGATE_EVENT_OPENED);
  EXPECT_NE(opened->session_id(), 0u);
  ASSERT_TRUE(opened->plan().found());
  EXPECT_DOUBLE_EQ(opened->plan().cost(), 9.0);
  EXPECT_EQ(opened->plan().planner(), "dstar_lite");
  EXPECT_FALSE(opened->plan().cache_hit());

  ASSERT_TRUE(session.Move({1, 2}, 8));
  auto moved = session.Next(kAnswerWait);
  ASSERT_TRUE(moved.has_value());
  EXPECT_EQ(moved->seq(), 8u);
  EXPECT_EQ(moved->event(), v1::NAVIGATE_EVENT_MOVED);
  EXPECT_EQ(moved->session_id(), opened->session_id());
  EXPECT_TRUE(moved->plan().cache_hit());
  EXPECT_DOUBLE_EQ(moved->plan().cost(), 8.0);
  EXPECT_EQ(moved->plan().path(0).x(), 1);

  // A shared observation blocks (5, 2): the answer routes around it, names
  // the version it produced, and the map really changed.
  ASSERT_TRUE(session.Observe({5, 2}, kLethalCost, /*session_only=*/false, 9));
  auto observed = session.Next(kAnswerWait);
  ASSERT_TRUE(observed.has_value());
  EXPECT_EQ(observed->event(), v1::NAVIGATE_EVENT_OBSERVED);
  EXPECT_EQ(observed->applied_version(), 2u);
  EXPECT_EQ(observed->plan().map_version(), 2u);
  EXPECT_EQ(observed->plan().repaired_cells(), 1);
  EXPECT_FALSE(PathHas(observed->plan(), {5, 2}));
  ExpectOptimal("room", observed->plan(), {9, 2});
  EXPECT_EQ((*server_->store().Get("room"))->version, 2u);

  EXPECT_TRUE(session.Finish().ok());
}

TEST_F(NavigationTest, PushesANewPathWithinASecondWhenAnotherClientBlocksIt) {
  StartServer();
  AddMap("hall", OpenGrid(20, 7));
  Session session(*planner_);
  ASSERT_TRUE(session.Open("hall", {0, 3}, {19, 3}));
  auto opened = session.Next(kAnswerWait);
  ASSERT_TRUE(opened.has_value());
  ASSERT_TRUE(PathHas(opened->plan(), {10, 3}));

  const auto before = std::chrono::steady_clock::now();
  const uint64_t version = UpdateCell("hall", {10, 3}, kLethalCost);
  auto pushed = session.Next(std::chrono::seconds(1));
  const auto waited = std::chrono::steady_clock::now() - before;
  ASSERT_TRUE(pushed.has_value()) << "no path pushed within one second";
  EXPECT_LE(waited, std::chrono::seconds(1));
  EXPECT_EQ(pushed->event(), v1::NAVIGATE_EVENT_MAP_CHANGED);
  EXPECT_EQ(pushed->seq(), 0u);
  EXPECT_EQ(pushed->plan().map_version(), version);
  EXPECT_FALSE(PathHas(pushed->plan(), {10, 3}));
  ExpectOptimal("hall", pushed->plan(), {19, 3});

  // A change that leaves the path as it is pushes nothing; the next answer
  // still reflects the new version.
  const uint64_t quiet = UpdateCell("hall", {0, 0}, kLethalCost);
  EXPECT_FALSE(session.Next(std::chrono::milliseconds(300)).has_value());
  ASSERT_TRUE(session.Move({1, 3}, 2));
  auto moved = session.Next(kAnswerWait);
  ASSERT_TRUE(moved.has_value());
  EXPECT_EQ(moved->event(), v1::NAVIGATE_EVENT_MOVED);
  EXPECT_EQ(moved->plan().map_version(), quiet);
  EXPECT_TRUE(session.Finish().ok());
}

TEST_F(NavigationTest, SessionOnlyObservationsStayInTheSession) {
  StartServer();
  AddMap("yard", OpenGrid(9, 5));
  Session mine(*planner_);
  Session other(*planner_);
  ASSERT_TRUE(mine.Open("yard", {0, 2}, {8, 2}));
  ASSERT_TRUE(other.Open("yard", {0, 2}, {8, 2}));
  ASSERT_TRUE(mine.Next(kAnswerWait).has_value());
  ASSERT_TRUE(other.Next(kAnswerWait).has_value());

  ASSERT_TRUE(mine.Observe({4, 2}, kLethalCost, /*session_only=*/true, 2));
  auto observed = mine.Next(kAnswerWait);
  ASSERT_TRUE(observed.has_value());
  EXPECT_EQ(observed->applied_version(), 0u);
  EXPECT_EQ(observed->plan().map_version(), 1u);
  EXPECT_FALSE(PathHas(observed->plan(), {4, 2}));
  EXPECT_GT(observed->plan().cost(), 8.0);

  EXPECT_EQ((*server_->store().Get("yard"))->version, 1u);
  EXPECT_FALSE(other.Next(std::chrono::milliseconds(300)).has_value());
  ASSERT_TRUE(other.Move({1, 2}, 2));
  auto moved = other.Next(kAnswerWait);
  ASSERT_TRUE(moved.has_value());
  EXPECT_DOUBLE_EQ(moved->plan().cost(), 7.0);

  // The private cell also overrides later shared versions for its session.
  UpdateCell("yard", {4, 0}, 100);
  ASSERT_TRUE(mine.Move({1, 2}, 3));
  std::optional<v1::NavigateResponse> answer;
  do {
    answer = mine.Next(kAnswerWait);
    ASSERT_TRUE(answer.has_value());
  } while (answer->event() != v1::NAVIGATE_EVENT_MOVED);
  EXPECT_FALSE(PathHas(answer->plan(), {4, 2}));
  EXPECT_EQ(answer->plan().map_version(), 2u);
  EXPECT_TRUE(mine.Finish().ok());
  EXPECT_TRUE(other.Finish().ok());
}

TEST_F(NavigationTest, UnreachableGoalIsAnAnswerAndRecovers) {
  StartServer();
  AddMap("door", OpenGrid(5, 1));
  Session session(*planner_);
  ASSERT_TRUE(session.Open("door", {0, 0}, {4, 0}));
  ASSERT_TRUE(session.Next(kAnswerWait).has_value());
  UpdateCell("door", {2, 0}, kLethalCost);
  auto pushed = session.Next(kAnswerWait);
  ASSERT_TRUE(pushed.has_value());
  EXPECT_FALSE(pushed->plan().found());
  EXPECT_EQ(pushed->plan().outcome(), v1::PLAN_OUTCOME_NO_PATH);
  UpdateCell("door", {2, 0}, kFreeCost);
  pushed = session.Next(kAnswerWait);
  ASSERT_TRUE(pushed.has_value());
  EXPECT_TRUE(pushed->plan().found());
  EXPECT_DOUBLE_EQ(pushed->plan().cost(), 4.0);
  EXPECT_TRUE(session.Finish().ok());
}

TEST_F(NavigationTest, BadMessagesEndTheSessionWithTheProblemNamed) {
  StartServer();
  AddMap("room", OpenGrid(4, 4));
  {
    Session session(*planner_);
    ASSERT_TRUE(session.Move({1, 1}, 3));
    const grpc::Status status = session.AwaitEnd();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_THAT(status.error_message(), HasSubstr("first message"));
  }
  {
    Session session(*planner_);
    ASSERT_TRUE(session.Open("nowhere", {0, 0}, {1, 1}));
    const grpc::Status status = session.AwaitEnd();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND);
  }
  {
    Session session(*planner_);
    ASSERT_TRUE(session.Open("room", {0, 0}, {9, 1}));
    const grpc::Status status = session.AwaitEnd();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_THAT(status.error_message(), HasSubstr("goal"));
  }
  {
    Session session(*planner_);
    ASSERT_TRUE(session.Open("room", {0, 0}, {3, 3}));
    ASSERT_TRUE(session.Next(kAnswerWait).has_value());
    ASSERT_TRUE(session.Move({4, 0}, 2));
    const grpc::Status status = session.AwaitEnd();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_THAT(status.error_message(), HasSubstr("pose (4, 0)"));
  }
  {
    Session session(*planner_);
    ASSERT_TRUE(session.Open("room", {0, 0}, {3, 3}));
    ASSERT_TRUE(session.Next(kAnswerWait).has_value());
    ASSERT_TRUE(session.Observe({9, 9}, kLethalCost, false, 2));
    const grpc::Status status = session.AwaitEnd();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_THAT(status.error_message(), HasSubstr("outside"));
  }
  // The server still serves.
  Session session(*planner_);
  ASSERT_TRUE(session.Open("room", {0, 0}, {3, 3}));
  auto opened = session.Next(kAnswerWait);
  ASSERT_TRUE(opened.has_value());
  EXPECT_TRUE(opened->plan().found());
  EXPECT_TRUE(session.Finish().ok());
}

TEST_F(NavigationTest, DeletedMapEndsItsSessions) {
  StartServer();
  AddMap("gone", OpenGrid(4, 4));
  Session session(*planner_);
  ASSERT_TRUE(session.Open("gone", {0, 0}, {3, 3}));
  ASSERT_TRUE(session.Next(kAnswerWait).has_value());
  ASSERT_TRUE(server_->store().Delete("gone").ok());
  const grpc::Status status = session.AwaitEnd();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_THAT(status.error_message(), HasSubstr("deleted"));
}

TEST_F(NavigationTest, IdleSessionsExpireAndTheLimitHolds) {
  ServerOptions options;
  options.session_idle_timeout = absl::Milliseconds(200);
  options.max_sessions = 1;
  StartServer(options);
  AddMap("room", OpenGrid(4, 4));
  Session first(*planner_);
  ASSERT_TRUE(first.Open("room", {0, 0}, {3, 3}));
  ASSERT_TRUE(first.Next(kAnswerWait).has_value());
  {
    Session second(*planner_);
    // Refused at once; the write may or may not get through before that.
    second.Open("room", {0, 0}, {3, 3});
    const grpc::Status status = second.AwaitEnd();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_THAT(status.error_message(), HasSubstr("--max_sessions"));
  }
  const grpc::Status status = first.AwaitEnd();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED);
  EXPECT_THAT(status.error_message(), HasSubstr("no message"));
}

// Several robots on one map, each moving along its path and sharing what it
// sees, while another client keeps changing the map: every answer and push
// must equal Dijkstra on the version it names, and no session sees another's
// start or goal.
TEST_F(NavigationTest, ConcurrentSessionsOnOneMapDoNotInterfere) {
  StartServer();
  std::mt19937 rng(5);
  Grid grid = OpenGrid(24, 24);
  for (int i = 0; i < 60; ++i) {
    grid.set_cost(static_cast<int>(rng() % 24), static_cast<int>(rng() % 24),
                  static_cast<uint8_t>(rng() % 3 == 0 ? kLethalCost : rng() % 200));
  }
  for (Cell c : {Cell{0, 0}, Cell{23, 23}, Cell{0, 23}, Cell{23, 0}, Cell{12, 0},
                 Cell{12, 23}}) {
    grid.set_cost(c, kFreeCost);
  }
  AddMap("floor", std::move(grid));

  struct Robot {
    Cell start, goal;
  };
  const std::vector<Robot> robots = {{{0, 0}, {23, 23}}, {{23, 23}, {0, 0}},
                                     {{0, 23}, {23, 0}}, {{12, 0}, {12, 23}}};
  std::atomic<bool> stop{false};
  std::thread disturber([&] {
    std::mt19937 r(11);
    while (!stop.load()) {
      const Cell c{static_cast<int>(r() % 24), static_cast<int>(r() % 24)};
      bool endpoint = false;
      for (const Robot& robot : robots) endpoint |= c == robot.goal;
      if (!endpoint) UpdateCell("floor", c, r() % 2 == 0 ? kLethalCost : r() % 100);
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  });

  std::vector<std::thread> threads;
  std::atomic<int> answers{0};
  for (size_t i = 0; i < robots.size(); ++i) {
    threads.emplace_back([&, i] {
      Session session(*planner_);
      const Robot robot = robots[i];
      ASSERT_TRUE(session.Open("floor", robot.start, robot.goal));
      uint64_t seq = 1;
      for (int step = 0; step < 30; ++step) {
        auto response = session.Next(kAnswerWait);
        ASSERT_TRUE(response.has_value());
        ++answers;
        EXPECT_EQ(response->plan().goal().x(), robot.goal.x);
        EXPECT_EQ(response->plan().goal().y(), robot.goal.y);
        ExpectOptimal("floor", response->plan(), robot.goal);
        if (response->event() == v1::NAVIGATE_EVENT_MAP_CHANGED) continue;
        const std::vector<Cell> path = PathOf(response->plan());
        if (step % 3 == 2 && path.size() > 2) {
          ASSERT_TRUE(session.Observe(path[2], 150, /*session_only=*/false, ++seq));
        } else if (path.size() > 1) {
          ASSERT_TRUE(session.Move(path[1], ++seq));
        } else {
          ASSERT_TRUE(session.Move(robot.start, ++seq));
        }
      }
      EXPECT_TRUE(session.Finish().ok());
    });
  }
  for (std::thread& t : threads) t.join();
  stop.store(true);
  disturber.join();
  EXPECT_GE(answers.load(), 4 * 30);
}

// A kinematic session's open message: a 2 x 1 cell Dubins robot turning on
// 2 cells, from (2.5, 2.5) facing east to (16.5, 2.5) facing east.
v1::NavigateRequest KinematicOpen(const std::string& map, int64_t replan_budget,
                                  int64_t options_budget) {
  v1::NavigateRequest request;
  request.set_seq(1);
  v1::NavigateOpen* open = request.mutable_open();
  open->set_map(map);
  open->set_planner(v1::PLANNER_HYBRID_ASTAR);
  open->set_replan_max_expansions(replan_budget);
  open->mutable_options()->set_max_expansions(options_budget);
  for (const auto& [x, y] : {std::pair{1.0, 0.5}, {1.0, -0.5}, {-1.0, -0.5}, {-1.0, 0.5}}) {
    v1::CellPoint* p = open->mutable_options()->mutable_footprint()->add_polygon_cells();
    p->set_x(x);
    p->set_y(y);
  }
  open->mutable_options()->set_min_turning_radius_cells(2.0);
  v1::CellPose* start = open->mutable_start()->mutable_cell_pose();
  start->set_x(2.5);
  start->set_y(2.5);
  v1::CellPose* goal = open->mutable_goal()->mutable_cell_pose();
  goal->set_x(16.5);
  goal->set_y(2.5);
  return request;
}

// The replan budget: NavigateOpen.replan_max_expansions, else
// options.max_expansions, else 20000; --max_expansions caps each.
TEST_F(NavigationTest, KinematicReplanBudgetTakesItsDefaultsAndTheServersCap) {
  for (const int64_t cap : {int64_t{0}, int64_t{300}}) {
    ServerOptions options;
    options.max_expansions = cap;
    StartServer(options);
    AddMap("open", Grid::Create(20, 8).value());
    const auto budget_of = [&](int64_t replan, int64_t in_options) {
      Session session(*planner_);
      EXPECT_TRUE(session.Write(KinematicOpen("open", replan, in_options)));
      const std::optional<v1::NavigateResponse> opened = session.Next(kAnswerWait);
      EXPECT_TRUE(opened.has_value());
      EXPECT_TRUE(session.Finish().ok());
      return opened.has_value() ? opened->replan_max_expansions() : -1;
    };
    const auto capped = [cap](int64_t b) { return cap > 0 ? std::min(b, cap) : b; };
    EXPECT_EQ(budget_of(0, 0), capped(20000)) << "cap " << cap;
    EXPECT_EQ(budget_of(0, 1234), capped(1234)) << "cap " << cap;
    EXPECT_EQ(budget_of(777, 1234), capped(777)) << "cap " << cap;
    server_->Shutdown();
    server_.reset();
  }
}

// A pose message without a heading keeps the robot's; one whose footprint
// collides is answered without a path, and the session goes on.
TEST_F(NavigationTest, KinematicPosesKeepTheHeadingAndACollidingPoseIsAnAnswer) {
  StartServer();
  Grid grid = Grid::Create(20, 8).value();
  grid.set_cost(10, 6, kLethalCost);
  AddMap("open", std::move(grid));
  Session session(*planner_);
  ASSERT_TRUE(session.Write(KinematicOpen("open", 0, 0)));
  std::optional<v1::NavigateResponse> answer = session.Next(kAnswerWait);
  ASSERT_TRUE(answer.has_value());
  ASSERT_TRUE(answer->plan().found()) << answer->ShortDebugString();

  v1::NavigateRequest turned;
  turned.set_seq(2);
  v1::CellPose* pose = turned.mutable_pose()->mutable_cell_pose();
  pose->set_x(4.5);
  pose->set_y(3.0);
  pose->set_yaw(0.3);
  ASSERT_TRUE(session.Write(turned));
  answer = session.Next(kAnswerWait);
  ASSERT_TRUE(answer.has_value());
  EXPECT_DOUBLE_EQ(answer->robot_pose().yaw(), 0.3);
  ASSERT_TRUE(answer->plan().found()) << answer->ShortDebugString();
  EXPECT_DOUBLE_EQ(answer->plan().poses(0).yaw(), 0.3);

  ASSERT_TRUE(session.Move(Cell{6, 3}, 3));  // a cell: still facing 0.3 rad
  answer = session.Next(kAnswerWait);
  ASSERT_TRUE(answer.has_value());
  EXPECT_DOUBLE_EQ(answer->robot_pose().x(), 6.5);
  EXPECT_DOUBLE_EQ(answer->robot_pose().yaw(), 0.3);

  ASSERT_TRUE(session.Move(Cell{9, 6}, 4));  // its front on the blocked cell
  answer = session.Next(kAnswerWait);
  ASSERT_TRUE(answer.has_value());
  EXPECT_EQ(answer->seq(), 4u);
  EXPECT_FALSE(answer->plan().found());
  EXPECT_EQ(answer->plan().poses_size(), 0);
  EXPECT_THAT(answer->plan().reason(), HasSubstr("start pose (9.5, 6.5, 0.3 rad) collides"));

  ASSERT_TRUE(session.Move(Cell{12, 3}, 5));  // clear again
  answer = session.Next(kAnswerWait);
  ASSERT_TRUE(answer.has_value());
  EXPECT_TRUE(answer->plan().found()) << answer->ShortDebugString();
  EXPECT_TRUE(session.Finish().ok());
}

}  // namespace
}  // namespace pathd::server
