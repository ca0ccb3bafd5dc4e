// jps_plus (JPS+ over per-version jump tables) against jps and A* in one run:
// per Moving AI map, the mean and 95th percentile planning time over
// scenarios spread over the whole scenario file (A* the in-run baseline),
// the table's build time and memory per cell; then on 1024 x 1024 maps,
// the table advanced around N random changed cells against a full rebuild.
// Every planner plans through one derived store per map, as in the server,
// so jps reads its packed map and jps_plus its table built once per map.
//
//   jps_plus_bench --movingai_dir=../shared/benchmarks/movingai --sample=200
#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/strings/str_split.h"
#include "absl/time/clock.h"
#include "core/map/cost_model.h"
#include "core/map_io/map_io.h"
#include "core/planners/jps/jump_table.h"
#include "core/search/derived.h"
#include "core/search/registry.h"

ABSL_FLAG(std::string, movingai_dir, "../shared/benchmarks/movingai",
          "folder holding <set>/<map>.map and <map>.map.scen files");
ABSL_FLAG(std::string, movingai_maps,
          "dao/brc202d,dao/arena2,street/Berlin_0_512,maze/maze512-4-0,"
          "room/32room_000,random/random512-25-0,bg512/AR0011SR,sc1/Aftershock",
          "maps under --movingai_dir, comma-separated (one per type)");
ABSL_FLAG(std::string, planners, "astar,jps,jps_plus",
          "planners to time, comma-separated (the first is the baseline)");
ABSL_FLAG(int, sample, 200, "scenarios per map, spread over the scenario file");
ABSL_FLAG(int, repeats, 3, "times each scenario is planned (the best counts)");
ABSL_FLAG(int, changes, 100, "cells changed per update on the 1024 x 1024 maps");
ABSL_FLAG(int, updates, 20, "updates timed per 1024 x 1024 map");
ABSL_FLAG(bool, rebuild, true, "also time the full rebuild after each update (false: profile advances)");

namespace {

using pathd::internal::JumpTable;

// Values built once for the one grid of a run; what a map's version keeps
// in the server's DerivedCache.
class OnceStore : public pathd::DerivedStore {
 public:
  explicit OnceStore(const pathd::Grid& grid) : grid_(grid) {}
  std::shared_ptr<const void> Get(const std::string& key, const pathd::DerivedRecipe& recipe,
                                  pathd::DerivedStop& stop) override {
    auto it = values_.find(key);
    if (it == values_.end()) it = values_.emplace(key, recipe.build(grid_, stop)).first;
    return it->second;
  }

 private:
  const pathd::Grid& grid_;
  std::map<std::string, std::shared_ptr<const void>> values_;
};

double Seconds(absl::Duration d) { return absl::ToDoubleSeconds(d); }

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(p * static_cast<double>(v.size())))];
}

void RunMap(const std::string& label, const std::string& path) {
  auto grid = pathd::ReadMovingAiMapFile(path);
  auto file = pathd::ReadMovingAiScenarioFileWithVersion(path + ".scen");
  if (!grid.ok() || !file.ok()) {
    std::printf("%-24s skipped: cannot read the map or its scenarios\n", label.c_str());
    return;
  }
  const size_t n = std::min(file->scenarios.size(),
                            static_cast<size_t>(std::max(1, absl::GetFlag(FLAGS_sample))));
  std::vector<pathd::Scenario> scenarios;
  for (size_t i = 0; i < n; ++i) {
    scenarios.push_back(file->scenarios[i * file->scenarios.size() / n]);
  }
  // The table alone: build time (best of 3) and memory.
  absl::Duration build = absl::InfiniteDuration();
  size_t bytes = 0;
  for (int r = 0; r < 3; ++r) {
    const absl::Time t0 = absl::Now();
    auto table = JumpTable::Build(*grid, false);
    build = std::min(build, absl::Now() - t0);
    bytes = table->MemoryBytes();
  }
  std::printf("%-24s %dx%d  table build %.2f ms, %.1f bytes/cell\n", label.c_str(),
              grid->width(), grid->height(), 1e3 * Seconds(build),
              static_cast<double>(bytes) / static_cast<double>(grid->size()));
  double astar_mean = 0;
  const std::vector<std::string> names =
      absl::StrSplit(absl::GetFlag(FLAGS_planners), ',', absl::SkipEmpty());
  for (const std::string& name : names) {
    const pathd::Planner* planner = pathd::PlannerRegistry::Default().Get(name);
    if (planner == nullptr) {
      std::printf("  %-9s unknown planner\n", name.c_str());
      continue;
    }
    OnceStore store(*grid);
    pathd::SearchScratch scratch;
    std::vector<double> us;
    double cost_sum = 0;
    for (const pathd::Scenario& s : scenarios) {
      pathd::PlanRequest request = pathd::PlanRequest::Between(s.start, s.goal);
      request.derived = &store;
      double best = 1e300;
      for (int r = 0; r < std::max(1, absl::GetFlag(FLAGS_repeats)); ++r) {
        const absl::Time t0 = absl::Now();
        auto result = planner->Plan(*grid, request, pathd::StopCondition::None(), scratch);
        best = std::min(best, 1e6 * Seconds(absl::Now() - t0));
        if (r == 0 && result.ok() && result->found()) cost_sum += result->cost;
      }
      us.push_back(best);
    }
    double mean = 0;
    for (double v : us) mean += v;
    mean /= static_cast<double>(us.size());
    if (astar_mean == 0) astar_mean = mean;
    std::printf("  %-9s mean %9.1f us  p95 %9.1f us  %6.1fx A*  (cost sum %.1f)\n", name.c_str(),
                mean, Percentile(us, 0.95), astar_mean / mean, cost_sum);
  }
}

