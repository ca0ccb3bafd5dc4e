// The fixture of concurrency_test (tests/server/concurrency_test.cc): the
// shared maps, the client threads' logs and the ConcurrencyTest class, whose
// client loops are in concurrency_clients.cc and whose watchdog and check
// against Dijkstra are in concurrency_test.cc.
#ifndef PATHD_TESTS_SERVER_CONCURRENCY_FIXTURE_H_
#define PATHD_TESTS_SERVER_CONCURRENCY_FIXTURE_H_

#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/search/registry.h"
#include "core/search/path_measure.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/planner.h"
#include "core/search/search_scratch.h"
#include "gtest/gtest.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "server/map_store.h"
#include "server/server.h"
#include "tests/testing/in_process_server.h"


namespace pathd::server::concurrency_test {

inline int EnvSeconds(const char* name, int fallback) {
  const char* value = std::getenv(name);
  if (value == nullptr || *value == '\0') return fallback;
  const int parsed = std::atoi(value);
  return parsed > 0 ? parsed : fallback;
}

// Deadline of every call: only there so a lost call cannot hang the test
// forever; the watchdog reports a stall long before it.
inline constexpr auto kCallDeadline = std::chrono::minutes(10);

// What each client thread does.
enum class Role { kPlan, kBatch, kNavigate, kUpdate };

inline const char* RoleName(Role role) {
  switch (role) {
    case Role::kPlan:
      return "plan";
    case Role::kBatch:
      return "batch";
    case Role::kNavigate:
      return "navigate";
    case Role::kUpdate:
      return "update";
  }
  return "?";
}

inline std::vector<Role> Roles() {
  std::vector<Role> roles;
  roles.insert(roles.end(), 12, Role::kPlan);
  roles.insert(roles.end(), 4, Role::kBatch);
  roles.insert(roles.end(), 10, Role::kNavigate);
  roles.insert(roles.end(), 6, Role::kUpdate);
  return roles;
}

// One shared map: its first version and the cells every plan starts or ends
// on. Updates and observations never touch those cells, so Plan endpoints
// stay valid on every version (robots still get blocked where they stand).
struct SharedMap {
  std::string name;
  Grid initial;
  std::vector<Cell> endpoints;
  std::set<std::pair<int, int>> reserved;

  bool Reserved(Cell c) const { return reserved.count({c.x, c.y}) != 0; }
  // Whether an inclusive rectangle covers an endpoint.
  bool Covers(const MapChange& change) const {
    for (const Cell& c : endpoints) {
      if (c.x >= change.x_min && c.x <= change.x_max && c.y >= change.y_min &&
          c.y <= change.y_max) {
        return true;
      }
    }
    return false;
  }
};

inline SharedMap MakeMap(const std::string& name, int width, int height,
                  uint32_t seed) {
  std::mt19937 rng(seed);
  SharedMap map{name, *Grid::Create(width, height), {}, {}};
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const uint32_t r = rng() % 100;
      if (r < 18) {
        map.initial.set_cost(x, y, kLethalCost);
      } else if (r < 35) {
        map.initial.set_cost(
            x, y, static_cast<uint8_t>(1 + rng() % kMaxTraversableCost));
      }
    }
  }
  while (map.endpoints.size() < 8) {
    const Cell c{static_cast<int>(rng() % width),
                 static_cast<int>(rng() % height)};
    if (!map.reserved.insert({c.x, c.y}).second) continue;
    map.initial.set_cost(c, kFreeCost);
    map.endpoints.push_back(c);
  }
  return map;
}

// An answer to check: the path the server gave for start -> goal under
// `cost` on version `version` of `map`.
struct Answer {
  size_t map = 0;
  uint64_t version = 0;
  Cell start;
  Cell goal;
  CostParams cost;
  // spm descends a float cost-to-go field and may end a rounding error above
  // the optimum; the others must match to double precision.
  double tolerance = 1e-9;
  std::string what;
  bool found = false;
  double path_cost = 0.0;
  std::vector<Cell> path;
  std::string reason;
};

// A map version some client produced, with the changes that made it.
struct Version {
  size_t map = 0;
  uint64_t version = 0;
  std::vector<MapChange> changes;
  std::string what;
};

// Everything one client thread saw; merged after the run so recording costs
// no locking while the load runs.
struct ClientLog {
  std::vector<Answer> answers;
  std::vector<Version> versions;
  std::vector<std::string> failures;
  int64_t pushes = 0;
};

