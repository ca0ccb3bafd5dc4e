// ant_colony and reaction_diffusion on Moving AI scenarios: per map and
// planner, over a sample of scenarios spread over the scenario file, the
// paths found, the mean and largest cost over the optimum (Dijkstra on the
// same map, cost_weight 0 so the .scen optimum applies), the mean planning
// time, and ant_colony's mean iteration of its best path ("iterations to
// convergence") and reaction_diffusion's mean relative deviation of the
// arrival time from the exact cost-to-go. Maps: the bundled maps/arena2.map
// and the --movingai_maps under --movingai_dir (skipped when absent).
//
//   nature_bench --movingai_dir=../shared/benchmarks/movingai --sample=20
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/strings/str_split.h"
#include "absl/time/clock.h"
#include "core/map_io/map_io.h"
#include "core/search/registry.h"

ABSL_FLAG(std::string, movingai_dir, "../shared/benchmarks/movingai",
          "folder holding <set>/<map>.map and <map>.map.scen files");
ABSL_FLAG(std::string, movingai_maps, "dao/den520d,room/32room_000,random/random512-10-0",
          "maps under --movingai_dir, comma-separated");
ABSL_FLAG(std::string, bundled, "maps/arena2.map", "a bundled map with its .scen");
ABSL_FLAG(int, sample, 20, "scenarios per map, spread over the scenario file");
ABSL_FLAG(std::string, planners, "ant_colony,reaction_diffusion", "planners to run");

namespace {

std::vector<pathd::Scenario> Spread(const std::vector<pathd::Scenario>& all, int n) {
  std::vector<pathd::Scenario> out;
  if (all.empty() || n <= 0) return out;
  const size_t count = std::min(all.size(), static_cast<size_t>(n));
  for (size_t i = 0; i < count; ++i) out.push_back(all[i * all.size() / count]);
  return out;
}

void RunMap(const std::string& label, const std::string& path,
            const std::vector<std::string>& planners) {
  auto grid = pathd::ReadMovingAiMapFile(path);
  auto file = pathd::ReadMovingAiScenarioFileWithVersion(path + ".scen");
  if (!grid.ok() || !file.ok()) {
    std::printf("%-26s skipped: cannot read the map or its scenarios\n", label.c_str());
    return;
  }
  const std::vector<pathd::Scenario> scenarios =
      Spread(file->scenarios, absl::GetFlag(FLAGS_sample));
  pathd::CostParams cost;
  cost.cost_weight = 0.0;
  const pathd::Planner* dijkstra = pathd::PlannerRegistry::Default().Get("dijkstra");
  pathd::SearchScratch scratch;
  std::vector<double> optimum;
  for (const pathd::Scenario& s : scenarios) {
    auto r = dijkstra->Plan(*grid, pathd::PlanRequest::Between(s.start, s.goal, cost),
                            pathd::StopCondition::None(), scratch);
    optimum.push_back(r.ok() && r->found() ? r->cost : -1.0);
  }
  for (const std::string& name : planners) {
    const pathd::Planner* planner = pathd::PlannerRegistry::Default().Get(name);
    if (planner == nullptr) {
      std::fprintf(stderr, "unknown planner %s\n", name.c_str());
      continue;
    }
    int found = 0, queries = 0;
    std::string misses;  // the outcomes of the queries not found
    double ratio_sum = 0, ratio_max = 0, ms_sum = 0, extra_sum = 0, expansions = 0;
    for (size_t i = 0; i < scenarios.size(); ++i) {
      if (optimum[i] < 0) continue;
      ++queries;
      const absl::Time t0 = absl::Now();
      auto r = planner->Plan(*grid,
                             pathd::PlanRequest::Between(scenarios[i].start,
                                                         scenarios[i].goal, cost),
                             pathd::StopCondition::None(), scratch);
      ms_sum += absl::ToDoubleMilliseconds(absl::Now() - t0);
      if (r.ok()) expansions += static_cast<double>(r->expansions);
      if (r.ok() && !r->found()) {
        if (!misses.empty()) misses += ", ";
        misses += std::string(pathd::PlanOutcomeName(r->outcome));
      }
      if (!r.ok() || !r->found()) continue;
      ++found;
      const double ratio = optimum[i] > 0 ? r->cost / optimum[i] : 1.0;
      ratio_sum += ratio;
      ratio_max = std::max(ratio_max, ratio);
      if (r->ant_colony) extra_sum += r->ant_colony->best_iteration;
      if (r->reaction_diffusion) extra_sum += r->reaction_diffusion->mean_relative_error;
    }
    const char* extra_name = name == "ant_colony" ? "best iteration" : "T error (mean)";
    std::printf("%-26s %-19s found %3d/%-3d cost/opt mean %.4f max %.4f  "
                "%9.1f ms/query %11.0f expansions/query  %s %.3f\n",
                label.c_str(), name.c_str(), found, queries,
                found ? ratio_sum / found : 0.0, ratio_max,
                queries ? ms_sum / queries : 0.0, queries ? expansions / queries : 0.0,
                extra_name,
                found ? extra_sum / found : 0.0);
    if (!misses.empty()) std::printf("%26s not found: %s\n", "", misses.c_str());
  }
}

}  // namespace

int main(int argc, char** argv) {
  absl::ParseCommandLine(argc, argv);
  const std::vector<std::string> planners =
      absl::StrSplit(absl::GetFlag(FLAGS_planners), ',', absl::SkipEmpty());
  std::printf("%d scenarios per map spread over its .scen, cost_weight 0, defaults\n",
              absl::GetFlag(FLAGS_sample));
  RunMap(absl::GetFlag(FLAGS_bundled), absl::GetFlag(FLAGS_bundled), planners);
  const std::filesystem::path root = absl::GetFlag(FLAGS_movingai_dir);
  if (!std::filesystem::exists(root)) {
    std::printf("%s absent: Moving AI maps skipped\n", root.string().c_str());
    return 0;
  }
  const std::vector<std::string> maps =
      absl::StrSplit(absl::GetFlag(FLAGS_movingai_maps), ',', absl::SkipEmpty());
  for (const std::string& map : maps) {
    RunMap(map, (root / map).string() + ".map", planners);
  }
  return 0;
}