// Advance around `changes` random flipped cells against a full build, on
// `grid` (1024 x 1024).
void RunUpdates(const std::string& label, pathd::Grid grid) {
  if (absl::GetFlag(FLAGS_updates) <= 0) return;
  std::mt19937 rng(19);
  auto table = JumpTable::Build(grid, false);
  std::vector<double> advance_us;
  std::vector<double> build_us;
  size_t own_tiles = 0;
  size_t tiles = 0;
  for (int u = 0; u < absl::GetFlag(FLAGS_updates); ++u) {
    std::vector<pathd::Cell> changed;
    for (int i = 0; i < absl::GetFlag(FLAGS_changes); ++i) {
      const pathd::Cell c{static_cast<int32_t>(rng() % grid.width()),
                          static_cast<int32_t>(rng() % grid.height())};
      grid.set_cost(c, grid.cost(c) == pathd::kFreeCost ? pathd::kLethalCost : pathd::kFreeCost);
      changed.push_back(c);
    }
    absl::Time t0 = absl::Now();
    auto advanced = JumpTable::Advance(*table, grid, changed);
    advance_us.push_back(1e6 * Seconds(absl::Now() - t0));
    if (absl::GetFlag(FLAGS_rebuild)) {
      t0 = absl::Now();
      auto rebuilt = JumpTable::Build(grid, false);
      build_us.push_back(1e6 * Seconds(absl::Now() - t0));
    }
    own_tiles += advanced->OwnTiles();
    tiles = (static_cast<size_t>(grid.width() + 15) / 16) * ((grid.height() + 15) / 16);
    table = advanced;
  }
  const double a = Percentile(advance_us, 0.5);
  const double b = Percentile(build_us, 0.5);
  std::printf("%-30s %d cells changed: advance median %8.1f us (p95 %8.1f), "
              "rebuild median %8.1f us: %5.1fx cheaper; %.1f%% of tiles copied\n",
              label.c_str(), absl::GetFlag(FLAGS_changes), a, Percentile(advance_us, 0.95), b,
              b / a,
              100.0 * static_cast<double>(own_tiles) /
                  static_cast<double>(tiles * advance_us.size()));
}

}  // namespace

int main(int argc, char** argv) {
  absl::ParseCommandLine(argc, argv);
  const std::string dir = absl::GetFlag(FLAGS_movingai_dir);
  const std::vector<std::string> maps =
      absl::StrSplit(absl::GetFlag(FLAGS_movingai_maps), ',', absl::SkipEmpty());
  for (const std::string& map : maps) {
    RunMap(map, dir + "/" + map + ".map");
  }
  std::printf("\nJump table updates on 1024 x 1024 maps\n");
  std::mt19937 rng(7);
  for (int pct : {10, 25}) {
    pathd::Grid grid = pathd::Grid::Create(1024, 1024).value();
    for (uint8_t& v : grid.mutable_cells()) {
      v = static_cast<int>(rng() % 100) < pct ? pathd::kLethalCost : pathd::kFreeCost;
    }
    RunUpdates("random " + std::to_string(pct) + "% blocked", grid);
  }
  // A game map tiled 2 x 2 and cut to 1024 x 1024.
  auto base = pathd::ReadMovingAiMapFile(dir + "/dao/brc202d.map");
  if (base.ok()) {
    pathd::Grid grid = pathd::Grid::Create(1024, 1024).value();
    for (int32_t y = 0; y < 1024; ++y) {
      for (int32_t x = 0; x < 1024; ++x) {
        grid.set_cost(x, y, base->cost(x % base->width(), y % base->height()));
      }
    }
    RunUpdates("dao/brc202d tiled", grid);
  }
  return 0;
}
