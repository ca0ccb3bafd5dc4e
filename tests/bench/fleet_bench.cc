// Multi-robot path finding benchmark (core/fleet/mapf.h): Moving AI maps
// (random, room, maze) and a generated warehouse, N robots with random
// distinct starts and goals (seeded), every solver with a deadline. Prints a
// markdown table: success rate, mean solver time (successes; wall time, one
// thread), and sum of costs over the lower bound (the sum of individual
// shortest paths, or CBS's bound), mean expansions and iterations
// (FleetPlan's counters). Every plan is checked with the
// independent checker (tests/testing/fleet_checker.h); a failed check is
// reported and counts as a failure.
//
//   build/tests/bench/fleet_bench --movingai_dir=../shared/benchmarks/movingai
//       --robots=10,50,100 --solvers=lacam,pibt,prioritized --deadline_s=30
#include <cstdio>
#include <filesystem>
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
#include "absl/time/time.h"
#include "core/fleet/mapf.h"
#include "core/map_io/map_io.h"
#include "tests/testing/fleet_checker.h"

ABSL_FLAG(std::string, movingai_dir, "../shared/benchmarks/movingai",
          "folder of the Moving AI maps");
ABSL_FLAG(
    std::string, maps,
    "random/random512-10-0.map,room/32room_000.map,maze/"
    "maze512-4-0.map,warehouse",
    "comma-separated maps under --movingai_dir; 'warehouse' is generated");
ABSL_FLAG(std::string, robots, "10,50,100,200,500", "robot counts");
ABSL_FLAG(std::string, solvers, "prioritized,cbs,ecbs,lacam,pibt",
          "solvers; ecbs = cbs with --suboptimality, lacam* = lacam refining "
          "until the deadline");
ABSL_FLAG(double, suboptimality, 1.5, "ECBS's bound");
ABSL_FLAG(int, instances, 3, "start/goal sets per map and robot count");
ABSL_FLAG(double, deadline_s, 30.0, "deadline per solver run, seconds");
ABSL_FLAG(int, max_cbs_robots, 100, "skip cbs/ecbs above this many robots");
ABSL_FLAG(int, seed, 21, "random seed for starts and goals");

