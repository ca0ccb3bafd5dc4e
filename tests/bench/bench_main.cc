// pathd_bench: runs the registered planners over Moving AI maps and their
// scenario files and prints, per map and planner, the number of queries and
// how many found a path, mean and p95 microseconds per query, mean expansions
// and expansions per second, the mean path length over the scenario's optimal
// length, and the speed-up over A* measured in the same run (A* runs first
// when listed). Figures, not assertions: docs/performance.md records them with the
// command that produced them.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/time/clock.h"
#include "core/search/registry.h"
#include "core/map_io/map_io.h"
#include "core/search/planner.h"
#include "tests/bench/movingai_maps.h"

ABSL_FLAG(std::string, movingai_dir, "../shared/benchmarks/movingai",
          "folder holding <set>/<map>.map and <map>.map.scen files");
ABSL_FLAG(std::string, maps, "",
          "comma-separated map paths relative to --movingai_dir (e.g. "
          "dao/brc202d.map); empty = every map found");
ABSL_FLAG(std::string, planners, "astar,dijkstra,bfs",
          "comma-separated planner names");
ABSL_FLAG(int, limit, 1000, "use at most the first N scenarios of each map (0 = all)");
ABSL_FLAG(int, sample, 0,
          "use N scenarios spread evenly over each map's whole scenario file "
          "(scenario floor((i + 1/2) * size / N) for i < N), instead of --limit's "
          "first N, which are the shortest; 0 = off");
ABSL_FLAG(int, repeat, 1, "run each query this many times (reports the per-query mean)");
ABSL_FLAG(double, heuristic_weight, 1.5, "weighted_astar's w");
ABSL_FLAG(int, lookahead, 64, "rtaa_star / lrta_star expansions per episode");
ABSL_FLAG(int64_t, max_expansions, 0,
          "expansion budget per query (0: none); planners that wander "
          "(real-time, potential field) get 4000000 when this is 0");

namespace fs = std::filesystem;

namespace {

struct Figures {
  int queries = 0;
  int found = 0;
  // Mean of length / optimal length over the found paths.
  double length_ratio = 0;
  double mean_us = 0;
  double p95_us = 0;
  double mean_expansions = 0;
  double expansions_per_second = 0;
  double mean_cost = 0;
};

Figures Run(const pathd::Planner& planner, const pathd::Grid& grid,
            const std::vector<pathd::Scenario>& scenarios, int repeat,
            pathd::SearchScratch& scratch) {
  std::vector<double> micros;
  micros.reserve(scenarios.size());
  double total_expansions = 0, total_seconds = 0, total_cost = 0, total_ratio = 0;
  int found = 0;
  const pathd::PlannerTraits& traits = planner.traits();
  int64_t budget = absl::GetFlag(FLAGS_max_expansions);
  if (budget == 0 && (traits.real_time || !traits.complete)) budget = 4'000'000;
  const pathd::StopCondition stop(absl::InfiniteFuture(), nullptr, budget);
  for (const pathd::Scenario& s : scenarios) {
    pathd::PlanRequest request = pathd::PlanRequest::Between(s.start, s.goal);
    request.heuristic_weight = absl::GetFlag(FLAGS_heuristic_weight);
    request.lookahead = absl::GetFlag(FLAGS_lookahead);
    const absl::Time t0 = absl::Now();
    absl::StatusOr<pathd::PlanResult> result;
    for (int r = 0; r < repeat; ++r) {
      result = planner.Plan(grid, request, stop, scratch);
    }
    const double seconds = absl::ToDoubleSeconds(absl::Now() - t0) / repeat;
    if (!result.ok()) {
      std::fprintf(stderr, "%s: %s\n", std::string(planner.name()).c_str(),
                   std::string(result.status().message()).c_str());
      return Figures{};
    }
    micros.push_back(seconds * 1e6);
    total_seconds += seconds;
    total_expansions += static_cast<double>(result->expansions);
    if (result->found()) {
      ++found;
      total_cost += result->cost;
      total_ratio += s.optimal_length > 0 ? result->length / s.optimal_length : 1.0;
    }
  }
  Figures f;
  f.queries = static_cast<int>(micros.size());
  f.found = found;
  if (micros.empty()) return f;
  if (found > 0) f.length_ratio = total_ratio / found;
  std::sort(micros.begin(), micros.end());
  f.mean_us = total_seconds * 1e6 / f.queries;
  f.p95_us = micros[std::min(micros.size() - 1, micros.size() * 95 / 100)];
  f.mean_expansions = total_expansions / f.queries;
  f.expansions_per_second = total_seconds > 0 ? total_expansions / total_seconds : 0;
  f.mean_cost = found > 0 ? total_cost / found : 0;
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "pathd_bench [--movingai_dir DIR] [--maps a.map,b.map] [--planners astar,...] "
      "[--limit N | --sample N] [--heuristic_weight W] [--lookahead N] [--max_expansions N]\n"
      "Prints per map and planner: queries, paths found, mean/p95 us per query, "
      "expansions per query and per second, mean length / optimal length, and "
      "the speed-up over A* (astar/x: A*'s mean time over this planner's).");
  absl::ParseCommandLine(argc, argv);
  const fs::path root = absl::GetFlag(FLAGS_movingai_dir);
  if (absl::GetFlag(FLAGS_maps).empty() && !fs::is_directory(root)) {
    std::printf("Moving AI benchmarks not found at %s; nothing to measure\n",
                root.c_str());
    return 0;
  }
  const std::vector<std::string> maps =
      pathd::bench::MovingAiMaps(root, absl::GetFlag(FLAGS_maps));
  std::vector<std::string> planners =
      absl::StrSplit(absl::GetFlag(FLAGS_planners), ',', absl::SkipEmpty());
  // A* first, so every other planner's speed-up is against this run's A*.
  std::stable_partition(planners.begin(), planners.end(),
                        [](const std::string& p) { return p == "astar"; });
  const int limit = absl::GetFlag(FLAGS_limit);
  const int repeat = std::max(1, absl::GetFlag(FLAGS_repeat));