inline Cell CellOf(const v1::Cell& c) { return Cell{c.x(), c.y()}; }

inline v1::Position CellPosition(Cell c) {
  v1::Position p;
  p.mutable_cell()->set_x(c.x);
  p.mutable_cell()->set_y(c.y);
  return p;
}

inline Answer RecordPlan(size_t map, const v1::PlanResponse& plan, Cell goal,
                  const CostParams& cost, std::string what) {
  Answer answer;
  answer.map = map;
  answer.version = plan.map_version();
  answer.start = CellOf(plan.start());
  answer.goal = goal;
  answer.cost = cost;
  answer.what = std::move(what);
  answer.found = plan.found();
  answer.path_cost = plan.cost();
  answer.reason = plan.reason();
  for (const v1::Cell& c : plan.path()) answer.path.push_back(CellOf(c));
  return answer;
}

inline void ToWire(const MapChange& change, v1::CellChange* out) {
  if (change.is_rect) {
    out->mutable_rect()->set_x_min(change.x_min);
    out->mutable_rect()->set_y_min(change.y_min);
    out->mutable_rect()->set_x_max(change.x_max);
    out->mutable_rect()->set_y_max(change.y_max);
  } else {
    out->mutable_cell()->set_x(change.x_min);
    out->mutable_cell()->set_y(change.y_min);
  }
  out->set_cost(change.cost);
}

class ConcurrencyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ServerOptions options;
    options.threads = 4;
    server_ = std::make_unique<testing::InProcessServer>(options);
    ASSERT_TRUE(server_->Start().ok());
    maps_.push_back(MakeMap("hall", 48, 32, 1));
    maps_.push_back(MakeMap("yard", 40, 40, 2));
    maps_.push_back(MakeMap("maze", 64, 24, 3));
    for (const SharedMap& map : maps_) {
      auto created = server_->store().Create(map.name, map.initial, false);
      ASSERT_TRUE(created.ok()) << created.status();
      ASSERT_EQ((*created)->version, 1u);
    }
    planner_ = &server_->planner();
    map_stub_ = &server_->maps();
    activity_ = std::make_unique<std::atomic<const char*>[]>(Roles().size());
  }

  void TearDown() override {
    if (server_ != nullptr) server_->Shutdown();
  }

  void Progress(int thread, const char* doing) {
    activity_[thread].store(doing, std::memory_order_relaxed);
    progress_.fetch_add(1, std::memory_order_relaxed);
  }

  // Cells of a random change batch: single cells or rectangles up to 4 x 4,
  // never covering an endpoint; lethal, free or a random traversable cost.
  std::vector<MapChange> RandomChanges(const SharedMap& map, std::mt19937& rng,
                                       int count) {
    std::vector<MapChange> changes;
    while (static_cast<int>(changes.size()) < count) {
      const uint32_t r = rng() % 10;
      const uint32_t cost = r < 4   ? kLethalCost
                            : r < 7 ? kFreeCost
                                    : 1 + rng() % kMaxTraversableCost;
      const int x = static_cast<int>(rng() % map.initial.width());
      const int y = static_cast<int>(rng() % map.initial.height());
      MapChange change;
      if (rng() % 2 == 0) {
        change = MapChange::ForCell(x, y, cost);
      } else {
        change =
            MapChange::ForRect(x, y,
                               std::min<int>(x + static_cast<int>(rng() % 4),
                                             map.initial.width() - 1),
                               std::min<int>(y + static_cast<int>(rng() % 4),
                                             map.initial.height() - 1),
                               cost);
      }
      if (!map.Covers(change)) changes.push_back(change);
    }
    return changes;
  }

  // A random plan request between two endpoints of a random map, with what
  // its answer must be checked against.
  struct RandomPlan {
    size_t map = 0;
    const char* planner = "";
    Cell start;
    Cell goal;
    CostParams cost;
    v1::PlanRequest request;
    std::string what;

    // Records `response` into `log` if it answers this request, else a
    // failure.
    void Record(const v1::PlanResponse& response, ClientLog& log) const {
      if (response.planner() != planner || CellOf(response.start()) != start ||
          CellOf(response.goal()) != goal) {
        log.failures.push_back(what + ": answer for " + response.planner() + " " +
                               CellToString(CellOf(response.start())) + " -> " +
                               CellToString(CellOf(response.goal())));
        return;
      }
      Answer answer = RecordPlan(map, response, goal, cost, what);
      if (request.planner() == v1::PLANNER_SPM) answer.tolerance = 1e-4;
      log.answers.push_back(std::move(answer));
    }
  };

  RandomPlan MakeRandomPlan(std::mt19937& rng) const {
    struct Choice {
      v1::Planner planner;
      const char* name;
    };
    constexpr std::array<Choice, 6> kPlanners = {
        {{v1::PLANNER_ASTAR, "astar"},
         {v1::PLANNER_DIJKSTRA, "dijkstra"},
         {v1::PLANNER_JPS, "jps"},
         {v1::PLANNER_DSTAR_LITE, "dstar_lite"},
         {v1::PLANNER_SPM, "spm"},
         // Its jump table is advanced by the derived cache per version.
         {v1::PLANNER_JPS_PLUS, "jps_plus"}}};
    RandomPlan plan;
    {
      const size_t m = rng() % maps_.size();
      plan.map = m;
      const SharedMap& map = maps_[m];
      const Choice& choice = kPlanners[rng() % kPlanners.size()];
      plan.planner = choice.name;
      const Cell start = map.endpoints[rng() % map.endpoints.size()];
      const Cell goal = map.endpoints[rng() % map.endpoints.size()];
      plan.start = start;
      plan.goal = goal;
      CostParams& cost = plan.cost;
      v1::PlanRequest& request = plan.request;
      request.set_map(map.name);
      request.set_planner(choice.planner);
      *request.mutable_start() = CellPosition(start);
      *request.mutable_goal() = CellPosition(goal);
      const bool jump = choice.planner == v1::PLANNER_JPS ||
                        choice.planner == v1::PLANNER_JPS_PLUS;
      if (jump) {
        // JPS needs uniform cost: cost_weight 0 makes every traversable cell
        // cost the same.
        cost.cost_weight = 0.0;
      } else if (rng() % 3 == 0) {
        cost.cost_weight = 0.5;
      }
      if (!jump && rng() % 3 == 0) {
        cost.connectivity = Connectivity::kFour;
      }
      request.mutable_options()->set_cost_weight(cost.cost_weight);
      request.mutable_options()->set_connectivity(
          cost.connectivity == Connectivity::kFour ? v1::CONNECTIVITY_FOUR
                                                   : v1::CONNECTIVITY_EIGHT);
      plan.what = absl::StrFormat("%s on %s %s -> %s", choice.name, map.name,
                                  CellToString(start), CellToString(goal));
    }
    return plan;
  }

  void PlanClient(int thread, ClientLog& log);

  // One PlanBatch stream per round: writes a burst of random requests with
  // distinct ids, reads every answer (in finishing order) and checks each
  // against the request its id names; then half-closes and expects OK.
  void BatchClient(int thread, ClientLog& log);

  void UpdateClient(int thread, ClientLog& log);

  // Robots: open a session between two endpoints, walk along the answered
  // path, now and then report a sensed change to the shared map, and close
  // after a few steps or at the goal. Every answer and push is recorded.
  void NavigateClient(int thread, ClientLog& log);

  void RunClient(int thread, Role role, ClientLog& log);

  // Aborts the process when no call completed for `stall`: a deadlock (or a
  // lost wake-up) would otherwise hang the test until ctest's timeout
  // without saying where.
  void Watchdog(std::chrono::seconds stall);

  // Rebuilds every version of every map from the recorded changes and checks
  // each answer against Dijkstra on its version. Returns the answers checked.
  size_t Verify(const std::vector<ClientLog>& logs);

  // Empty when `answer` is right for `grid` (the version it names).
  static std::string Check(const Grid& grid, const Answer& answer,
                           std::map<std::tuple<int, int, int, int, int, double>,
                                    std::optional<double>>& memo);

  std::unique_ptr<testing::InProcessServer> server_;
  v1::PlannerService::Stub* planner_ = nullptr;
  v1::MapService::Stub* map_stub_ = nullptr;
  std::vector<SharedMap> maps_;

  std::atomic<bool> stop_{false};
  std::atomic<int64_t> progress_{0};
  std::unique_ptr<std::atomic<const char*>[]> activity_;
  std::mutex watchdog_mu_;
  std::condition_variable watchdog_cv_;
  bool watchdog_stop_ = false;
};

}  // namespace pathd::server::concurrency_test

#endif  // PATHD_TESTS_SERVER_CONCURRENCY_FIXTURE_H_
