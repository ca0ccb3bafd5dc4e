// Fleet sessions (docs/service.md, "Fleet sessions") over a real gRPC channel
// to a PathdServer: robots in one group, each its own session and thread,
// driving their timed paths only as far as released, at random speeds. The
// test's own world model holds the cells each robot stands in or is moving
// through (both ends and, diagonally, the two side cells) and fails if two
// robots ever hold one cell; every move is one legal grid step onto a free
// cell; every robot reaches its goal. Also: joins that name the robot in the
// way, a robot that leaves, a map change that blocks a planned cell. No
// timing assertion: waits are bounded by generous deadlines only.
#include <grpcpp/grpcpp.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "absl/strings/str_format.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "tests/testing/in_process_server.h"

namespace pathd::server {
namespace {

using ::testing::HasSubstr;

// One fleet session: writes from the test thread, a reader thread keeps the
// newest fleet state (from answers and pushes).
class FleetClient {
 public:
  explicit FleetClient(v1::PlannerService::Stub& stub) {
    context_.set_deadline(std::chrono::system_clock::now() +
                          std::chrono::seconds(120));
    stream_ = stub.Navigate(&context_);
    reader_ = std::thread([this] { ReadLoop(); });
  }
  ~FleetClient() {
    Close();
    reader_.join();
  }

  // Opens; the answer (or the error that ended the call).
  std::optional<v1::NavigateResponse> Open(const std::string& map, int sx,
                                           int sy, int gx, int gy,
                                           v1::FleetSolver solver = {},
                                           const std::string& group = "g") {
    v1::NavigateRequest request;
    v1::NavigateOpen* open = request.mutable_open();
    open->set_map(map);
    open->mutable_start()->mutable_cell()->set_x(sx);
    open->mutable_start()->mutable_cell()->set_y(sy);
    open->mutable_goal()->mutable_cell()->set_x(gx);
    open->mutable_goal()->mutable_cell()->set_y(gy);
    open->mutable_fleet()->set_group(group);
    open->mutable_fleet()->set_solver(solver);
    return Exchange(request);
  }

  std::optional<v1::NavigateResponse> Move(int x, int y) {
    v1::NavigateRequest request;
    request.mutable_pose()->mutable_cell()->set_x(x);
    request.mutable_pose()->mutable_cell()->set_y(y);
    return Exchange(request);
  }

  // The newest fleet state after at least `after` updates, waiting up to
  // `wait`; nullopt when the stream ended or nothing came.
  std::optional<std::pair<v1::FleetSessionPlan, int64_t>> Next(
      int64_t after, absl::Duration wait) {
    absl::MutexLock lock(&mu_);
    WaitUntil(
        [this, after]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
          return updates_ > after || ended_;
        },
        wait);
    if (updates_ <= after) return std::nullopt;
    return std::make_pair(latest_, updates_);
  }

  void Close() {
    absl::MutexLock lock(&mu_);
    if (closed_) return;
    closed_ = true;
    stream_->WritesDone();
  }

  grpc::Status status() {
    absl::MutexLock lock(&mu_);
    WaitUntil([this]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) { return ended_; },
              absl::InfiniteDuration());
    return final_;
  }

