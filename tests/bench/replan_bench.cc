// replan_bench: what incremental replanning buys, measured in one run.
//  - D* Lite: after the robot has moved along its path, k cells just ahead of
//    it become blocked (k = 1, 10, 100); the repair (UpdateMap + Plan) against
//    A* from scratch on the same new map, per trial, as a ratio of medians.
//    Blockages that leave no way to the goal are counted and timed apart
//    ("cut"), then undone.
//  - Shortest path map: a query (PathFrom) on a cached field against A* on
//    the same query.
//  - Memory per cell of D* Lite's state and of a field.
//  - With --threshold: repairing a field after k changed cells (scattered or
//    in one square cluster) against rebuilding it, which is how the repair
//    or rebuild rule in core/incremental/incremental_search.cc was chosen, and what
//    ShortestPathMap::UpdateMap with that rule then takes.
// Maps: a 1024 x 1024 grid with random obstacles (fixed seed) and the shared
// Moving AI maps (start and goal of each map's longest scenario). Figures,
// not assertions.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/time/clock.h"
#include "core/search/registry.h"
#include "core/incremental/incremental_search.h"
#include "core/incremental/engine.h"
#include "core/map_io/map_io.h"
#include "core/search/planner.h"
#include "tests/bench/movingai_maps.h"

ABSL_FLAG(std::string, movingai_dir, "../shared/benchmarks/movingai",
          "folder holding <set>/<map>.map and <map>.map.scen files");
ABSL_FLAG(std::string, maps, "",
          "comma-separated map paths relative to --movingai_dir; empty = every map");
ABSL_FLAG(int, size, 1024, "side of the random map");
ABSL_FLAG(double, obstacles, 0.2, "obstacle fraction of the random map");
ABSL_FLAG(int, trials, 20, "replanning trials per map and k");
ABSL_FLAG(int, queries, 100, "shortest path map queries per map");
ABSL_FLAG(bool, threshold, false,
          "also measure field repair against rebuild for growing k");

namespace fs = std::filesystem;
using pathd::Cell;
using pathd::Grid;

