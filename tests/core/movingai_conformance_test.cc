// Conformance against the Moving AI benchmarks in ../shared: A* and Dijkstra
// reproduce every scenario's stored optimal length within the precision the
// file stores it with, and BFS paths have the fewest moves (checked against a
// separate reference BFS in this file). Skips, saying so, when the benchmark
// folder is absent. Set PATHD_MOVINGAI_DIR to point elsewhere, and
// PATHD_CONFORMANCE_STRIDE=N to check every N-th scenario only (for slow
// sanitizer builds; the default checks every scenario).
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/map_io.h"
#include "core/planner.h"
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

int Stride() {
  const char* env = std::getenv("PATHD_CONFORMANCE_STRIDE");
  const int stride = env != nullptr ? std::atoi(env) : 1;
  return stride > 0 ? stride : 1;
}

class MovingAiConformance : public ::testing::TestWithParam<std::string> {};

TEST_P(MovingAiConformance, OptimalLengthsAndFewestMoves) {
  const fs::path map_path = BenchmarkDir() / GetParam();
  auto grid = ReadMovingAiMapFile(map_path.string());
  ASSERT_TRUE(grid.ok()) << grid.status();
  auto file = ReadMovingAiScenarioFileWithVersion(map_path.string() + ".scen");
  ASSERT_TRUE(file.ok()) << file.status();
  ASSERT_FALSE(file->scenarios.empty());

  const Planner* astar = PlannerRegistry::Default().Get("astar");
  const Planner* dijkstra = PlannerRegistry::Default().Get("dijkstra");
  const Planner* bfs = PlannerRegistry::Default().Get("bfs");
  SearchScratch scratch;
  std::vector<int> depth(grid->size()), stamp(grid->size(), -1);
  int checked = 0;
  const int stride = Stride();
  for (size_t i = 0; i < file->scenarios.size(); i += stride) {
    const Scenario& s = file->scenarios[i];
    const double tolerance = ScenarioTolerance(s, file->version);
    const PlanRequest request = PlanRequest::Between(s.start, s.goal);
    for (const Planner* planner : {astar, dijkstra}) {
      auto r = planner->Plan(*grid, request, StopCondition::None(), scratch);
      ASSERT_TRUE(r.ok()) << r.status();
      ASSERT_TRUE(r->found()) << planner->name() << " line " << s.line;
      ASSERT_NEAR(r->cost, s.optimal_length, tolerance)
          << planner->name() << " " << GetParam() << " line " << s.line;
      // On a 0/254 map cost and length coincide.
      ASSERT_DOUBLE_EQ(r->cost, r->length);
    }
    auto b = bfs->Plan(*grid, request, StopCondition::None(), scratch);
    ASSERT_TRUE(b.ok() && b->found()) << "bfs line " << s.line;
    ASSERT_TRUE(MeasurePath(*grid, b->path, request.cost).valid) << "bfs line " << s.line;
    ASSERT_EQ(static_cast<int>(b->path.size()) - 1,
              ReferenceMoves(*grid, s.start, s.goal, depth, stamp, s.line))
        << "bfs " << GetParam() << " line " << s.line;
    ++checked;
  }
  std::printf("%s: %d of %zu scenarios checked, A* and Dijkstra optimal, BFS "
              "fewest moves\n",
              GetParam().c_str(), checked, file->scenarios.size());
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