 private:
  std::optional<v1::NavigateResponse> Exchange(v1::NavigateRequest& request) {
    request.set_seq(++seq_);
    if (!stream_->Write(request)) return std::nullopt;
    absl::MutexLock lock(&mu_);
    WaitUntil(
        [this]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
          return answers_.count(seq_) > 0 || ended_;
        },
        absl::Seconds(60));
    auto it = answers_.find(seq_);
    if (it == answers_.end()) return std::nullopt;
    return it->second;
  }

  // Waits on the condition variable and tests `done` itself: Abseil's Await
  // would evaluate it inside another thread's Unlock, which TSan cannot see
  // as holding mu_ (as in DerivedCache, docs/decisions.md).
  template <typename Done>
  void WaitUntil(Done done, absl::Duration wait)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    const absl::Time until = absl::Now() + wait;
    while (!done()) {
      if (cv_.WaitWithDeadline(&mu_, until)) return;
    }
  }

  void ReadLoop() {
    v1::NavigateResponse response;
    while (stream_->Read(&response)) {
      absl::MutexLock lock(&mu_);
      if (response.has_fleet()) {
        latest_ = response.fleet();
        ++updates_;
      }
      if (response.event() != v1::NAVIGATE_EVENT_FLEET) {
        answers_[response.seq()] = response;
      }
      cv_.SignalAll();
    }
    const grpc::Status status = stream_->Finish();
    absl::MutexLock lock(&mu_);
    final_ = status;
    ended_ = true;
    cv_.SignalAll();
  }

  grpc::ClientContext context_;
  std::unique_ptr<
      grpc::ClientReaderWriter<v1::NavigateRequest, v1::NavigateResponse>>
      stream_;
  std::thread reader_;
  uint64_t seq_ = 0;
  absl::Mutex mu_;
  absl::CondVar cv_;
  std::map<uint64_t, v1::NavigateResponse> answers_ ABSL_GUARDED_BY(mu_);
  v1::FleetSessionPlan latest_ ABSL_GUARDED_BY(mu_);
  int64_t updates_ ABSL_GUARDED_BY(mu_) = 0;
  bool ended_ ABSL_GUARDED_BY(mu_) = false;
  bool closed_ ABSL_GUARDED_BY(mu_) = false;
  grpc::Status final_ ABSL_GUARDED_BY(mu_);
};

// The test's world: which robot holds which cell.
class World {
 public:
  explicit World(std::vector<std::string> rows) : rows_(std::move(rows)) {}

  bool Free(int x, int y) const {
    return y >= 0 && y < static_cast<int>(rows_.size()) && x >= 0 &&
           x < static_cast<int>(rows_[y].size()) && rows_[y][x] != '#';
  }

  // An obstacle appeared (before any robot may drive there).
  void Block(int x, int y) { rows_[y][x] = '#'; }

  // Robot `r` now stands at `c` (its start).
  void Place(int r, std::pair<int, int> c) { Claim(r, {c}); }

  // Robot `r` drives from `a` to `b`: holds both (and the sides of a
  // diagonal) while moving, then only `b`. Records what breaks the rules.
  void Drive(int r, std::pair<int, int> a, std::pair<int, int> b) {
    const int dx = b.first - a.first, dy = b.second - a.second;
    if (std::abs(dx) > 1 || std::abs(dy) > 1 || !Free(b.first, b.second) ||
        (dx != 0 && dy != 0 &&
         (!Free(a.first, b.second) || !Free(b.first, a.second)))) {
      Fail(absl::StrFormat("robot %d: (%d,%d) -> (%d,%d) is no legal step", r,
                           a.first, a.second, b.first, b.second));
    }
    std::vector<std::pair<int, int>> cells = {a, b};
    if (dx != 0 && dy != 0) {
      cells.push_back({a.first, b.second});
      cells.push_back({b.first, a.second});
    }
    Claim(r, cells);
    // On the way (other threads run meanwhile).
    std::this_thread::sleep_for(std::chrono::microseconds(200));
    Claim(r, {b});
  }

  // The robot left: it holds nothing.
  void Leave(int r) { Claim(r, {}); }

  std::vector<std::string> failures() {
    absl::MutexLock lock(&mu_);
    return failures_;
  }

 private:
  void Claim(int r, const std::vector<std::pair<int, int>>& cells) {
    absl::MutexLock lock(&mu_);
    for (auto it = held_.begin(); it != held_.end();) {
      it = it->second == r ? held_.erase(it) : std::next(it);
    }
    for (const auto& c : cells) {
      auto [it, inserted] = held_.emplace(c, r);
      if (!inserted && it->second != r) {
        failures_.push_back(
            absl::StrFormat("robots %d and %d both hold (%d,%d)", r, it->second,
                            c.first, c.second));
      }
    }
  }
  void Fail(std::string what) {
    absl::MutexLock lock(&mu_);
    failures_.push_back(std::move(what));
  }

