// replan_bench: what incremental state buys over planning from scratch.
//
// For each map, robot runs between far-apart reachable cells: D* Lite plans
// once, the robot drives `--drive` cells along its path, then k cells near it
// change (the path cell `--ahead` moves ahead is blocked plus k - 1 cells
// around it, blocked or re-weighted), and D* Lite repairs. The repair
// (SetStart + UpdateMap + Plan) is timed against A* from scratch on the same
// new map from the same cell, in the same run; costs must agree. Then the
// shortest path map of the goal answers random starts against A* on the same
// queries. Prints a table of means and the ratios; figures, not assertions.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/str_split.h"
#include "core/grid.h"
#include "core/incremental.h"
#include "core/map_io.h"
#include "core/planner.h"
#include "core/search_scratch.h"
#include "tests/bench/movingai_maps.h"

ABSL_FLAG(std::string, movingai_dir, "../shared/benchmarks/movingai",
          "folder holding <set>/<map>.map files");
ABSL_FLAG(std::string, maps,
          "dao/brc202d.map,random/random512-25-0.map,street/Berlin_0_512.map,"
          "bg512/AR0011SR.map,maze/maze512-4-0.map",
          "comma-separated Moving AI maps relative to --movingai_dir (empty: all)");
ABSL_FLAG(int, random_size, 1024, "side of the random map (0: skip it)");
ABSL_FLAG(double, random_density, 0.2, "share of blocked cells on the random map");
ABSL_FLAG(int, runs, 20, "robot runs per map and k");
ABSL_FLAG(std::string, ks, "1,10,100", "changed cells per repair");
ABSL_FLAG(int, drive, 10, "cells the robot drives before the change");
ABSL_FLAG(int, ahead, 8, "how far ahead of the robot, along its path, the change is");
ABSL_FLAG(int, spm_queries, 200, "shortest-path-map queries per map");
ABSL_FLAG(uint32_t, seed, 1, "random seed");

namespace fs = std::filesystem;

