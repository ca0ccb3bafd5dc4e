// pathd_bench: runs the registered planners over Moving AI maps and their
// scenario files and prints, per map and planner, the number of queries, mean
// and p95 microseconds per query, mean expansions and expansions per second,
// plus the speed ratio against A* measured in the same run. Figures, not
// assertions: the README records them with the command that produced them.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/time/clock.h"
#include "core/map_io.h"
#include "core/planner.h"

ABSL_FLAG(std::string, movingai_dir, "../shared/benchmarks/movingai",
          "folder holding <set>/<map>.map and <map>.map.scen files");
ABSL_FLAG(std::string, maps, "",
          "comma-separated map paths relative to --movingai_dir (e.g. "
          "dao/brc202d.map); empty = every map found");
ABSL_FLAG(std::string, planners, "astar,dijkstra,bfs",
          "comma-separated planner names");
ABSL_FLAG(int, limit, 1000, "use at most the first N scenarios of each map (0 = all)");
ABSL_FLAG(int, repeat, 1, "run each query this many times (reports the per-query mean)");

namespace fs = std::filesystem;

namespace {

struct Figures {
  int queries = 0;
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
  double total_expansions = 0, total_seconds = 0, total_cost = 0;
  for (const pathd::Scenario& s : scenarios) {
    const pathd::PlanRequest request = pathd::PlanRequest::Between(s.start, s.goal);
    double best_cost = 0;
    const absl::Time t0 = absl::Now();
    int64_t expansions = 0;
    for (int r = 0; r < repeat; ++r) {
      auto result = planner.Plan(grid, request, pathd::StopCondition::None(), scratch);
      if (!result.ok() || !result->found()) {
        std::fprintf(stderr, "%s failed on line %d\n", std::string(planner.name()).c_str(),
                     s.line);
        continue;
      }
      expansions = result->expansions;
      best_cost = result->cost;
    }
    const double seconds = absl::ToDoubleSeconds(absl::Now() - t0) / repeat;
    micros.push_back(seconds * 1e6);
    total_seconds += seconds;
    total_expansions += static_cast<double>(expansions);
    total_cost += best_cost;
  }
  Figures f;
  f.queries = static_cast<int>(micros.size());
  if (micros.empty()) return f;
  std::sort(micros.begin(), micros.end());
  f.mean_us = total_seconds * 1e6 / f.queries;
  f.p95_us = micros[std::min(micros.size() - 1, micros.size() * 95 / 100)];
  f.mean_expansions = total_expansions / f.queries;
  f.expansions_per_second = total_seconds > 0 ? total_expansions / total_seconds : 0;
  f.mean_cost = total_cost / f.queries;
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "pathd_bench [--movingai_dir DIR] [--maps a.map,b.map] [--planners astar,...] "
      "[--limit N]\nPrints per map and planner: queries, mean/p95 us per query, "
      "expansions per query and per second, and time relative to A*.");
  absl::ParseCommandLine(argc, argv);
  const fs::path root = absl::GetFlag(FLAGS_movingai_dir);
  std::vector<std::string> maps;
  if (!absl::GetFlag(FLAGS_maps).empty()) {
    maps = absl::StrSplit(absl::GetFlag(FLAGS_maps), ',', absl::SkipEmpty());
  } else {
    std::error_code ec;
    if (!fs::is_directory(root, ec)) {
      std::printf("Moving AI benchmarks not found at %s; nothing to measure\n",
                  root.c_str());
      return 0;
    }
    for (const auto& e : fs::recursive_directory_iterator(root, ec)) {
      if (e.path().extension() == ".map") maps.push_back(fs::relative(e.path(), root));
    }
    std::sort(maps.begin(), maps.end());
  }
  const std::vector<std::string> planners =
      absl::StrSplit(absl::GetFlag(FLAGS_planners), ',', absl::SkipEmpty());
  const int limit = absl::GetFlag(FLAGS_limit);
  const int repeat = std::max(1, absl::GetFlag(FLAGS_repeat));

  std::printf("pathd_bench: %u hardware threads, single-threaded queries, limit %d, "
              "repeat %d\n",
              std::thread::hardware_concurrency(), limit, repeat);
  std::printf("%-28s %-10s %7s %10s %10s %12s %12s %9s\n", "map", "planner", "queries",
              "mean_us", "p95_us", "expansions", "exp_per_s", "vs_astar");
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
    if (limit > 0 && static_cast<int>(scenarios.size()) > limit) scenarios.resize(limit);
    double astar_mean = 0;
    for (const std::string& planner_name : planners) {
      const pathd::Planner* planner = pathd::PlannerRegistry::Default().Get(planner_name);
      if (planner == nullptr) {
        std::fprintf(stderr, "unknown planner %s (known: %s)\n", planner_name.c_str(),
                     absl::StrJoin(pathd::PlannerRegistry::Default().Names(), ",").c_str());
        return 2;
      }
      const Figures f = Run(*planner, *grid, scenarios, repeat, scratch);
      if (planner_name == "astar") astar_mean = f.mean_us;
      char ratio[32] = "-";
      if (astar_mean > 0 && f.mean_us > 0) {
        std::snprintf(ratio, sizeof ratio, "%.2fx", f.mean_us / astar_mean);
      }
      std::printf("%-28s %-10s %7d %10.1f %10.1f %12.0f %12.3g %9s\n", name.c_str(),
                  planner_name.c_str(), f.queries, f.mean_us, f.p95_us,
                  f.mean_expansions, f.expansions_per_second, ratio);
      std::fflush(stdout);
    }
  }
  return 0;
}