  std::printf("pathd_bench: %u hardware threads, single-threaded queries, limit %d, "
              "sample %d, repeat %d\n",
              std::thread::hardware_concurrency(), limit, absl::GetFlag(FLAGS_sample),
              repeat);
  std::printf("%-28s %-24s %7s %6s %10s %10s %12s %10s %8s %9s\n", "map", "planner",
              "queries", "found", "mean_us", "p95_us", "expansions", "exp_per_s",
              "len/opt", "astar/x");
  pathd::SearchScratch scratch;
  for (const std::string& name : maps) {
    const fs::path map_path = root / name;
    auto grid = pathd::ReadMovingAiMapFile(map_path.string());
    if (!grid.ok()) {
      std::fprintf(stderr, "%s\n", std::string(grid.status().message()).c_str());
      return 1;
    }
    auto file = pathd::ReadMovingAiScenarioFileWithVersion(map_path.string() + ".scen");
    if (!file.ok()) {
      std::fprintf(stderr, "%s\n", std::string(file.status().message()).c_str());
      return 1;
    }
    std::vector<pathd::Scenario> scenarios = file->scenarios;
    const int sample = absl::GetFlag(FLAGS_sample);
    if (sample > 0 && static_cast<int>(scenarios.size()) > sample) {
      std::vector<pathd::Scenario> picked;
      const double stride = static_cast<double>(scenarios.size()) / sample;
      for (int i = 0; i < sample; ++i) {
        picked.push_back(scenarios[static_cast<size_t>(i * stride + stride / 2)]);
      }
      scenarios = std::move(picked);
    } else if (limit > 0 && static_cast<int>(scenarios.size()) > limit) {
      scenarios.resize(limit);
    }
    double astar_mean = 0;
    for (const std::string& planner_name : planners) {
      const pathd::Planner* planner = pathd::PlannerRegistry::Default().Get(planner_name);
      if (planner == nullptr) {
        std::fprintf(stderr, "unknown planner %s (known: %s)\n", planner_name.c_str(),
                     absl::StrJoin(pathd::PlannerRegistry::Default().Names(), ",").c_str());
        return 2;
      }
      const Figures f = Run(*planner, *grid, scenarios, repeat, scratch);
      if (f.queries == 0) continue;  // refused the map (reason printed)
      if (planner_name == "astar") astar_mean = f.mean_us;
      char ratio[32] = "-";
      if (astar_mean > 0 && f.mean_us > 0) {
        std::snprintf(ratio, sizeof ratio, "%.2f", astar_mean / f.mean_us);
      }
      std::printf("%-28s %-24s %7d %6d %10.1f %10.1f %12.0f %10.3g %8.4f %9s\n",
                  name.c_str(), planner_name.c_str(), f.queries, f.found, f.mean_us,
                  f.p95_us, f.mean_expansions, f.expansions_per_second, f.length_ratio,
                  ratio);
      std::fflush(stdout);
    }
  }
  return 0;
}
