// 32 client threads against one in-process PathdServer on 127.0.0.1:0, all on
// the same three maps at once: Plan calls with the optimal planners (astar,
// dijkstra, jps, dstar_lite, spm), Navigate sessions (open, poses, shared
// observations, pushed paths) and UpdateMap calls. Every answer names the map
// version it was planned on; after the run the test rebuilds every version
// from the recorded updates and observations alone and checks each answer's
// cost against the reference Dijkstra on that version. A watchdog aborts the
// process with each thread's current call when no call completes for a while
// (a deadlock). `make test-tsan` runs this under ThreadSanitizer.
//
// PATHD_CONCURRENCY_SECONDS sets the run length (default 3) for longer local
// soaks; PATHD_CONCURRENCY_STALL_SECONDS the watchdog's limit (default 120,
// far above any call's time even under TSan on a loaded machine).
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

namespace pathd::server {
namespace {

int EnvSeconds(const char* name, int fallback) {
  const char* value = std::getenv(name);
  if (value == nullptr || *value == '\0') return fallback;
  const int parsed = std::atoi(value);
  return parsed > 0 ? parsed : fallback;
}

// Deadline of every call: only there so a lost call cannot hang the test
// forever; the watchdog reports a stall long before it.
constexpr auto kCallDeadline = std::chrono::minutes(10);

// What each client thread does.
enum class Role { kPlan, kBatch, kNavigate, kUpdate };

const char* RoleName(Role role) {
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

std::vector<Role> Roles() {
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

SharedMap MakeMap(const std::string& name, int width, int height,
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

Cell CellOf(const v1::Cell& c) { return Cell{c.x(), c.y()}; }

v1::Position CellPosition(Cell c) {
  v1::Position p;
  p.mutable_cell()->set_x(c.x);
  p.mutable_cell()->set_y(c.y);
  return p;
}

Answer RecordPlan(size_t map, const v1::PlanResponse& plan, Cell goal,
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

void ToWire(const MapChange& change, v1::CellChange* out) {
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
    constexpr std::array<Choice, 5> kPlanners = {
        {{v1::PLANNER_ASTAR, "astar"},
         {v1::PLANNER_DIJKSTRA, "dijkstra"},
         {v1::PLANNER_JPS, "jps"},
         {v1::PLANNER_DSTAR_LITE, "dstar_lite"},
         {v1::PLANNER_SPM, "spm"}}};
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
      if (choice.planner == v1::PLANNER_JPS) {
        // JPS needs uniform cost: cost_weight 0 makes every traversable cell
        // cost the same.
        cost.cost_weight = 0.0;
      } else if (rng() % 3 == 0) {
        cost.cost_weight = 0.5;
      }
      if (choice.planner != v1::PLANNER_JPS && rng() % 3 == 0) {
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

  void PlanClient(int thread, ClientLog& log) {
    std::mt19937 rng(100 + thread);
    while (!stop_.load()) {
      RandomPlan plan = MakeRandomPlan(rng);
      plan.what = "Plan " + plan.what;
      grpc::ClientContext context;
      context.set_deadline(std::chrono::system_clock::now() + kCallDeadline);
      v1::PlanResponse response;
      Progress(thread, "Plan");
      const grpc::Status status = planner_->Plan(&context, plan.request, &response);
      Progress(thread, "between calls");
      if (!status.ok()) {
        log.failures.push_back(plan.what + ": " + status.error_message());
        continue;
      }
      plan.Record(response, log);
    }
  }

  // One PlanBatch stream per round: writes a burst of random requests with
  // distinct ids, reads every answer (in finishing order) and checks each
  // against the request its id names; then half-closes and expects OK.
  void BatchClient(int thread, ClientLog& log) {
    std::mt19937 rng(300 + thread);
    int round = 0;
    while (!stop_.load()) {
      grpc::ClientContext context;
      context.set_deadline(std::chrono::system_clock::now() + kCallDeadline);
      Progress(thread, "PlanBatch open");
      auto stream = planner_->PlanBatch(&context);
      std::map<std::string, RandomPlan> pending;
      const int burst = 4 + static_cast<int>(rng() % 12);
      for (int i = 0; i < burst; ++i) {
        RandomPlan plan = MakeRandomPlan(rng);
        const std::string id = absl::StrCat(round, "-", i);
        plan.what = absl::StrCat("PlanBatch item ", id, " ", plan.what);
        v1::PlanBatchRequest item;
        item.set_request_id(id);
        *item.mutable_request() = plan.request;
        Progress(thread, "PlanBatch write");
        if (!stream->Write(item)) break;
        pending.emplace(id, std::move(plan));
      }
      Progress(thread, "PlanBatch writes done");
      stream->WritesDone();
      v1::PlanBatchResponse answer;
      while (true) {
        Progress(thread, "PlanBatch read");
        if (!stream->Read(&answer)) break;
        auto it = pending.find(answer.request_id());
        if (it == pending.end()) {
          log.failures.push_back(absl::StrCat("PlanBatch: answer for unknown or "
                                              "repeated id '",
                                              answer.request_id(), "'"));
          continue;
        }
        if (answer.has_error()) {
          log.failures.push_back(it->second.what + ": " + answer.error().message());
        } else {
          it->second.Record(answer.result(), log);
        }
        pending.erase(it);
      }
      Progress(thread, "PlanBatch finish");
      const grpc::Status status = stream->Finish();
      Progress(thread, "between calls");
      if (!status.ok()) {
        log.failures.push_back(absl::StrCat("PlanBatch round ", round, ": ",
                                            status.error_message()));
      }
      for (const auto& [id, plan] : pending) {
        log.failures.push_back(plan.what + ": never answered");
      }
      ++round;
    }
  }

  void UpdateClient(int thread, ClientLog& log) {
    std::mt19937 rng(200 + thread);
    while (!stop_.load()) {
      const size_t m = rng() % maps_.size();
      const SharedMap& map = maps_[m];
      const std::vector<MapChange> changes =
          RandomChanges(map, rng, 1 + static_cast<int>(rng() % 3));
      v1::UpdateMapRequest request;
      request.set_name(map.name);
      for (const MapChange& change : changes)
        ToWire(change, request.add_changes());
      grpc::ClientContext context;
      context.set_deadline(std::chrono::system_clock::now() + kCallDeadline);
      v1::UpdateMapResponse response;
      Progress(thread, "UpdateMap");
      const grpc::Status status =
          map_stub_->UpdateMap(&context, request, &response);
      Progress(thread, "between calls");
      if (!status.ok()) {
        log.failures.push_back("UpdateMap " + map.name + ": " +
                               status.error_message());
        continue;
      }
      log.versions.push_back(
          Version{m, response.version(), changes, "UpdateMap"});
      // A short pause now and then lets plans finish on a version before the
      // next one replaces it (cache hits as well as repairs).
      if (rng() % 4 == 0)
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }

  // Robots: open a session between two endpoints, walk along the answered
  // path, now and then report a sensed change to the shared map, and close
  // after a few steps or at the goal. Every answer and push is recorded.
  void NavigateClient(int thread, ClientLog& log) {
    std::mt19937 rng(300 + thread);
    while (!stop_.load()) {
      const size_t m = rng() % maps_.size();
      const SharedMap& map = maps_[m];
      const Cell start = map.endpoints[rng() % map.endpoints.size()];
      const Cell goal = map.endpoints[rng() % map.endpoints.size()];
      const std::string what =
          absl::StrFormat("Navigate on %s to %s", map.name, CellToString(goal));
      grpc::ClientContext context;
      context.set_deadline(std::chrono::system_clock::now() + kCallDeadline);
      Progress(thread, "Navigate open");
      auto stream = planner_->Navigate(&context);

      // Writes `request` and reads up to its answer; pushes before it are
      // recorded too. Returns the answer, or nullopt when the stream ended.
      std::vector<MapChange> observed;
      auto exchange = [&](const v1::NavigateRequest& request)
          -> std::optional<v1::NavigateResponse> {
        if (!stream->Write(request)) return std::nullopt;
        v1::NavigateResponse response;
        for (;;) {
          Progress(thread, "Navigate read");
          if (!stream->Read(&response)) return std::nullopt;
          Progress(thread, "between calls");
          const bool pushed =
              response.event() == v1::NAVIGATE_EVENT_MAP_CHANGED;
          if (!pushed && response.seq() != request.seq()) {
            log.failures.push_back(
                absl::StrFormat("%s: answer to seq %d, expected %d", what,
                                response.seq(), request.seq()));
          }
          if (CellOf(response.plan().goal()) != goal) {
            log.failures.push_back(
                what + ": answer names goal " +
                CellToString(CellOf(response.plan().goal())));
          }
          log.answers.push_back(RecordPlan(
              m, response.plan(), goal, CostParams(),
              absl::StrFormat("%s: %s", what,
                              v1::NavigateEvent_Name(response.event()))));
          if (pushed) {
            ++log.pushes;
            continue;
          }
          return response;
        }
      };

      v1::NavigateRequest open;
      open.set_seq(1);
      open.mutable_open()->set_map(map.name);
      *open.mutable_open()->mutable_start() = CellPosition(start);
      *open.mutable_open()->mutable_goal() = CellPosition(goal);
      std::optional<v1::NavigateResponse> answer = exchange(open);
      for (uint64_t seq = 2; answer.has_value() && seq < 20 && !stop_.load();
           ++seq) {
        const auto& path = answer->plan().path();
        if (path.size() < 2) break;  // at the goal, or no path on this version
        v1::NavigateRequest request;
        request.set_seq(seq);
        if (rng() % 4 == 0) {
          const std::vector<MapChange> changes = RandomChanges(map, rng, 1);
          for (const MapChange& change : changes) {
            ToWire(change, request.mutable_observe()->add_changes());
          }
          answer = exchange(request);
          if (!answer.has_value()) break;
          if (answer->applied_version() == 0) {
            log.failures.push_back(what +
                                   ": shared observation produced no version");
          } else {
            log.versions.push_back(Version{m, answer->applied_version(),
                                           changes, what + " observation"});
          }
        } else {
          *request.mutable_pose() = CellPosition(CellOf(path[1]));
          answer = exchange(request);
        }
      }
      stream->WritesDone();
      // Pushes sent before the server saw the end of the stream.
      v1::NavigateResponse response;
      Progress(thread, "Navigate drain");
      while (stream->Read(&response)) {
        Progress(thread, "Navigate drain");
        if (response.event() != v1::NAVIGATE_EVENT_MAP_CHANGED) {
          log.failures.push_back(what + ": unasked non-push after WritesDone");
        }
        ++log.pushes;
        log.answers.push_back(RecordPlan(m, response.plan(), goal, CostParams(),
                                         what + ": pushed while closing"));
      }
      Progress(thread, "Navigate finish");
      const grpc::Status status = stream->Finish();
      Progress(thread, "between calls");
      if (!status.ok())
        log.failures.push_back(what + ": " + status.error_message());
    }
  }

  void RunClient(int thread, Role role, ClientLog& log) {
    switch (role) {
      case Role::kPlan:
        PlanClient(thread, log);
        break;
      case Role::kBatch:
        BatchClient(thread, log);
        break;
      case Role::kNavigate:
        NavigateClient(thread, log);
        break;
      case Role::kUpdate:
        UpdateClient(thread, log);
        break;
    }
    Progress(thread, "done");
  }

  // Aborts the process when no call completed for `stall`: a deadlock (or a
  // lost wake-up) would otherwise hang the test until ctest's timeout
  // without saying where.
  void Watchdog(std::chrono::seconds stall) {
    std::unique_lock<std::mutex> lock(watchdog_mu_);
    int64_t last = progress_.load();
    auto last_change = std::chrono::steady_clock::now();
    while (!watchdog_cv_.wait_for(lock, std::chrono::milliseconds(200),
                                  [this] { return watchdog_stop_; })) {
      const int64_t now_progress = progress_.load();
      const auto now = std::chrono::steady_clock::now();
      if (now_progress != last) {
        last = now_progress;
        last_change = now;
        continue;
      }
      if (now - last_change < stall) continue;
      std::fprintf(stderr,
                   "concurrency_test: DEADLOCK? no call completed for %lld s; "
                   "what each client thread is in:\n",
                   static_cast<long long>(stall.count()));
      const std::vector<Role> roles = Roles();
      for (size_t i = 0; i < roles.size(); ++i) {
        const char* doing = activity_[i].load();
        std::fprintf(stderr, "  thread %zu (%s): %s\n", i, RoleName(roles[i]),
                     doing == nullptr ? "-" : doing);
      }
      std::fflush(stderr);
      std::abort();
    }
  }

  // Rebuilds every version of every map from the recorded changes and checks
  // each answer against Dijkstra on its version. Returns the answers checked.
  size_t Verify(const std::vector<ClientLog>& logs) {
    std::vector<std::map<uint64_t, const Version*>> versions(maps_.size());
    std::vector<std::vector<const Answer*>> answers(maps_.size());
    for (const ClientLog& log : logs) {
      for (const Version& v : log.versions) {
        const auto [it, inserted] = versions[v.map].emplace(v.version, &v);
        EXPECT_TRUE(inserted)
            << maps_[v.map].name << " version " << v.version
            << " returned to both " << it->second->what << " and " << v.what;
      }
      for (const Answer& a : log.answers) answers[a.map].push_back(&a);
    }
    size_t checked = 0;
    int reported = 0;
    for (size_t m = 0; m < maps_.size(); ++m) {
      const SharedMap& map = maps_[m];
      const uint64_t last = (*server_->store().Get(map.name))->version;
      // Every version after the first came from a recorded call: nothing else
      // changes the maps, so a gap means a version nobody was told about.
      EXPECT_EQ(versions[m].size(), last - 1) << map.name;
      std::sort(answers[m].begin(), answers[m].end(),
                [](const Answer* a, const Answer* b) {
                  return a->version < b->version;
                });
      Grid grid = map.initial;
      uint64_t version = 1;
      // Reference costs on the current version, by (start, goal, cost).
      std::map<std::tuple<int, int, int, int, int, double>,
               std::optional<double>>
          memo;
      for (const Answer* answer : answers[m]) {
        if (answer->version < 1 || answer->version > last) {
          ADD_FAILURE() << answer->what << ": version " << answer->version
                        << " outside 1.." << last;
          continue;
        }
        while (version < answer->version) {
          ++version;
          auto it = versions[m].find(version);
          if (it == versions[m].end()) continue;  // reported above
          for (const MapChange& c : it->second->changes) {
            for (int y = c.y_min; y <= c.y_max; ++y) {
              for (int x = c.x_min; x <= c.x_max; ++x) {
                grid.set_cost(x, y, static_cast<uint8_t>(c.cost));
              }
            }
          }
          memo.clear();
        }
        const std::string problem = Check(grid, *answer, memo);
        ++checked;
        if (!problem.empty() && reported++ < 20) {
          ADD_FAILURE() << answer->what << " on version " << answer->version
                        << ": " << problem;
        }
      }
    }
    EXPECT_EQ(reported, 0)
        << "answers that disagree with Dijkstra on their version";
    return checked;
  }

  // Empty when `answer` is right for `grid` (the version it names).
  static std::string Check(const Grid& grid, const Answer& answer,
                           std::map<std::tuple<int, int, int, int, int, double>,
                                    std::optional<double>>& memo) {
    if (!Traversable(grid.cost(answer.start), answer.cost.unknown_is_free)) {
      // A robot whose cell was blocked under it: no path, and the reason says
      // why.
      if (answer.found) return "found a path from a blocked start";
      if (answer.reason.find("start") == std::string::npos) {
        return "blocked start, but the reason does not say so: " +
               answer.reason;
      }
      return {};
    }
    const auto key = std::make_tuple(
        answer.start.x, answer.start.y, answer.goal.x, answer.goal.y,
        static_cast<int>(answer.cost.connectivity), answer.cost.cost_weight);
    auto it = memo.find(key);
    if (it == memo.end()) {
      SearchScratch scratch;
      absl::StatusOr<PlanResult> reference =
          PlannerRegistry::Default()
              .Get("dijkstra")
              ->Plan(
                  grid,
                  PlanRequest::Between(answer.start, answer.goal, answer.cost),
                  StopCondition::None(), scratch);
      if (!reference.ok())
        return "reference failed: " + reference.status().ToString();
      it = memo.emplace(key, reference->found()
                                 ? std::optional<double>(reference->cost)
                                 : std::nullopt)
               .first;
    }
    const std::optional<double>& expected = it->second;
    if (answer.found != expected.has_value()) {
      return absl::StrFormat("found=%d but Dijkstra found=%d (%s)",
                             answer.found, expected.has_value(), answer.reason);
    }
    if (!answer.found) return {};
    if (std::abs(answer.path_cost - *expected) >
        answer.tolerance * (1.0 + *expected)) {
      return absl::StrFormat("cost %.9f, Dijkstra %.9f", answer.path_cost,
                             *expected);
    }
    if (answer.path.empty() || answer.path.front() != answer.start ||
        answer.path.back() != answer.goal) {
      return "path does not run from start to goal";
    }
    const PathMeasure measured = MeasurePath(grid, answer.path, answer.cost);
    if (!measured.valid) {
      return absl::StrFormat("path illegal at index %d",
                             measured.first_invalid);
    }
    if (std::abs(measured.cost - answer.path_cost) >
        1e-6 * (1.0 + answer.path_cost)) {
      return absl::StrFormat("path costs %.9f, answer says %.9f", measured.cost,
                             answer.path_cost);
    }
    return {};
  }

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

TEST_F(ConcurrencyTest, MixedClientsGetAnswersRightForTheVersionTheyName) {
  const int seconds = EnvSeconds("PATHD_CONCURRENCY_SECONDS", 3);
  const int stall = EnvSeconds("PATHD_CONCURRENCY_STALL_SECONDS", 120);
  std::thread watchdog(
      [this, stall] { Watchdog(std::chrono::seconds(stall)); });

  const std::vector<Role> roles = Roles();
  ASSERT_EQ(roles.size(), 32u);
  std::vector<ClientLog> logs(roles.size());
  std::vector<std::thread> clients;
  for (size_t i = 0; i < roles.size(); ++i) {
    clients.emplace_back([this, i, &roles, &logs] {
      RunClient(static_cast<int>(i), roles[i], logs[i]);
    });
  }
  std::this_thread::sleep_for(std::chrono::seconds(seconds));
  stop_.store(true);
  for (std::thread& t : clients) t.join();
  {
    std::lock_guard<std::mutex> lock(watchdog_mu_);
    watchdog_stop_ = true;
  }
  watchdog_cv_.notify_all();
  watchdog.join();

  std::map<Role, size_t> answers_by_role;
  size_t versions = 0;
  int64_t pushes = 0;
  for (size_t i = 0; i < roles.size(); ++i) {
    answers_by_role[roles[i]] += logs[i].answers.size();
    versions += logs[i].versions.size();
    pushes += logs[i].pushes;
    for (size_t f = 0; f < logs[i].failures.size() && f < 5; ++f) {
      ADD_FAILURE() << "thread " << i << ": " << logs[i].failures[f];
    }
  }
  // Every kind of traffic really ran alongside the others.
  EXPECT_GT(answers_by_role[Role::kPlan], 0u);
  EXPECT_GT(answers_by_role[Role::kBatch], 0u);
  EXPECT_GT(answers_by_role[Role::kNavigate], 0u);
  EXPECT_GT(versions, 0u);

  const size_t checked = Verify(logs);
  std::printf(
      "concurrency_test: %d s, %zu Plan answers, %zu PlanBatch answers, %zu "
      "Navigate answers (%lld pushed), "
      "%zu map versions; %zu answers checked against Dijkstra on their "
      "version\n",
      seconds, answers_by_role[Role::kPlan], answers_by_role[Role::kBatch],
      answers_by_role[Role::kNavigate],
      static_cast<long long>(pushes), versions, checked);
}

}  // namespace
}  // namespace pathd::server
