// 32 client threads against one in-process PathdServer on 127.0.0.1:0, all on
// the same three maps at once: Plan calls with the optimal planners (astar,
// dijkstra, jps, jps_plus, dstar_lite, spm), Navigate sessions (open, poses,
// shared observations, pushed paths) and UpdateMap calls. Every answer names the map
// version it was planned on; after the run the test rebuilds every version
// from the recorded updates and observations alone and checks each answer's
// cost against the reference Dijkstra on that version. A watchdog aborts the
// process with each thread's current call when no call completes for a while
// (a deadlock). `make test-tsan` runs this under ThreadSanitizer.
//
// PATHD_CONCURRENCY_SECONDS sets the run length (default 3) for longer local
// soaks; PATHD_CONCURRENCY_STALL_SECONDS the watchdog's limit (default 120,
// far above any call's time even under TSan on a loaded machine).
#include "tests/server/concurrency_fixture.h"

namespace pathd::server::concurrency_test {

void ConcurrencyTest::Watchdog(std::chrono::seconds stall) {
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

size_t ConcurrencyTest::Verify(const std::vector<ClientLog>& logs) {
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

std::string ConcurrencyTest::Check(
    const Grid& grid, const Answer& answer,
    std::map<std::tuple<int, int, int, int, int, double>, std::optional<double>>&
        memo) {
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

}  // namespace pathd::server::concurrency_test