namespace pathd {
namespace {

// A warehouse-like map in the spirit of Moving AI's MAPF warehouse maps
// (their warehouse-10-20-10-2-1 is 161 x 63 cells): rows of shelves 10
// cells long and 1 deep with 1-cell aisles between rows, 2-cell cross
// aisles between shelves and 10-cell free margins left and right for
// stations.
Grid Warehouse() {
  constexpr int kW = 170;
  constexpr int kH = 84;
  Grid g = Grid::Create(kW, kH).value();
  for (int y = 4; y < kH - 4; ++y) {
    if (y % 2 != 0) continue;  // shelf rows on even y, aisles between
    for (int x = 10; x < kW - 10; ++x) {
      if ((x - 10) % 12 < 10) g.set_cost(x, y, kLethalCost);
    }
  }
  return g;
}

std::vector<Cell> LargestComponent(const Grid& g) {
  std::vector<int> seen(g.size(), 0);
  std::vector<Cell> best;
  for (int y = 0; y < g.height(); ++y) {
    for (int x = 0; x < g.width(); ++x) {
      if (!Traversable(g.cost(x, y), false) || seen[g.Index(x, y)] != 0)
        continue;
      std::vector<Cell> comp{{x, y}};
      seen[g.Index(x, y)] = 1;
      for (size_t k = 0; k < comp.size(); ++k) {
        for (const auto& [dx, dy] :
             {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
          const Cell v{comp[k].x + dx, comp[k].y + dy};
          if (g.InBounds(v) && Traversable(g.cost(v), false) &&
              seen[g.Index(v)] == 0) {
            seen[g.Index(v)] = 1;
            comp.push_back(v);
          }
        }
      }
      if (comp.size() > best.size()) best = std::move(comp);
    }
  }
  return best;
}

struct Cellwise {
  int runs = 0;
  int solved = 0;
  double seconds = 0.0;
  double ratio = 0.0;
  double expansions = 0.0;
  double iterations = 0.0;
};

void RunMap(const std::string& name, const Grid& grid, std::mt19937& rng) {
  const std::vector<Cell> component = LargestComponent(grid);
  std::vector<std::string> solvers =
      absl::StrSplit(absl::GetFlag(FLAGS_solvers), ',', absl::SkipEmpty());
  for (const absl::string_view rs :
       absl::StrSplit(absl::GetFlag(FLAGS_robots), ',')) {
    int n = 0;
    if (!absl::SimpleAtoi(rs, &n) || n <= 0 ||
        n > static_cast<int>(component.size()))
      continue;
    std::vector<FleetProblem> problems;
    for (int k = 0; k < absl::GetFlag(FLAGS_instances); ++k) {
      std::vector<Cell> starts = component;
      std::vector<Cell> goals = component;
      std::shuffle(starts.begin(), starts.end(), rng);
      std::shuffle(goals.begin(), goals.end(), rng);
      FleetProblem p;
      p.grids = {&grid};
      for (int i = 0; i < n; ++i)
        p.robots.push_back(FleetRobot{starts[i], goals[i], 0});
      problems.push_back(std::move(p));
    }
    for (const std::string& s : solvers) {
      FleetOptions options;
      if (s == "prioritized") {
        options.solver = FleetSolver::kPrioritized;
      } else if (s == "cbs" || s == "ecbs") {
        if (n > absl::GetFlag(FLAGS_max_cbs_robots)) continue;
        options.solver = FleetSolver::kCbs;
        if (s == "ecbs")
          options.suboptimality = absl::GetFlag(FLAGS_suboptimality);
      } else if (s == "lacam") {
        options.solver = FleetSolver::kLacam;
      } else if (s == "lacam*") {
        // Refines until the deadline: its time is the deadline unless the
        // search is exhausted sooner.
        options.solver = FleetSolver::kLacam;
        options.refine = true;
      } else if (s == "pibt") {
        options.solver = FleetSolver::kPibt;
      } else {
        std::fprintf(stderr, "unknown solver %s\n", s.c_str());
        continue;
      }
      Cellwise c;
      for (const FleetProblem& p : problems) {
        const absl::Time t0 = absl::Now();
        const StopCondition stop(
            t0 + absl::Seconds(absl::GetFlag(FLAGS_deadline_s)), nullptr, 0);
        absl::StatusOr<FleetPlan> plan = PlanFleet(p, options, stop);
        const double secs = absl::ToDoubleSeconds(absl::Now() - t0);
        ++c.runs;
        // A refining LaCAM* stops at the deadline with its best plan.
        if (!plan.ok() || !plan->complete) continue;
        std::vector<testing::FleetCheckRobot> robots;
        for (const FleetRobot& r : p.robots)
          robots.push_back({r.start, r.goal, &grid});
        const testing::FleetCheckResult check =
            testing::CheckFleetPlan(robots, true, false, plan->paths);
        if (!check.ok || check.sum_of_costs != plan->sum_of_costs) {
          std::fprintf(stderr, "%s %s %d robots: CHECK FAILED: %s\n",
                       name.c_str(), s.c_str(), n, check.error.c_str());
          continue;
        }
        ++c.solved;
        c.seconds += secs;
        c.expansions += static_cast<double>(plan->expansions);
        c.iterations += static_cast<double>(plan->iterations);
        c.ratio += static_cast<double>(plan->sum_of_costs) /
                   static_cast<double>(std::max<int64_t>(1, plan->lower_bound));
      }
      if (c.solved > 0) {
        std::printf("| %s | %d | %s | %d/%d | %.3f | %.3f | %.0f | %.0f |\n",
                    name.c_str(), n, s.c_str(), c.solved, c.runs,
                    c.seconds / c.solved, c.ratio / c.solved,
                    c.expansions / c.solved, c.iterations / c.solved);
      } else {
        std::printf("| %s | %d | %s | 0/%d | - | - | - | - |\n", name.c_str(),
                    n, s.c_str(), c.runs);
      }
      std::fflush(stdout);
    }
  }
}

}  // namespace
}  // namespace pathd

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage("Times the multi-robot path finding solvers.");
  absl::ParseCommandLine(argc, argv);
  std::mt19937 rng(absl::GetFlag(FLAGS_seed));
  std::printf(
      "deadline %.0f s per run; time = mean over solved runs; "
      "soc/lb = sum of costs / lower bound\n\n",
      absl::GetFlag(FLAGS_deadline_s));
  std::printf(
      "| map | robots | solver | solved | time s | soc/lb | expansions | "
      "iterations |\n");
  std::printf("|---|---:|---|---:|---:|---:|---:|---:|\n");
  const std::filesystem::path dir = absl::GetFlag(FLAGS_movingai_dir);
  for (const absl::string_view m :
       absl::StrSplit(absl::GetFlag(FLAGS_maps), ',', absl::SkipEmpty())) {
    const std::string name(m);
    if (name == "warehouse") {
      const pathd::Grid g = pathd::Warehouse();
      pathd::RunMap("warehouse (generated 170x84)", g, rng);
      continue;
    }
    absl::StatusOr<pathd::Grid> g =
        pathd::ReadMovingAiMapFile((dir / name).string());
    if (!g.ok()) {
      std::fprintf(stderr, "skipping %s: %s\n", name.c_str(),
                   g.status().ToString().c_str());
      continue;
    }
    pathd::RunMap(name, *g, rng);
  }
  return 0;
}
