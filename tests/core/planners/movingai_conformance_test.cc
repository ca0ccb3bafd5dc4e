// Conformance of every registered planner against the Moving AI benchmarks in
// ../shared: Dijkstra reproduces every scenario's stored optimal length within
// the precision the file stores it with, the other optimal planners match
// Dijkstra, fewest-move planners match a separate reference BFS in this file,
// and the rest are checked by what their traits promise (PlannerStride and
// kPlannerScenariosPerMap say how often). Skips, saying so, when the
// benchmark folder is absent. Set
// PATHD_MOVINGAI_DIR to point elsewhere, PATHD_CONFORMANCE_STRIDE=N to check
// every N-th scenario only (slow sanitizer builds), PATHD_CONFORMANCE_FULL=1
// to check every planner on every scenario.
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "absl/time/time.h"
#include "core/search/registry.h"
#include "core/search/path_measure.h"
#include "core/map_io/map_io.h"
#include "core/search/planner.h"
#include "gtest/gtest.h"

namespace pathd {
namespace {

namespace fs = std::filesystem;

fs::path BenchmarkDir() {
  if (const char* env = std::getenv("PATHD_MOVINGAI_DIR")) return env;
  return "../shared/benchmarks/movingai";
}

// Every "<set>/<name>.map" that has a ".map.scen" beside it, sorted.
std::vector<std::string> BenchmarkMaps() {
  std::vector<std::string> maps;
  std::error_code ec;
  const fs::path root = BenchmarkDir();
  if (!fs::is_directory(root, ec)) return maps;
  for (const auto& entry : fs::recursive_directory_iterator(root, ec)) {
    const fs::path& p = entry.path();
    if (p.extension() == ".map" && fs::exists(p.string() + ".scen")) {
      maps.push_back(fs::relative(p, root).string());
    }
  }
  std::sort(maps.begin(), maps.end());
  return maps;
}

// Fewest legal moves from start to goal, by a plain BFS written separately
// from the planners (its own neighbour rule), stopping at the goal.
int ReferenceMoves(const Grid& grid, Cell start, Cell goal, std::vector<int>& depth,
                   std::vector<int>& stamp, int id) {
  const int w = grid.width(), h = grid.height();
  auto free_cell = [&](int x, int y) {
    return x >= 0 && y >= 0 && x < w && y < h && grid.cost(x, y) == kFreeCost;
  };
  std::vector<Cell> queue{start};
  stamp[grid.Index(start)] = id;
  depth[grid.Index(start)] = 0;
  for (size_t head = 0; head < queue.size(); ++head) {
    const Cell c = queue[head];
    const int d = depth[grid.Index(c)];
    if (c == goal) return d;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx == 0 && dy == 0) continue;
        const int nx = c.x + dx, ny = c.y + dy;
        if (!free_cell(nx, ny)) continue;
        if (dx != 0 && dy != 0 && (!free_cell(c.x + dx, c.y) || !free_cell(c.x, c.y + dy))) {
          continue;
        }
        const size_t i = grid.Index(nx, ny);
        if (stamp[i] == id) continue;
        stamp[i] = id;
        depth[i] = d + 1;
        queue.push_back({nx, ny});
      }
    }
  }
  return -1;
}

int EnvInt(const char* name, int fallback) {
  const char* env = std::getenv(name);
  const int value = env != nullptr ? std::atoi(env) : fallback;
  return value > 0 ? value : fallback;
}

// How often each planner is checked: every scenario for the searches that
// stop at the goal and for the exact distance transform (a whole-map Dijkstra
// sweep per query, ~5-20 ms), every n-th for the raster distance transform
// (hundreds of passes per query on the mazes, ~150 ms), the any-angle
// searches, the incremental searches (LPA*, D* Lite, shortest path map: run
// here from scratch per query, their repairs are checked against fresh
// searches by incremental_test), and the planners that wander (real-time,
// potential field), so the suite stays within minutes on 2 cores.
// PATHD_CONFORMANCE_STRIDE=N multiplies every stride (sanitizer builds);
// PATHD_CONFORMANCE_FULL=1 checks every planner on every scenario.
int PlannerStride(const Planner& planner) {
  if (std::getenv("PATHD_CONFORMANCE_FULL") != nullptr) return 1;
  const PlannerTraits& t = planner.traits();
  int stride = 1;
  if (planner.name() == "distance_transform") {
    stride = 20;
  } else if (planner.name() == "voronoi") {
    // Two searches per query over the clearance field (10-50 ms on 512²
    // maps); cell_planners_test and geometric_planners_test check it
    // against brute force.
    stride = 50;
  } else if (t.any_angle || t.incremental) {
    stride = 4;
  } else if (t.real_time || !t.complete) {
    stride = 25;
  } else if (!t.optimal && !t.fewest_moves && !t.bounded) {
    stride = 5;
  }
  return stride;
}