namespace pathd {
namespace {

using Clock = std::chrono::steady_clock;

double Micros(Clock::duration d) {
  return std::chrono::duration<double, std::micro>(d).count();
}

Grid RandomGrid(int side, double density, std::mt19937& rng) {
  Grid grid = *Grid::Create(side, side);
  std::bernoulli_distribution blocked(density);
  for (int y = 0; y < side; ++y) {
    for (int x = 0; x < side; ++x) {
      if (blocked(rng)) grid.set_cost(x, y, kLethalCost);
    }
  }
  return grid;
}

Cell RandomFree(const Grid& grid, std::mt19937& rng) {
  for (;;) {
    const Cell c{static_cast<int32_t>(rng() % static_cast<uint32_t>(grid.width())),
                 static_cast<int32_t>(rng() % static_cast<uint32_t>(grid.height()))};
    if (grid.cost(c) == kFreeCost) return c;
  }
}

struct Sums {
  double repair_us = 0;
  double astar_us = 0;
  double repair_expansions = 0;
  double astar_expansions = 0;
  int runs = 0;
  int mismatches = 0;
};

// k cells around `center`: the centre itself blocked, then cells of a
// growing square around it, each blocked or given a random cost. Never the
// robot's cell or the goal.
std::vector<Cell> ChangeAround(Grid& grid, Cell center, int k, Cell robot, Cell goal,
                               std::mt19937& rng) {
  std::vector<Cell> changed;
  for (int r = 0; static_cast<int>(changed.size()) < k && r < grid.width(); ++r) {
    std::vector<Cell> ring;
    for (int dy = -r; dy <= r; ++dy) {
      for (int dx = -r; dx <= r; ++dx) {
        if (std::max(std::abs(dx), std::abs(dy)) != r) continue;
        const Cell c{center.x + dx, center.y + dy};
        if (!grid.InBounds(c) || c == robot || c == goal) continue;
        ring.push_back(c);
      }
    }
    std::shuffle(ring.begin(), ring.end(), rng);
    for (const Cell& c : ring) {
      if (static_cast<int>(changed.size()) == k) break;
      const uint8_t before = grid.cost(c);
      const uint8_t after = changed.empty() || rng() % 2 == 0
                                ? kLethalCost
                                : static_cast<uint8_t>(1 + rng() % 200);
      if (after == before) continue;
      grid.set_cost(c, after);
      changed.push_back(c);
    }
  }
  return changed;
}

void BenchMap(const std::string& name, const Grid& base, const std::vector<int>& ks,
              std::mt19937& rng) {
  const Planner& astar = *PlannerRegistry::Default().Get("astar");
  SearchScratch scratch;
  const int runs = absl::GetFlag(FLAGS_runs);
  const int drive = absl::GetFlag(FLAGS_drive);
  const int ahead = absl::GetFlag(FLAGS_ahead);
  const double cells = static_cast<double>(base.size());
  size_t dstar_bytes = 0;

  for (int k : ks) {
    Sums sums;
    int attempts = 0;
    while (sums.runs < runs && attempts++ < runs * 20) {
      auto grid = std::make_shared<const Grid>(base);
      const Cell start = RandomFree(*grid, rng);
      const Cell goal = RandomFree(*grid, rng);
      if (std::abs(start.x - goal.x) + std::abs(start.y - goal.y) < grid->width() / 2) {
        continue;
      }
      auto dstar = DStarLite::Create(grid, goal, CostParams{});
      if (!dstar.ok() || !(*dstar)->SetStart(start).ok()) continue;
      absl::StatusOr<PlanResult> first = (*dstar)->Plan(StopCondition::None());
      if (!first.ok() || !first->found() ||
          static_cast<int>(first->path.size()) <= drive + ahead + 1) {
        continue;
      }
      const Cell robot = first->path[static_cast<size_t>(drive)];
      const Cell center = first->path[static_cast<size_t>(drive + ahead)];
      Grid next = *grid;
      const std::vector<Cell> changed = ChangeAround(next, center, k, robot, goal, rng);
      auto next_grid = std::make_shared<const Grid>(std::move(next));

      const Clock::time_point t0 = Clock::now();
      absl::Status moved = (*dstar)->SetStart(robot);
      absl::Status updated = (*dstar)->UpdateMap(next_grid, changed);
      absl::StatusOr<PlanResult> repaired = (*dstar)->Plan(StopCondition::None());
      const Clock::time_point t1 = Clock::now();
      absl::StatusOr<PlanResult> fresh =
          astar.Plan(*next_grid, PlanRequest::Between(robot, goal), StopCondition::None(),
                     scratch);
      const Clock::time_point t2 = Clock::now();
      if (!moved.ok() || !updated.ok() || !repaired.ok() || !fresh.ok()) {
        std::fprintf(stderr, "%s: run failed\n", name.c_str());
        continue;
      }
      if (repaired->found() != fresh->found() ||
          (fresh->found() && std::abs(repaired->cost - fresh->cost) >
                                 1e-9 * (1.0 + fresh->cost))) {
        ++sums.mismatches;
      }
      sums.repair_us += Micros(t1 - t0);
      sums.astar_us += Micros(t2 - t1);
      sums.repair_expansions += static_cast<double>(repaired->expansions);
      sums.astar_expansions += static_cast<double>(fresh->expansions);
      dstar_bytes = std::max(dstar_bytes, (*dstar)->MemoryBytes());
      ++sums.runs;
    }
    if (sums.runs == 0) {
      std::printf("%-24s k=%-4d no runs (no long enough paths)\n", name.c_str(), k);
      continue;
    }
    const double n = sums.runs;
    std::printf("%-24s k=%-4d runs=%-3d dstar_repair_us=%9.1f astar_us=%9.1f "
                "astar/repair=%6.1fx  expansions %8.0f vs %8.0f%s\n",
                name.c_str(), k, sums.runs, sums.repair_us / n, sums.astar_us / n,
                sums.astar_us / sums.repair_us, sums.repair_expansions / n,
                sums.astar_expansions / n,
                sums.mismatches > 0 ? "  COST MISMATCH" : "");
  }

  // Shortest path map: one field per goal, many starts.
  auto grid = std::make_shared<const Grid>(base);
  const Cell goal = RandomFree(*grid, rng);
  const Clock::time_point b0 = Clock::now();
  auto spm = ShortestPathMap::Build(grid, goal, CostParams{}, StopCondition::None());
  const Clock::time_point b1 = Clock::now();
  if (!spm.ok()) {
    std::fprintf(stderr, "%s: %s\n", name.c_str(), std::string(spm.status().message()).c_str());
    return;
  }
  double spm_us = 0, astar_us = 0;
  int queries = 0, mismatches = 0;
  for (int q = 0; q < absl::GetFlag(FLAGS_spm_queries); ++q) {
    const Cell start = RandomFree(*grid, rng);
    const Clock::time_point t0 = Clock::now();
    absl::StatusOr<PlanResult> fast = (*spm)->PathFrom(start);
    const Clock::time_point t1 = Clock::now();
    absl::StatusOr<PlanResult> fresh = astar.Plan(
        *grid, PlanRequest::Between(start, goal), StopCondition::None(), scratch);
    const Clock::time_point t2 = Clock::now();
    if (!fast.ok() || !fresh.ok()) continue;
    if (fast->found() != fresh->found() ||
        (fresh->found() && std::abs(fast->cost - fresh->cost) > 1e-5 * (1.0 + fresh->cost))) {
      ++mismatches;
    }
    spm_us += Micros(t1 - t0);
    astar_us += Micros(t2 - t1);
    ++queries;
  }
  std::printf("%-24s spm build_ms=%7.1f query_us=%8.2f astar_us=%9.1f "
              "astar/spm=%7.1fx (%d queries)%s\n",
              name.c_str(), Micros(b1 - b0) / 1000.0, spm_us / queries,
              astar_us / queries, astar_us / spm_us, queries,
              mismatches > 0 ? "  COST MISMATCH" : "");
  std::printf("%-24s memory bytes/cell: dstar_lite %.2f, spm field %.2f\n", name.c_str(),
              static_cast<double>(dstar_bytes) / cells,
              static_cast<double>((*spm)->MemoryBytes()) / cells);
}

}  // namespace
}  // namespace pathd

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "replan_bench [--maps a.map,...] [--random_size 1024] [--runs 20] [--ks 1,10,100]\n"
      "D* Lite repair vs A* from scratch after k changed cells near the robot, and\n"
      "shortest-path-map queries vs A*, with memory per cell.");
  absl::ParseCommandLine(argc, argv);
  std::vector<int> ks;
  for (absl::string_view k : absl::StrSplit(absl::GetFlag(FLAGS_ks), ',', absl::SkipEmpty())) {
    ks.push_back(std::max(1, std::atoi(std::string(k).c_str())));
  }
  std::mt19937 rng(absl::GetFlag(FLAGS_seed));
  if (const int side = absl::GetFlag(FLAGS_random_size); side > 0) {
    const pathd::Grid grid = pathd::RandomGrid(side, absl::GetFlag(FLAGS_random_density), rng);
    pathd::BenchMap("random" + std::to_string(side), grid, ks, rng);
  }
  const fs::path root = absl::GetFlag(FLAGS_movingai_dir);
  if (!fs::exists(root)) {
    std::printf("Moving AI maps not found at %s: skipping them\n", root.string().c_str());
    return 0;
  }
  for (const std::string& name : pathd::bench::MovingAiMaps(root, absl::GetFlag(FLAGS_maps))) {
    absl::StatusOr<pathd::Grid> grid = pathd::ReadMovingAiMapFile((root / name).string());
    if (!grid.ok()) {
      std::fprintf(stderr, "%s\n", std::string(grid.status().message()).c_str());
      return 1;
    }
    pathd::BenchMap(name, *grid, ks, rng);
  }
  return 0;
}
