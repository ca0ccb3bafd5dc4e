// pathd_check: runs planners over Moving AI maps and their scenario files and
// reports every query whose result is wrong: no path, a path that is not a
// legal move chain (or any-angle chain) from start to goal, a reported cost
// or length that differs from the path's measure, or, for planners whose
// traits say optimal, a cost other than the scenario's stored optimum. A local
// tool for planner authors (the conformance test runs the same checks in
// ctest); prints one line per map and planner and exits 1 on any failure.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "core/search/registry.h"
#include "core/search/path_measure.h"
#include "core/map_io/map_io.h"
#include "core/search/planner.h"
#include "tests/bench/movingai_maps.h"

ABSL_FLAG(std::string, movingai_dir, "../shared/benchmarks/movingai",
          "folder holding <set>/<map>.map and <map>.map.scen files");
ABSL_FLAG(std::string, maps, "",
          "comma-separated map paths relative to --movingai_dir (e.g. "
          "dao/brc202d.map); empty = every map found");
ABSL_FLAG(std::string, planners, "astar", "comma-separated planner names");
ABSL_FLAG(int, stride, 1, "check every N-th scenario only");
ABSL_FLAG(int, max_reports, 5, "failures printed per map and planner");

namespace fs = std::filesystem;

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "pathd_check [--movingai_dir DIR] [--maps a.map,b.map] [--planners "
      "jps,...] "
      "[--stride N]\nChecks every scenario's path, cost and (for optimal "
      "planners) "
      "the stored optimal length.");
  absl::ParseCommandLine(argc, argv);
  const fs::path root = absl::GetFlag(FLAGS_movingai_dir);
  const std::vector<std::string> maps =
      pathd::bench::MovingAiMaps(root, absl::GetFlag(FLAGS_maps));
  if (maps.empty()) {
    std::fprintf(stderr, "no Moving AI maps under %s\n", root.c_str());
    return 2;
  }
  std::vector<const pathd::Planner*> planners;
  const std::vector<std::string> names =
      absl::StrSplit(absl::GetFlag(FLAGS_planners), ',', absl::SkipEmpty());
  for (const std::string& name : names) {
    const pathd::Planner* p = pathd::PlannerRegistry::Default().Get(name);
    if (p == nullptr) {
      std::fprintf(stderr, "unknown planner %s (known: %s)\n", name.c_str(),
                   absl::StrJoin(pathd::PlannerRegistry::Default().Names(), ",")
                       .c_str());
      return 2;
    }
    // The checks are the grid's (legal moves, the scenario's optimum); a
    // kinematic planner's paths are poses for a robot with a turning radius,
    // which tests/core/planners/state_lattice_test checks.
    if (p->traits().kinematic) {
      std::fprintf(stderr, "planner %s is kinematic: pathd_check checks grid paths\n",
                   name.c_str());
      return 2;
    }
    planners.push_back(p);
  }
  const int stride = std::max(1, absl::GetFlag(FLAGS_stride));
  const int max_reports = absl::GetFlag(FLAGS_max_reports);

  pathd::SearchScratch scratch;
  int total_failures = 0;
  for (const std::string& name : maps) {
    const fs::path map_path = root / name;
    auto grid = pathd::ReadMovingAiMapFile(map_path.string());
    auto file =
        pathd::ReadMovingAiScenarioFileWithVersion(map_path.string() + ".scen");
    if (!grid.ok() || !file.ok()) {
      std::fprintf(
          stderr, "%s: %s\n", name.c_str(),
          std::string((grid.ok() ? file.status() : grid.status()).message())
              .c_str());
      return 2;
    }
    for (const pathd::Planner* planner : planners) {
      int checked = 0, failures = 0;
      auto fail = [&](const pathd::Scenario& s, const std::string& what) {
        if (++failures <= max_reports) {
          std::printf("  FAIL %s %s line %d (%d,%d)->(%d,%d): %s\n",
                      name.c_str(), std::string(planner->name()).c_str(),
                      s.line, s.start.x, s.start.y, s.goal.x, s.goal.y,
                      what.c_str());
        }
      };
      for (size_t i = 0; i < file->scenarios.size(); i += stride) {
        const pathd::Scenario& s = file->scenarios[i];
        ++checked;
        const pathd::PlanRequest request =
            pathd::PlanRequest::Between(s.start, s.goal);
        auto r = planner->Plan(*grid, request, pathd::StopCondition::None(),
                               scratch);
        if (!r.ok()) {
          fail(s, std::string(r.status().message()));
          continue;
        }
        if (!r->found()) {
          fail(s, std::string(pathd::PlanOutcomeName(r->outcome)));
          continue;
        }
        const pathd::PathMeasure m =
            pathd::MeasureResultPath(*grid, *r, request.cost);
        if (!m.valid || r->path.front() != s.start ||
            r->path.back() != s.goal) {
          fail(s, "path is not a legal chain from start to goal");
          continue;
        }
        if (std::abs(m.cost - r->cost) > 1e-9 ||
            std::abs(m.length - r->length) > 1e-9) {
          fail(s, "reported cost/length " + std::to_string(r->cost) + "/" +
                      std::to_string(r->length) + " but the path measures " +
                      std::to_string(m.cost) + "/" + std::to_string(m.length));
          continue;
        }
        const double tolerance = pathd::ScenarioTolerance(s, file->version);
        if (planner->traits().optimal &&
            std::abs(r->cost - s.optimal_length) > tolerance) {
          fail(s, "cost " + std::to_string(r->cost) + " but optimal " +
                      std::to_string(s.optimal_length));
        }
      }
      total_failures += failures;
      std::printf("%-28s %-10s checked %6d failures %d\n", name.c_str(),
                  std::string(planner->name()).c_str(), checked, failures);
      std::fflush(stdout);
    }
  }
  return total_failures == 0 ? 0 : 1;
}
