// Table benchmark: N x M cost tables (core/fleet/table.h) on Moving AI maps,
// 512 x 512 as shipped and 1024 x 1024 made by tiling one 2 x 2, against one
// A* query per entry of a row: the time of the table, per entry, and over
// M A* queries (the target: a 100 x 100 table under 10x the time of
// one A* query per destination). Backward tables are timed with fresh fields
// (as a cold server cache builds them) and again with every field cached
// (as a repeated table finds them); forward tables search per source. Times
// are the thread's CPU time.
//
//   build/tests/bench/table_bench --movingai_dir=../shared/benchmarks/movingai
//       --maps=street/Berlin_0_512.map,room/32room_000.map --sizes=10,100,500
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_split.h"
#include "absl/time/clock.h"
#include "core/fleet/table.h"
#include "core/map_io/map_io.h"
#include "core/search/registry.h"
#include "core/search/search_scratch.h"

ABSL_FLAG(std::string, movingai_dir, "../shared/benchmarks/movingai",
          "folder of the Moving AI maps");
ABSL_FLAG(std::string, maps, "street/Berlin_0_512.map,room/32room_000.map",
          "comma-separated maps under --movingai_dir");
ABSL_FLAG(std::string, sizes, "10,100", "table sides N (N x N tables)");
ABSL_FLAG(int, astar_queries, 100, "A* queries timed per map and size for the mean");
ABSL_FLAG(bool, tile, true, "also run each map tiled 2 x 2 (1024 x 1024 from 512)");
ABSL_FLAG(int, seed, 21, "random seed for the sources and destinations");

namespace pathd {
namespace {

Grid Tiled(const Grid& g) {
  Grid out = Grid::Create(2 * g.width(), 2 * g.height()).value();
  for (int32_t y = 0; y < out.height(); ++y) {
    for (int32_t x = 0; x < out.width(); ++x) {
      out.set_cost(x, y, g.cost(x % g.width(), y % g.height()));
    }
  }
  return out;
}

std::vector<Cell> RandomFree(const Grid& grid, std::mt19937& rng, int n) {
  std::vector<Cell> out;
  while (static_cast<int>(out.size()) < n) {
    const Cell c{static_cast<int32_t>(rng() % grid.width()),
                 static_cast<int32_t>(rng() % grid.height())};
    if (Traversable(grid.cost(c), false)) out.push_back(c);
  }
  return out;
}

// CPU seconds of this thread: the benchmark is single-threaded, and on a
// machine shared with builds CPU time holds still where wall time does not.
double CpuNow() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}
double Seconds(double t0) { return CpuNow() - t0; }

void Run(const std::string& name, std::shared_ptr<const Grid> grid, int n, std::mt19937& rng) {
  const std::vector<Cell> sources = RandomFree(*grid, rng, n);
  const std::vector<Cell> dests = RandomFree(*grid, rng, n);
  const CostParams cost;
  // One A* query: the mean over pairs of this table.
  const Planner* astar = PlannerRegistry::Default().Get("astar");
  SearchScratch scratch;
  const int queries = absl::GetFlag(FLAGS_astar_queries);
  double t0 = CpuNow();
  for (int q = 0; q < queries; ++q) {
    PlanRequest request;
    request.start = sources[q % n];
    request.goal = dests[(q * 7 + 3) % n];
    request.cost = cost;
    (void)astar->Plan(*grid, request, StopCondition::None(), scratch);
  }
  const double astar_s = Seconds(t0) / queries;
  const double budget_s = n * astar_s;  // one A* query per destination

  // Backward, fresh fields; then the same with the fields kept.
  std::map<std::pair<int32_t, int32_t>, std::shared_ptr<const ShortestPathMap>> kept;
  const FieldProvider keeping = [&](Cell goal,
                                    const StopCondition& stop) -> absl::StatusOr<FieldLookup> {
    auto& slot = kept[{goal.x, goal.y}];
    if (slot != nullptr) return FieldLookup{PlanOutcome::kFound, slot, true, 0};
    absl::StatusOr<std::unique_ptr<ShortestPathMap>> built =
        ShortestPathMap::Build(grid, goal, cost, stop);
    if (!built.ok()) return built.status();
    slot = std::move(*built);
    return FieldLookup{PlanOutcome::kFound, slot, false, 0};
  };
  struct Row {
    const char* method;
    double seconds;
  };
  std::vector<Row> rows;
  t0 = CpuNow();
  (void)ComputeTable(grid, cost, sources, dests, TableMethod::kBackward, keeping,
                     StopCondition::None());
  rows.push_back({"backward, fields built", Seconds(t0)});
  t0 = CpuNow();
  (void)ComputeTable(grid, cost, sources, dests, TableMethod::kBackward, keeping,
                     StopCondition::None());
  rows.push_back({"backward, fields cached", Seconds(t0)});
  t0 = CpuNow();
  (void)ComputeTable(grid, cost, sources, dests, TableMethod::kForward, {},
                     StopCondition::None());
  rows.push_back({"forward", Seconds(t0)});
  for (const Row& r : rows) {
    std::printf("| %s | %dx%d | %d x %d | %s | %.3f | %.1f | %.3f | %.2f |\n", name.c_str(),
                grid->width(), grid->height(), n, n, r.method, r.seconds,
                1e6 * r.seconds / (static_cast<double>(n) * n), 1e3 * astar_s,
                r.seconds / budget_s);
    std::fflush(stdout);
  }
}

}  // namespace
}  // namespace pathd

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage("Times N x N cost tables against A* queries.");
  absl::ParseCommandLine(argc, argv);
  std::mt19937 rng(absl::GetFlag(FLAGS_seed));
  std::vector<int> sizes;
  for (const absl::string_view s : absl::StrSplit(absl::GetFlag(FLAGS_sizes), ',')) {
    int n = 0;
    if (absl::SimpleAtoi(s, &n) && n > 0) sizes.push_back(n);
  }
  std::printf(
      "| map | size | table | method | CPU s | us per entry | one A* (ms) | table / (N x A*) "
      "|\n|---|---|---|---|---|---|---|---|\n");
  for (const absl::string_view map : absl::StrSplit(absl::GetFlag(FLAGS_maps), ',')) {
    const std::string path =
        (std::filesystem::path(absl::GetFlag(FLAGS_movingai_dir)) / std::string(map)).string();
    absl::StatusOr<pathd::Grid> grid = pathd::ReadMovingAiMapFile(path);
    if (!grid.ok()) {
      std::fprintf(stderr, "%s: %s\n", path.c_str(), std::string(grid.status().message()).c_str());
      return 1;
    }
    auto shared = std::make_shared<const pathd::Grid>(*grid);
    std::vector<std::pair<std::string, std::shared_ptr<const pathd::Grid>>> variants = {
        {std::string(map), shared}};
    if (absl::GetFlag(FLAGS_tile)) {
      variants.push_back({std::string(map) + " (2x2)",
                          std::make_shared<const pathd::Grid>(pathd::Tiled(*grid))});
    }
    for (const auto& [name, g] : variants) {
      for (const int n : sizes) pathd::Run(name, g, n, rng);
    }
  }
  return 0;
}
