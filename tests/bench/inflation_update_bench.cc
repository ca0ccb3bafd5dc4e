// inflation_update_bench: a shaped grid (robot radius, Nav2 inflation costs,
// optionally clearance costs) brought to a new map version by
// AdvanceShapedGrid after 1, 10, 100, ... scattered changed cells, against
// ShapeGrid of the whole new map. Prints median milliseconds of each, their
// ratio, and the cells of the windows the advance read; each advanced grid
// is checked against the full one. Figures, not assertions.
#include <algorithm>
#include <cstdio>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_split.h"
#include "absl/time/clock.h"
#include "core/map/grid.h"
#include "core/map/inflation.h"

ABSL_FLAG(int, size, 2048, "map side, cells");
ABSL_FLAG(double, resolution, 0.05, "metres per cell");
ABSL_FLAG(double, robot_radius, 0.2, "robot radius, metres");
ABSL_FLAG(double, inflation_radius, 0.55, "inflation radius, metres");
ABSL_FLAG(double, cost_scaling_factor, 10.0, "Nav2's cost_scaling_factor, per metre");
ABSL_FLAG(double, min_clearance, 0.0, "minimum clearance, metres (0: none)");
ABSL_FLAG(double, obstacles, 0.1, "share of cells in random obstacle rectangles");
ABSL_FLAG(std::string, changes, "1,10,100,1000", "comma-separated changed cell counts");
ABSL_FLAG(int, runs, 21, "updates timed per count");
ABSL_FLAG(int, seed, 1, "random seed");

namespace {

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Rectangles of 1..24 cells a side until `share` of the map is lethal.
pathd::Grid RandomObstacleMap(int side, double share, std::mt19937& rng) {
  pathd::Grid grid = pathd::Grid::Create(side, side).value();
  std::uniform_int_distribution<int> at(0, side - 1), extent(1, 24);
  const auto want = static_cast<int64_t>(share * static_cast<double>(grid.size()));
  int64_t lethal = 0;
  while (lethal < want) {
    const int x0 = at(rng), y0 = at(rng);
    const int x1 = std::min(side - 1, x0 + extent(rng) - 1);
    const int y1 = std::min(side - 1, y0 + extent(rng) - 1);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        if (grid.cost(x, y) != pathd::kLethalCost) ++lethal;
        grid.set_cost(x, y, pathd::kLethalCost);
      }
    }
  }
  return grid;
}

}  // namespace

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "inflation_update_bench [--size N] [--changes 1,10,100] [--runs N] ...\n"
      "Prints median ms of AdvanceShapedGrid after N scattered changes against "
      "ShapeGrid of the whole map.");
  absl::ParseCommandLine(argc, argv);
  std::vector<int> counts;
  for (absl::string_view c :
       absl::StrSplit(absl::GetFlag(FLAGS_changes), ',', absl::SkipEmpty())) {
    int value = 0;
    if (!absl::SimpleAtoi(c, &value) || value < 1) {
      std::fprintf(stderr, "bad change count '%s'\n", std::string(c).c_str());
      return 2;
    }
    counts.push_back(value);
  }
  const int side = absl::GetFlag(FLAGS_size);
  const int runs = std::max(1, absl::GetFlag(FLAGS_runs));
  const double res = absl::GetFlag(FLAGS_resolution);
  std::mt19937 rng(static_cast<uint32_t>(absl::GetFlag(FLAGS_seed)));
  pathd::Grid stored = RandomObstacleMap(side, absl::GetFlag(FLAGS_obstacles), rng);
  stored.set_resolution(res);
  const pathd::GridShape shape =
      pathd::GridShape::Of(absl::GetFlag(FLAGS_robot_radius) / res,
                           absl::GetFlag(FLAGS_inflation_radius) / res,
                           absl::GetFlag(FLAGS_cost_scaling_factor) * res,
                           absl::GetFlag(FLAGS_min_clearance) / res, false);
  absl::StatusOr<pathd::Grid> first = pathd::ShapeGrid(stored, shape);
  if (!first.ok()) {
    std::fprintf(stderr, "%s\n", std::string(first.status().message()).c_str());
    return 1;
  }
  pathd::Grid shaped = *std::move(first);
  std::printf(
      "map %dx%d at %g m, %.1f%% lethal; robot radius %g cells, inflation radius %g "
      "cells, %g per cell, clearance %g cells; reach %g cells; %d runs per count\n",
      side, side, res,
      100.0 * static_cast<double>(stored.CountBlocked()) /
          static_cast<double>(stored.size()),
      shape.robot_radius_cells, shape.inflation_radius_cells, shape.cost_scaling_per_cell,
      shape.min_clearance_cells, pathd::ShapeReach(shape), runs);
  // The floor of any advance that hands out a new grid: one copy.
  std::vector<double> copy_ms;
  for (int i = 0; i < runs; ++i) {
    const absl::Time t0 = absl::Now();
    pathd::Grid copy = shaped;
    // Keeps the compiler from eliding the copy.
    asm volatile("" : : "g"(copy.mutable_cells().data()) : "memory");
    copy_ms.push_back(absl::ToDoubleMilliseconds(absl::Now() - t0));
  }
  std::printf("copy of the grid: median %.3f ms\n\n", Median(copy_ms));
  std::printf("%8s %12s %12s %8s %14s %9s\n", "changes", "advance_ms", "full_ms", "ratio",
              "window_cells", "advanced");

  std::uniform_int_distribution<int> at(0, side - 1);
  for (const int count : counts) {
    std::vector<double> advance_ms, full_ms;
    int64_t window_cells = 0;
    int advanced = 0;
    for (int run = 0; run < runs; ++run) {
      // Scattered cells toggled between free and lethal, listed row-major
      // as the map store records them.
      std::vector<pathd::Cell> changed;
      for (int i = 0; i < count; ++i) changed.push_back({at(rng), at(rng)});
      std::sort(changed.begin(), changed.end(), [](pathd::Cell a, pathd::Cell b) {
        return a.y != b.y ? a.y < b.y : a.x < b.x;
      });
      changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
      for (const pathd::Cell c : changed) {
        stored.set_cost(c, stored.cost(c) == pathd::kLethalCost ? pathd::kFreeCost
                                                                : pathd::kLethalCost);
      }
      absl::Time t0 = absl::Now();
      absl::StatusOr<pathd::ShapedGridAdvance> next =
          pathd::AdvanceShapedGrid(shaped, stored, changed, shape);
      advance_ms.push_back(absl::ToDoubleMilliseconds(absl::Now() - t0));
      t0 = absl::Now();
      absl::StatusOr<pathd::Grid> full = pathd::ShapeGrid(stored, shape);
      full_ms.push_back(absl::ToDoubleMilliseconds(absl::Now() - t0));
      if (!next.ok() || !full.ok() || next->grid.cells() != full->cells()) {
        std::fprintf(stderr, "the advanced grid differs from the full one\n");
        return 1;
      }
      window_cells += next->window_cells;
      advanced += next->advanced;
      shaped = std::move(next->grid);
    }
    const double a = Median(advance_ms);
    const double f = Median(full_ms);
    std::printf("%8d %12.3f %12.3f %8.1f %14lld %6d/%d\n", count, a, f, f / a,
                static_cast<long long>(window_cells / runs), advanced, runs);
  }
  return 0;
}