  std::vector<std::string> rows_;
  absl::Mutex mu_;
  std::map<std::pair<int, int>, int> held_ ABSL_GUARDED_BY(mu_);
  std::vector<std::string> failures_ ABSL_GUARDED_BY(mu_);
};

// Drives robot `r` of `client` along its released timed path to its goal;
// "" or what went wrong.
std::string DriveToGoal(int r, FleetClient& client, World& world,
                        std::pair<int, int> goal, uint32_t seed) {
  std::mt19937 rng(seed);
  int64_t seen = 0;
  std::pair<int, int> at{-1, -1};
  const absl::Time give_up = absl::Now() + absl::Seconds(90);
  while (absl::Now() < give_up) {
    auto next = client.Next(seen - 1, absl::Seconds(30));
    if (!next.has_value())
      return absl::StrFormat("robot %d: no fleet state", r);
    const v1::FleetSessionPlan& fleet = next->first;
    seen = next->second;
    // A frozen group (planned false) still releases the robot to the end of
    // its stretch, which it drives to; then it waits for the new plan.
    const auto& cells = fleet.path().cells();
    if (cells.empty()) {
      // Not planned yet: wait for a push.
      if (!client.Next(seen, absl::Seconds(30)).has_value()) {
        return absl::StrFormat("robot %d: no plan within 30 s (%s)", r,
                               fleet.reason());
      }
      continue;
    }
    const std::pair<int, int> here{
        cells[static_cast<int>(fleet.progress())].x(),
        cells[static_cast<int>(fleet.progress())].y()};
    if (at.first < 0) at = here;
    if (here != at)
      return absl::StrFormat("robot %d: the server has it elsewhere", r);
    if (fleet.planned() && fleet.progress() + 1 == cells.size()) {
      if (at != goal)
        return absl::StrFormat("robot %d: the plan ends off its goal", r);
      return "";
    }
    std::optional<std::pair<int, int>> step;
    for (int64_t t = fleet.progress() + 1; t <= fleet.release(); ++t) {
      const std::pair<int, int> c{cells[static_cast<int>(t)].x(),
                                  cells[static_cast<int>(t)].y()};
      if (c != at) {
        step = c;
        break;
      }
    }
    if (!step.has_value()) {
      if (!client.Next(seen, absl::Seconds(30)).has_value()) {
        return absl::StrFormat("robot %d: not released within 30 s (%s)", r,
                               fleet.reason());
      }
      continue;
    }
    // A random pace: some robots dawdle.
    std::this_thread::sleep_for(std::chrono::microseconds(
        std::uniform_int_distribution<int>(0, 3000)(rng)));
    world.Drive(r, at, *step);
    at = *step;
    auto answer = client.Move(at.first, at.second);
    if (!answer.has_value())
      return absl::StrFormat("robot %d: the move got no answer", r);
    seen = std::max<int64_t>(seen, 0);
  }
  return absl::StrFormat("robot %d: not at its goal within 90 s", r);
}