namespace {

constexpr uint32_t kSeed = 20240605;

double Micros(absl::Duration d) { return absl::ToDoubleMicroseconds(d); }

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct Scene {
  std::string name;
  std::shared_ptr<const Grid> grid;
  Cell start;
  Cell goal;
};

bool Free(const Grid& grid, Cell c) {
  return grid.InBounds(c) && pathd::Traversable(grid.cost(c), false);
}

Scene RandomScene(int size, double obstacles) {
  std::mt19937 rng(kSeed);
  Grid grid = Grid::Create(size, size).value();
  std::bernoulli_distribution blocked(obstacles);
  for (uint8_t& v : grid.mutable_cells()) v = blocked(rng) ? pathd::kLethalCost : 0;
  const Cell start{size / 64, size / 64};
  const Cell goal{size - 1 - size / 64, size - 1 - size / 64};
  grid.set_cost(start, pathd::kFreeCost);
  grid.set_cost(goal, pathd::kFreeCost);
  return Scene{"random " + std::to_string(size) + "x" + std::to_string(size),
               std::make_shared<const Grid>(std::move(grid)), start, goal};
}

// The map with the start and goal of its longest scenario.
std::optional<Scene> MovingAiScene(const fs::path& root, const std::string& name) {
  auto grid = pathd::ReadMovingAiMapFile((root / name).string());
  auto file = pathd::ReadMovingAiScenarioFileWithVersion((root / name).string() + ".scen");
  if (!grid.ok() || !file.ok() || file->scenarios.empty()) return std::nullopt;
  const pathd::Scenario* longest = &file->scenarios.front();
  for (const pathd::Scenario& s : file->scenarios) {
    if (s.optimal_length > longest->optimal_length) longest = &s;
  }
  return Scene{name, std::make_shared<const Grid>(*std::move(grid)), longest->start,
               longest->goal};
}

// The k free cells nearest (ring by ring) to `center`, sparing `keep`s.
std::vector<Cell> Blob(const Grid& grid, Cell center, int k,
                       std::initializer_list<Cell> keep) {
  std::vector<Cell> cells;
  for (int r = 0; static_cast<int>(cells.size()) < k && r < grid.width(); ++r) {
    for (int dy = -r; dy <= r && static_cast<int>(cells.size()) < k; ++dy) {
      for (int dx = -r; dx <= r && static_cast<int>(cells.size()) < k; ++dx) {
        if (std::max(std::abs(dx), std::abs(dy)) != r) continue;
        const Cell c{center.x + dx, center.y + dy};
        if (!Free(grid, c)) continue;
        if (std::find(keep.begin(), keep.end(), c) != keep.end()) continue;
        cells.push_back(c);
      }
    }
  }
  return cells;
}

struct ReplanFigures {
  double dstar_us = 0;
  double astar_us = 0;
  double expansions = 0;
  int trials = 0;
  // Trials where the blocked cells cut the robot off from the goal (no
  // detour exists): D* Lite must then raise every cell of the cut-off part,
  // while A* only floods the robot's pocket. Timed separately (medians), then
  // the change is undone so the robot drives on.
  int cut_off = 0;
  double cut_dstar_us = 0;
  double cut_astar_us = 0;
};

// D* Lite follows its path; each trial moves the robot 5 cells on, blocks k
// cells around the path cell 6 ahead, and times the repair and A*. Changes
// that leave no path to the goal are timed apart and undone.
ReplanFigures ReplanTrials(const Scene& scene, int k, int trials) {
  const pathd::Planner& astar = *pathd::PlannerRegistry::Default().Get("astar");
  pathd::SearchScratch scratch;
  auto dstar = pathd::DStarLite::Create(scene.grid, scene.goal, {}).value();
  std::shared_ptr<const Grid> grid = scene.grid;
  Cell robot = scene.start;
  (void)dstar->SetStart(robot);
  auto plan = dstar->Plan(pathd::StopCondition::None());
  std::vector<double> dstar_us, astar_us, expansions, cut_dstar_us, cut_astar_us;
  int cut_off = 0;
  for (int t = 0; t < trials && plan.ok() && plan->found(); ++t) {
    if (plan->path.size() < 12) break;
    robot = plan->path[5];
    (void)dstar->SetStart(robot);
    plan = dstar->Plan(pathd::StopCondition::None());
    if (!plan.ok() || !plan->found()) break;
    Grid next = *grid;
    const std::vector<Cell> changed = Blob(next, plan->path[6], k, {robot, scene.goal});
    for (const Cell c : changed) next.set_cost(c, pathd::kLethalCost);
    const absl::Time c0 = absl::Now();
    auto check = astar.Plan(next, pathd::PlanRequest::Between(robot, scene.goal),
                            pathd::StopCondition::None(), scratch);
    const absl::Time c1 = absl::Now();
    if (!check.ok()) break;
    if (!check->found()) {
      ++cut_off;
      cut_astar_us.push_back(Micros(c1 - c0));
      auto cut_grid = std::make_shared<const Grid>(std::move(next));
      const absl::Time d0 = absl::Now();
      (void)dstar->UpdateMap(cut_grid, changed);
      auto cut_plan = dstar->Plan(pathd::StopCondition::None());
      const absl::Time d1 = absl::Now();
      if (!cut_plan.ok() || cut_plan->found()) {
        std::fprintf(stderr, "%s: D* Lite found a path A* did not\n", scene.name.c_str());
        break;
      }
      cut_dstar_us.push_back(Micros(d1 - d0));
      // Undo the change (untimed) and drive on.
      (void)dstar->UpdateMap(grid, changed);
      plan = dstar->Plan(pathd::StopCondition::None());
      continue;
    }
    grid = std::make_shared<const Grid>(std::move(next));

    const absl::Time t0 = absl::Now();
    (void)dstar->UpdateMap(grid, changed);
    plan = dstar->Plan(pathd::StopCondition::None());
    const absl::Time t1 = absl::Now();
    auto a = astar.Plan(*grid, pathd::PlanRequest::Between(robot, scene.goal),
                        pathd::StopCondition::None(), scratch);
    const absl::Time t2 = absl::Now();
    if (!plan.ok() || !a.ok() || !plan->found() ||
        std::abs(plan->cost - a->cost) > 1e-9 * (1 + a->cost)) {
      std::fprintf(stderr, "%s: D* Lite and A* disagree\n", scene.name.c_str());
      break;
    }
    dstar_us.push_back(Micros(t1 - t0));
    astar_us.push_back(Micros(t2 - t1));
    expansions.push_back(static_cast<double>(dstar->last_stats().expansions));
  }
  return {Median(dstar_us), Median(astar_us), Median(expansions),
          static_cast<int>(dstar_us.size()), cut_off, Median(cut_dstar_us),
          Median(cut_astar_us)};
}

struct QueryFigures {
  double spm_us = 0;
  double astar_us = 0;
  double build_ms = 0;
  double dstar_bytes_per_cell = 0;
  double spm_bytes_per_cell = 0;
};

QueryFigures QueryTrials(const Scene& scene, int queries) {
  const pathd::Planner& astar = *pathd::PlannerRegistry::Default().Get("astar");
  pathd::SearchScratch scratch;
  QueryFigures f;
  const double cells = static_cast<double>(scene.grid->size());
  auto dstar = pathd::DStarLite::Create(scene.grid, scene.goal, {}).value();
  (void)dstar->SetStart(scene.start);
  (void)dstar->Plan(pathd::StopCondition::None());
  f.dstar_bytes_per_cell = static_cast<double>(dstar->MemoryBytes()) / cells;

  const absl::Time b0 = absl::Now();
  auto spm = pathd::ShortestPathMap::Build(scene.grid, scene.goal, {},
                                           pathd::StopCondition::None())
                 .value();
  f.build_ms = Micros(absl::Now() - b0) / 1000.0;
  f.spm_bytes_per_cell = static_cast<double>(spm->MemoryBytes()) / cells;

  std::mt19937 rng(kSeed);
  std::vector<double> spm_us, astar_us;
  for (int q = 0; q < queries * 20 && static_cast<int>(spm_us.size()) < queries; ++q) {
    const Cell s{static_cast<int32_t>(rng() % scene.grid->width()),
                 static_cast<int32_t>(rng() % scene.grid->height())};
    if (!Free(*scene.grid, s) || std::isinf(spm->CostToGo(s))) continue;
    const absl::Time t0 = absl::Now();
    auto r = spm->PathFrom(s);
    const absl::Time t1 = absl::Now();
    auto a = astar.Plan(*scene.grid, pathd::PlanRequest::Between(s, scene.goal),
                        pathd::StopCondition::None(), scratch);
    const absl::Time t2 = absl::Now();
    if (!r.ok() || !a.ok() || !r->found() ||
        std::abs(r->cost - a->cost) > 1e-9 * (1 + a->cost)) {
      std::fprintf(stderr, "%s: SPM and A* disagree from (%d, %d)\n",
                   scene.name.c_str(), s.x, s.y);
      continue;
    }
    spm_us.push_back(Micros(t1 - t0));
    astar_us.push_back(Micros(t2 - t1));
  }
  f.spm_us = Median(spm_us);
  f.astar_us = Median(astar_us);
  return f;
}

// Repair against rebuild of the field of a goal in the middle of the map.
void ThresholdTrials(const Scene& scene) {
  using Field = pathd::internal::IncrementalSearch<pathd::internal::FieldConfig>;
  const Grid& grid = *scene.grid;
  Cell goal{grid.width() / 2, grid.height() / 2};
  while (!Free(grid, goal)) goal.x = (goal.x + 1) % grid.width();
  Field base(scene.grid, {}, pathd::internal::MoveRules(), goal);
  std::vector<double> build_us;
  for (int i = 0; i < 3; ++i) {
    const absl::Time t0 = absl::Now();
    base.Reset();
    base.Compute(pathd::StopCondition::None());
    base.store().Settle();
    build_us.push_back(Micros(absl::Now() - t0));
  }
  const double rebuild = Median(build_us);
  std::printf("\n%s: rebuild %.0f us (goal (%d, %d), %zu cells)\n", scene.name.c_str(),
              rebuild, goal.x, goal.y, grid.size());
  auto base_map =
      pathd::ShortestPathMap::Build(scene.grid, goal, {}, pathd::StopCondition::None())
          .value();
  std::printf("  %-9s %8s %9s %12s %12s %8s %14s %8s %8s\n", "pattern", "k", "fraction",
              "repair us", "expansions", "/rebuild", "UpdateMap us", "/rebuild",
              "rebuilt");
  std::mt19937 rng(kSeed);
  for (const bool clustered : {false, true}) {
    for (int k = 1; k <= static_cast<int>(grid.size()) / 4; k *= 4) {
      std::vector<double> repair_us, expansions, update_us;
      int rebuilt = 0;
      for (int t = 0; t < 5; ++t) {
        Grid next = grid;
        std::vector<Cell> changed;
        if (clustered) {
          const int side = std::max(1, static_cast<int>(std::sqrt(k)));
          const Cell corner{static_cast<int32_t>(rng() % (grid.width() - side + 1)),
                            static_cast<int32_t>(rng() % (grid.height() - side + 1))};
          for (int dy = 0; dy < side; ++dy) {
            for (int dx = 0; dx < side; ++dx) changed.push_back({corner.x + dx, corner.y + dy});
          }
        } else {
          for (int i = 0; i < k; ++i) {
            changed.push_back({static_cast<int32_t>(rng() % grid.width()),
                               static_cast<int32_t>(rng() % grid.height())});
          }
        }
        // Toggle: free cells become blocked, blocked ones free.
        for (const Cell c : changed) {
          if (c == goal) continue;
          next.set_cost(c, Free(next, c) ? pathd::kLethalCost : pathd::kFreeCost);
        }
        Field field = base;
        auto shared = std::make_shared<const Grid>(std::move(next));
        std::unique_ptr<pathd::ShortestPathMap> map = base_map->Clone();
        const absl::Time u0 = absl::Now();
        (void)map->UpdateMap(shared, changed);
        update_us.push_back(Micros(absl::Now() - u0));
        rebuilt += map->last_stats().rebuilt ? 1 : 0;
        const absl::Time t0 = absl::Now();
        field.SwitchGrid(shared, changed);
        const auto end = field.Compute(pathd::StopCondition::None());
        field.store().Settle();
        repair_us.push_back(Micros(absl::Now() - t0));
        expansions.push_back(static_cast<double>(end.expansions));
      }
      const double repair = Median(repair_us);
      std::printf("  %-9s %8d %9.5f %12.0f %12.0f %8.3f %14.0f %8.3f %6d/5\n",
                  clustered ? "cluster" : "scattered", k,
                  static_cast<double>(k) / static_cast<double>(grid.size()), repair,
                  Median(expansions), repair / rebuild, Median(update_us),
                  Median(update_us) / rebuild, rebuilt);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "replan_bench [--movingai_dir DIR] [--maps a.map,...] [--trials N] "
      "[--threshold]");
  absl::ParseCommandLine(argc, argv);
  std::vector<Scene> scenes{RandomScene(absl::GetFlag(FLAGS_size),
                                        absl::GetFlag(FLAGS_obstacles))};
  const fs::path root = absl::GetFlag(FLAGS_movingai_dir);
  const std::vector<std::string> maps =
      pathd::bench::MovingAiMaps(root, absl::GetFlag(FLAGS_maps));
  if (maps.empty()) {
    std::printf("Moving AI maps not found under %s: random map only\n", root.c_str());
  }
  for (const std::string& name : maps) {
    std::optional<Scene> scene = MovingAiScene(root, name);
    if (scene.has_value()) {
      scenes.push_back(*std::move(scene));
    } else {
      std::printf("skipping %s: unreadable map or scenarios\n", name.c_str());
    }
  }

  const int trials = absl::GetFlag(FLAGS_trials);
  std::printf("D* Lite repair after k cells blocked just ahead of the robot vs A* "
              "from scratch (medians of %d trials)\n",
              trials);
  std::printf("%-26s %5s %12s %10s %8s %11s %7s %8s %13s %10s\n", "map", "k",
              "D* Lite us", "A* us", "A*/D*", "expansions", "trials", "cut off",
              "cut: D* us", "cut: A* us");
  for (const Scene& scene : scenes) {
    for (const int k : {1, 10, 100}) {
      const ReplanFigures f = ReplanTrials(scene, k, trials);
      std::printf("%-26s %5d %12.1f %10.1f %8.1f %11.0f %7d %8d %13.1f %10.1f\n",
                  scene.name.c_str(), k, f.dstar_us, f.astar_us,
                  f.dstar_us > 0 ? f.astar_us / f.dstar_us : 0.0, f.expansions, f.trials,
                  f.cut_off, f.cut_dstar_us, f.cut_astar_us);
      std::fflush(stdout);
    }
  }

  std::printf("\nShortest path map query (PathFrom) vs A* on the same query "
              "(medians of %d queries); memory per cell\n",
              absl::GetFlag(FLAGS_queries));
  std::printf("%-26s %9s %10s %9s %10s %12s %12s\n", "map", "SPM us", "A* us", "A*/SPM",
              "build ms", "D* B/cell", "SPM B/cell");
  for (const Scene& scene : scenes) {
    const QueryFigures f = QueryTrials(scene, absl::GetFlag(FLAGS_queries));
    std::printf("%-26s %9.1f %10.1f %9.1f %10.1f %12.2f %12.2f\n", scene.name.c_str(),
                f.spm_us, f.astar_us, f.spm_us > 0 ? f.astar_us / f.spm_us : 0.0,
                f.build_ms, f.dstar_bytes_per_cell, f.spm_bytes_per_cell);
    std::fflush(stdout);
  }

  if (absl::GetFlag(FLAGS_threshold)) {
    std::printf("\nShortest path map: repair after k toggled cells vs rebuild "
                "(medians of 5)\n");
    for (const Scene& scene : scenes) ThresholdTrials(scene);
  }
  return 0;
}