// Dijkstra checks at most about kDijkstraScenariosPerMap scenarios of one
// map against the file's optimum, every other planner at most about
// kPlannerScenariosPerMap of those: the mazes have 5760-11960 scenarios (the
// other maps 470-3060); at 4000/1500 one maze took 4.6 minutes alone and
// the suite kept CI over its hour, on queries that all look alike. Both
// samples are spread over the whole file, so every length bucket is kept.
constexpr size_t kDijkstraScenariosPerMap = 2000;
constexpr size_t kPlannerScenariosPerMap = 750;

// Budget for the planners that may wander: several times what any optimal
// search of these maps expands (a 512x512 map has 262,144 cells); LRTA*
// spent a sixth of a maze's time failing at 4,000,000.
constexpr int64_t kWanderBudget = 1'500'000;


struct PlannerTally {
  const Planner* planner = nullptr;
  int stride = 1;
  int checked = 0;
  int found = 0;
  // Sum of cost / optimal over found paths, for the non-optimal planners.
  double ratio_sum = 0.0;
  // Time in Plan: shows where the suite's minutes go.
  absl::Duration planning;
};

class MovingAiConformance : public ::testing::TestWithParam<std::string> {};

// Every registered planner against the stored optimal lengths: optimal
// planners match Dijkstra (and Dijkstra the file) within the file's precision;
// fewest-move planners match a reference BFS; weighted A* stays within its
// bound; any-angle paths have line of sight and are never longer than the
// optimum; every other planner's paths are legal and collision-free whenever
// it reports success, and complete ones always succeed on these solvable
// scenarios.
TEST_P(MovingAiConformance, EveryPlannerOnEveryScenario) {
  const fs::path map_path = BenchmarkDir() / GetParam();
  auto grid = ReadMovingAiMapFile(map_path.string());
  ASSERT_TRUE(grid.ok()) << grid.status();
  auto file = ReadMovingAiScenarioFileWithVersion(map_path.string() + ".scen");
  ASSERT_TRUE(file.ok()) << file.status();
  ASSERT_FALSE(file->scenarios.empty());

  const PlannerRegistry& registry = PlannerRegistry::Default();
  const Planner* dijkstra = registry.Get("dijkstra");
  ASSERT_NE(dijkstra, nullptr);
  std::vector<PlannerTally> tallies;
  for (const std::string& name : registry.Names()) {
    const Planner* p = registry.Get(name);
    // Geometric planners answer in the plane, shorter than the grid optimum
    // these scenarios list: geometric_movingai_test checks them. Kinematic
    // planners answer for a robot that cannot follow every grid path:
    // state_lattice_test and hybrid_astar_test check them.
    if (p != dijkstra && !p->traits().geometric && !p->traits().kinematic) {
      tallies.push_back({p, PlannerStride(*p)});
    }
  }
  constexpr double kWeight = 1.5;
  SearchScratch scratch;
  std::vector<int> depth(grid->size()), stamp(grid->size(), -1);
  const bool full = std::getenv("PATHD_CONFORMANCE_FULL") != nullptr;
  const size_t count = file->scenarios.size();
  // Scenario i = k * step for the k-th Dijkstra check; a planner with
  // stride s sees every s-th of those.
  const size_t step = static_cast<size_t>(EnvInt("PATHD_CONFORMANCE_STRIDE", 1)) *
                      (full ? 1 : (count + kDijkstraScenariosPerMap - 1) /
                                      kDijkstraScenariosPerMap);
  const size_t checks = (count + step - 1) / step;
  const size_t map_stride =
      full ? 1 : (checks + kPlannerScenariosPerMap - 1) / kPlannerScenariosPerMap;
  for (PlannerTally& tally : tallies) {
    tally.stride *= static_cast<int>(map_stride);
  }
  int checked = 0;
  int bfs_id = 0;
  for (size_t i = 0, k = 0; i < count; i += step, ++k) {
    const Scenario& s = file->scenarios[i];
    const double tolerance = ScenarioTolerance(s, file->version);
    PlanRequest request = PlanRequest::Between(s.start, s.goal);
    request.heuristic_weight = kWeight;
    auto d = dijkstra->Plan(*grid, request, StopCondition::None(), scratch);
    ASSERT_TRUE(d.ok()) << d.status();
    ASSERT_TRUE(d->found()) << "dijkstra line " << s.line;
    ASSERT_NEAR(d->cost, s.optimal_length, tolerance)
        << "dijkstra " << GetParam() << " line " << s.line;
    // On a 0/254 map cost and length coincide.
    ASSERT_DOUBLE_EQ(d->cost, d->length);
    const double optimum = d->cost;
    ++checked;
    // Computed once per scenario, by the first fewest-moves planner checked.
    int reference_moves = -1;

    for (PlannerTally& tally : tallies) {
      if (k % static_cast<size_t>(tally.stride) != 0) continue;
      const Planner& planner = *tally.planner;
      const PlannerTraits& t = planner.traits();
      const bool wanders = t.real_time || !t.complete;
      const StopCondition stop =
          wanders ? StopCondition(absl::InfiniteFuture(), nullptr, kWanderBudget)
                  : StopCondition::None();
      const absl::Time started = absl::Now();
      auto r = planner.Plan(*grid, request, stop, scratch);
      tally.planning += absl::Now() - started;
      ASSERT_TRUE(r.ok()) << planner.name() << ": " << r.status();
      const std::string where =
          absl::StrFormat("%s %s line %d", planner.name(), GetParam(), s.line);
      ++tally.checked;
      if (!r->found()) {
        ASSERT_TRUE(wanders) << where << ": " << PlanOutcomeName(r->outcome);
        ASSERT_TRUE(r->outcome == PlanOutcome::kExpansionLimit ||
                    r->outcome == PlanOutcome::kLocalMinimum)
            << where << ": " << PlanOutcomeName(r->outcome);
        continue;
      }
      ++tally.found;
      ASSERT_EQ(r->path.front(), s.start) << where;
      ASSERT_EQ(r->path.back(), s.goal) << where;
      const PathMeasure m = MeasureResultPath(*grid, *r, request.cost);
      ASSERT_TRUE(m.valid) << where << ": illegal step " << m.first_invalid;
      ASSERT_NEAR(r->cost, m.cost, 1e-9 * (1 + m.cost)) << where;
      ASSERT_NEAR(r->length, m.length, 1e-9 * (1 + m.length)) << where;
      tally.ratio_sum += r->cost / (optimum > 0 ? optimum : 1.0);
      if (t.optimal) {
        ASSERT_NEAR(r->cost, optimum, 1e-9 * (1 + optimum)) << where;
      } else if (t.fewest_moves) {
        if (reference_moves < 0) {
          reference_moves =
              ReferenceMoves(*grid, s.start, s.goal, depth, stamp, ++bfs_id);
        }
        ASSERT_EQ(static_cast<int>(r->path.size()) - 1, reference_moves) << where;
      } else if (t.bounded) {
        ASSERT_LE(r->cost, kWeight * optimum + 1e-9 * (1 + optimum)) << where;
      } else if (t.any_angle) {
        ASSERT_LE(r->length, optimum + 1e-9 * (1 + optimum)) << where;
      }
    }
  }
  std::printf("%s: %d of %zu scenarios, dijkstra matches the file\n",
              GetParam().c_str(), checked, file->scenarios.size());
  for (const PlannerTally& tally : tallies) {
    std::printf(
        "  %-26s every %3d: %5d checked, %5d found, mean cost/optimal %.4f, "
        "%.1f s\n",
        std::string(tally.planner->name()).c_str(), tally.stride,
        tally.checked, tally.found,
        tally.found > 0 ? tally.ratio_sum / tally.found : 0.0,
        absl::ToDoubleSeconds(tally.planning));
  }
}

std::string TestName(const ::testing::TestParamInfo<std::string>& info) {
  std::string name;
  for (char c : info.param) {
    name += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  }
  return name;
}

INSTANTIATE_TEST_SUITE_P(Shared, MovingAiConformance,
                         ::testing::ValuesIn(BenchmarkMaps()), TestName);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(MovingAiConformance);

TEST(MovingAiBenchmarks, PresentOrSkipped) {
  if (BenchmarkMaps().empty()) {
    GTEST_SKIP() << "Moving AI benchmarks not found at " << BenchmarkDir()
                 << " (expected ../shared/benchmarks/movingai beside the project "
                    "root, or PATHD_MOVINGAI_DIR); conformance checks skipped";
  }
  std::printf("Moving AI benchmarks: %zu maps under %s\n", BenchmarkMaps().size(),
              BenchmarkDir().c_str());
}

}  // namespace
}  // namespace pathd