class FleetSessionTest : public ::testing::Test {
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

// A hall with pillars; robots swap sides through it.
const std::vector<std::string> kHall = {
    "............",  //
    "............",  //
    "..#..##..#..",  //
    "............",  //
    "....#..#....",  //
    "............",  //
    "..#..##..#..",  //
    "............",  //
};

TEST_F(FleetSessionTest, RobotsAtRandomPacesNeverShareACellAndAllArrive) {
  ASSERT_TRUE(server_->CreateMapFromRows("hall", kHall, 0.5).ok());
  struct Robot {
    std::pair<int, int> start, goal;
  };
  // Round 0: four pairs swapping places (all join before anyone drives).
  const std::vector<Robot> swaps = {
      {{0, 0}, {11, 7}}, {{11, 7}, {0, 0}}, {{0, 7}, {11, 0}},
      {{11, 0}, {0, 7}}, {{5, 0}, {6, 7}},  {{6, 7}, {5, 0}},
      {{0, 3}, {11, 4}}, {{11, 4}, {0, 3}},
  };
  // Rounds 1 and 2: the same starts, goals that are nobody's start (a robot
  // that has not joined yet is not there in this test's world, and one that
  // arrived early would stand on a later robot's start for ever).
  const std::vector<Robot> crossings = {
      {{0, 0}, {11, 6}}, {{11, 7}, {0, 1}}, {{0, 7}, {11, 1}},
      {{11, 0}, {0, 6}}, {{5, 0}, {7, 6}},  {{6, 7}, {5, 1}},
      {{0, 3}, {11, 3}}, {{11, 4}, {0, 4}},
  };
  for (int round = 0; round < 3; ++round) {
    const std::vector<Robot>& robots = round == 0 ? swaps : crossings;
    // Round 0: every robot joins, then all drive. Rounds 1 and 2: each robot
    // drives as soon as it has joined, so later joins freeze a moving group
    // (it finishes the stretches it was released for, then is planned
    // again from where it stands), and a join whose start is on a driving
    // robot's stretch is refused and tried again, as a client would.
    World world(kHall);
    std::vector<std::unique_ptr<FleetClient>> clients;
    std::vector<std::string> errors(robots.size());
    std::vector<std::thread> drivers;
    // Each driver holds its own client (the vector grows as robots join).
    const auto start_driver = [&](size_t r) {
      FleetClient* client = clients[r].get();
      drivers.emplace_back([&, r, client] {
        errors[r] =
            DriveToGoal(static_cast<int>(r), *client, world, robots[r].goal,
                        static_cast<uint32_t>(round * 100 + r));
      });
    };
    bool all_joined = true;
    for (size_t r = 0; r < robots.size() && all_joined; ++r) {
      std::unique_ptr<FleetClient> client;
      std::optional<v1::NavigateResponse> opened;
      for (int attempt = 0; attempt < 1000 && !opened.has_value(); ++attempt) {
        client = std::make_unique<FleetClient>(server_->planner());
        opened =
            client->Open("hall", robots[r].start.first, robots[r].start.second,
                         robots[r].goal.first, robots[r].goal.second);
        if (opened.has_value()) break;
        const grpc::Status status = client->status();
        if (status.error_message().find("stands or may drive now") ==
            std::string::npos) {
          ADD_FAILURE() << "robot " << r << ": " << status.error_message();
          break;
        }
        client.reset();
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
      if (!opened.has_value()) {
        all_joined = false;
        ADD_FAILURE() << "robot " << r << " never joined";
        break;
      }
      EXPECT_EQ(opened->event(), v1::NAVIGATE_EVENT_OPENED);
      EXPECT_TRUE(opened->has_fleet());
      // It is there from its join on (a robot outside the group is none of
      // the group's business).
      world.Place(static_cast<int>(r), robots[r].start);
      clients.push_back(std::move(client));
      if (round > 0) start_driver(r);
    }
    if (round == 0 && all_joined) {
      for (size_t r = 0; r < robots.size(); ++r) start_driver(r);
    }
    for (std::thread& t : drivers) t.join();
    if (!all_joined) break;
    for (size_t r = 0; r < robots.size(); ++r)
      EXPECT_EQ(errors[r], "") << "round " << round;
    EXPECT_THAT(world.failures(), ::testing::IsEmpty()) << "round " << round;
    for (auto& client : clients) {
      client->Close();
      EXPECT_TRUE(client->status().ok()) << client->status().error_message();
    }
  }
}

TEST_F(FleetSessionTest, AJoinInTheWayOrWithAnotherSolverIsRefusedByName) {
  ASSERT_TRUE(server_->CreateMapFromRows("hall", kHall, 0.5).ok());
  FleetClient first(server_->planner());
  ASSERT_TRUE(first.Open("hall", 0, 0, 11, 0).has_value());
  {
    FleetClient same_goal(server_->planner());
    same_goal.Open("hall", 0, 7, 11, 0);
    const grpc::Status status = same_goal.status();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_THAT(status.error_message(),
                HasSubstr("open.goal (11, 0) is the goal of session"));
  }
  {
    FleetClient same_start(server_->planner());
    same_start.Open("hall", 0, 0, 11, 7);
    const grpc::Status status = same_start.status();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_THAT(status.error_message(), HasSubstr("stands or may drive now"));
  }
  {
    FleetClient other_solver(server_->planner());
    other_solver.Open("hall", 0, 7, 11, 7, v1::FLEET_SOLVER_CBS);
    const grpc::Status status = other_solver.status();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_THAT(status.error_message(), HasSubstr("plans with lacam, not cbs"));
  }
  {
    // Another group is another fleet: its own solver.
    FleetClient other_group(server_->planner());
    auto opened =
        other_group.Open("hall", 0, 7, 11, 7, v1::FLEET_SOLVER_CBS, "night");
    ASSERT_TRUE(opened.has_value()) << other_group.status().error_message();
    EXPECT_EQ(opened->fleet().robots(), 1);
  }
  FleetClient second(server_->planner());
  auto opened = second.Open("hall", 0, 7, 11, 7);
  ASSERT_TRUE(opened.has_value()) << second.status().error_message();
  EXPECT_EQ(opened->fleet().robots(), 2);
}

// Drives `client`'s robot as far as it is released now (no waiting);
// returns its fleet state then.
v1::FleetSessionPlan DriveReleased(FleetClient& client) {
  for (;;) {
    auto state = client.Next(-1, absl::Seconds(0));
    if (!state.has_value()) return {};
    const v1::FleetSessionPlan& fleet = state->first;
    if (fleet.progress() >= fleet.release()) return fleet;
    const v1::Cell& next =
        fleet.path().cells(static_cast<int>(fleet.progress() + 1));
    if (!client.Move(next.x(), next.y()).has_value()) return {};
  }
}

TEST_F(FleetSessionTest, ARobotThatLeavesHoldsNobodyBack) {
  // Two corridors crossing at (5, 1): whichever robot the plan sends
  // through the crossing second is held back until the other has passed,
  // or has left.
  const std::vector<std::string> rows = {
      "#####.#####",  //
      "...........",  //
      "#####.#####",  //
      "#####.#####",  //
      "#####.#####",  //
  };
  ASSERT_TRUE(server_->CreateMapFromRows("cross", rows, 0.5).ok());
  std::vector<std::unique_ptr<FleetClient>> robots;
  robots.push_back(std::make_unique<FleetClient>(server_->planner()));
  ASSERT_TRUE(robots[0]->Open("cross", 0, 1, 10, 1).has_value());
  robots.push_back(std::make_unique<FleetClient>(server_->planner()));
  auto joined = robots[1]->Open("cross", 5, 4, 5, 0);
  ASSERT_TRUE(joined.has_value()) << robots[1]->status().error_message();
  // The join froze the group: robot 0 finishes its stretch, then the two
  // are planned together.
  EXPECT_FALSE(joined->fleet().planned());
  const uint64_t epoch = joined->fleet().epoch();
  {
    // Robot 0 was told (a push) that the group froze.
    auto told = robots[0]->Next(1, absl::Seconds(30));
    ASSERT_TRUE(told.has_value());
    EXPECT_FALSE(told->first.planned());
    EXPECT_THAT(told->first.reason(),
                HasSubstr("once 1 robot(s) have finished"));
  }
  for (;;) {
    auto frozen = robots[0]->Next(-1, absl::Seconds(0));
    ASSERT_TRUE(frozen.has_value());
    const v1::FleetSessionPlan& fleet = frozen->first;
    if (fleet.epoch() != epoch || fleet.progress() >= fleet.release()) break;
    const v1::Cell& next =
        fleet.path().cells(static_cast<int>(fleet.progress() + 1));
    ASSERT_TRUE(robots[0]->Move(next.x(), next.y()).has_value());
  }
  // The last report planned the group; robot 1 hears of it in a push.
  std::vector<v1::FleetSessionPlan> state(2);
  for (int r = 0; r < 2; ++r) {
    int64_t seen = -1;
    for (int wait = 0; wait < 100 && !state[r].planned(); ++wait) {
      auto s = robots[r]->Next(seen, absl::Seconds(1));
      if (!s.has_value()) continue;
      state[r] = s->first;
      seen = s->second;
    }
    ASSERT_TRUE(state[r].planned())
        << "robot " << r << ": " << state[r].reason();
  }
  // The robot the plan sends through the crossing second drives as far as
  // released: it stops before the crossing, where the first has not passed.
  const auto crossing_step = [](const v1::FleetSessionPlan& fleet) {
    for (int t = 0; t < fleet.path().cells_size(); ++t) {
      if (fleet.path().cells(t).x() == 5 && fleet.path().cells(t).y() == 1)
        return t;
    }
    return -1;
  };
  ASSERT_GE(crossing_step(state[0]), 0);
  ASSERT_GE(crossing_step(state[1]), 0);
  const int waiting = crossing_step(state[0]) > crossing_step(state[1]) ? 0 : 1;
  const int other = 1 - waiting;
  const v1::FleetSessionPlan held = DriveReleased(*robots[waiting]);
  EXPECT_LT(held.release(), crossing_step(held));
  auto before = robots[waiting]->Next(-1, absl::Seconds(0));
  ASSERT_TRUE(before.has_value());
  const int64_t release_before = before->first.release();
  robots[other]->Close();
  EXPECT_TRUE(robots[other]->status().ok());
  robots[other].reset();
  auto after = robots[waiting]->Next(before->second, absl::Seconds(30));
  ASSERT_TRUE(after.has_value()) << "no push released the waiting robot";
  EXPECT_GT(after->first.release(), release_before);
  EXPECT_EQ(after->first.robots(), 1);
}

TEST_F(FleetSessionTest, AMapChangeOnAPlannedCellPlansTheGroupAgain) {
  ASSERT_TRUE(server_->CreateMapFromRows("hall", kHall, 0.5).ok());
  FleetClient a(server_->planner());
  auto opened = a.Open("hall", 0, 3, 11, 3);
  ASSERT_TRUE(opened.has_value());
  ASSERT_TRUE(opened->fleet().planned());
  const uint64_t epoch = opened->fleet().epoch();
  // Alone, it is released kReleaseHorizon (4) steps ahead; block the cell
  // two steps ahead, inside that stretch.
  const auto& cells = opened->fleet().path().cells();
  ASSERT_GT(cells.size(), 4);
  EXPECT_EQ(opened->fleet().release(), 4);
  const v1::Cell blocked = cells[2];
  v1::UpdateMapRequest update;
  update.set_name("hall");
  v1::CellChange* change = update.add_changes();
  change->mutable_cell()->set_x(blocked.x());
  change->mutable_cell()->set_y(blocked.y());
  change->set_cost(254);
  grpc::ClientContext context;
  v1::UpdateMapResponse updated;
  ASSERT_TRUE(server_->maps().UpdateMap(&context, update, &updated).ok());
  // The release is cut back to the cell before the blocked one: the robot
  // stops there, and the group is planned again from where it stopped.
  auto frozen = a.Next(1, absl::Seconds(30));
  ASSERT_TRUE(frozen.has_value());
  EXPECT_FALSE(frozen->first.planned());
  EXPECT_EQ(frozen->first.epoch(), epoch);
  EXPECT_EQ(frozen->first.release(), 1);
  World world(kHall);
  world.Block(blocked.x(), blocked.y());
  world.Place(0, {0, 3});
  EXPECT_EQ(DriveToGoal(0, a, world, {11, 3}, 7), "");
  EXPECT_THAT(world.failures(), ::testing::IsEmpty());
  auto last = a.Next(0, absl::Seconds(1));
  ASSERT_TRUE(last.has_value());
  EXPECT_GT(last->first.epoch(), epoch);
  for (const v1::Cell& c : last->first.path().cells()) {
    EXPECT_FALSE(c.x() == blocked.x() && c.y() == blocked.y());
  }
}

}  // namespace
}  // namespace pathd::server
