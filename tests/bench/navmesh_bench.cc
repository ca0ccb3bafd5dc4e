// navmesh_bench: the navigation mesh and Polyanya, in figures.
//  - Per Moving AI map: mesh build time, triangles and the convex polygons
//    merged from them, bytes; then a spread of its scenarios (every k-th,
//    across all buckets) planned by `navmesh` (mesh cached, as the
//    server's derived store keeps it), `astar` and `theta_star`, with the
//    mean time per query of each, and the checks that every navmesh
//    polyline is clear and never longer than Theta*'s path.
//  - Advance: on a random 1024 x 1024 map, re-meshing after 1, 10 and 100
//    changed cells against a rebuild (medians over trials).
// Figures, not assertions.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/time/clock.h"
#include "core/geometry/navmesh.h"
#include "core/map_io/map_io.h"
#include "core/search/derived.h"
#include "core/search/path_measure.h"
#include "core/search/planner.h"
#include "core/search/registry.h"
#include "tests/bench/movingai_maps.h"

ABSL_FLAG(std::string, movingai_dir, "../shared/benchmarks/movingai",
          "folder holding <set>/<map>.map and <map>.map.scen files");
ABSL_FLAG(std::string, maps, "",
          "comma-separated map paths relative to --movingai_dir; empty = every map");
ABSL_FLAG(int, queries, 60, "scenarios per map, spread over the file");
ABSL_FLAG(int, advance_trials, 9, "trials per changed-cell count");
ABSL_FLAG(int, tile_size, pathd::NavMesh::kDefaultTileSize,
          "mesh tile side in cells (1..128): smaller tiles advance cheaper, "
          "larger ones search faster");

namespace pathd {
namespace {

// The server's derived cache reduced to one map version: built on first
// use; the mesh with --tile_size.
class OneVersionStore final : public DerivedStore {
 public:
  explicit OneVersionStore(const Grid& grid) : grid_(grid) {}
  std::shared_ptr<const void> Get(const std::string& key, const DerivedRecipe& recipe,
                                  DerivedStop& stop) override {
    auto& slot = values_[key];
    if (slot == nullptr) {
      slot = key.rfind("navmesh", 0) == 0
                 ? NavMesh::Build(grid_, false, absl::GetFlag(FLAGS_tile_size))
                 : recipe.build(grid_, stop);
    }
    return slot;
  }

 private:
  const Grid& grid_;
  std::map<std::string, std::shared_ptr<const void>> values_;
};

double Micros(absl::Duration d) { return absl::ToDoubleMicroseconds(d); }

void BenchMap(const std::filesystem::path& root, const std::string& name) {
  const auto grid = ReadMovingAiMapFile((root / name).string());
  const auto scen = ReadMovingAiScenarioFile((root / name).string() + ".scen");
  if (!grid.ok() || !scen.ok() || scen->empty()) {
    std::printf("%-28s skipped\n", name.c_str());
    return;
  }
  const auto mesh = NavMesh::Build(*grid, false, absl::GetFlag(FLAGS_tile_size));
  const size_t n = std::min<size_t>(scen->size(), absl::GetFlag(FLAGS_queries));
  const size_t stride = scen->size() / n;
  const Planner* navmesh = PlannerRegistry::Default().Get("navmesh");
  const Planner* astar = PlannerRegistry::Default().Get("astar");
  const Planner* theta = PlannerRegistry::Default().Get("theta_star");
  OneVersionStore store(*grid);
  SearchScratch scratch;
  absl::Duration t_mesh, t_astar, t_theta;
  int bad = 0;
  int longer = 0;
  int64_t expansions = 0;
  for (size_t i = 0; i < n; ++i) {
    const Scenario& s = (*scen)[i * stride];
    PlanRequest request = PlanRequest::Between(s.start, s.goal);
    request.derived = &store;
    if (i == 0) (void)navmesh->Plan(*grid, request, StopCondition::None(), scratch);
    absl::Time t0 = absl::Now();
    const auto m = navmesh->Plan(*grid, request, StopCondition::None(), scratch);
    t_mesh += absl::Now() - t0;
    t0 = absl::Now();
    const auto a = astar->Plan(*grid, request, StopCondition::None(), scratch);
    t_astar += absl::Now() - t0;
    t0 = absl::Now();
    const auto t = theta->Plan(*grid, request, StopCondition::None(), scratch);
    t_theta += absl::Now() - t0;
    if (!m.ok() || !m->found() || !t.ok() || !a.ok()) {
      ++bad;
      continue;
    }
    expansions += m->expansions;
    if (!MeasureResultPath(*grid, *m, request.cost).valid) ++bad;
    if (t->found() && m->length > t->length + 1e-9) ++longer;
  }
  const double k = static_cast<double>(n);
  std::printf(
      "%-28s %5dx%-5d build %8.1f ms %7lld tris %7lld polys %7.2f MB | %3zu queries: navmesh %8.1f us "
      "(%6.0f exp)  astar %9.1f us  theta* %9.1f us  x%5.1f vs theta*  x%5.1f vs astar | "
      "bad %d longer-than-theta* %d\n",
      name.c_str(), grid->width(), grid->height(),
      absl::ToDoubleMilliseconds(mesh->build_time()),
      static_cast<long long>(mesh->triangle_count()),
      static_cast<long long>(mesh->polygon_count()), mesh->bytes() / 1048576.0, n,
      Micros(t_mesh) / k, static_cast<double>(expansions) / k, Micros(t_astar) / k,
      Micros(t_theta) / k, Micros(t_theta) / Micros(t_mesh),
      Micros(t_astar) / Micros(t_mesh), bad, longer);
}

// Toggles `changed` cells, scattered over the map or in one square, and
// re-meshes; prints the median over trials against `build_ms`.
void MeasureAdvance(Grid& grid, std::shared_ptr<const NavMesh>& mesh, std::mt19937& rng,
                    int changed, bool clustered, double build_ms) {
  const int32_t side_cells = grid.width();
  const int side = static_cast<int>(std::ceil(std::sqrt(changed)));
  std::vector<double> times;
  std::vector<int> tiles;
  for (int trial = 0; trial < absl::GetFlag(FLAGS_advance_trials); ++trial) {
    std::vector<Cell> cells;
    const int32_t x0 = static_cast<int32_t>(rng() % (side_cells - side));
    const int32_t y0 = static_cast<int32_t>(rng() % (side_cells - side));
    for (int i = 0; i < changed; ++i) {
      const Cell c = clustered ? Cell{x0 + i % side, y0 + i / side}
                               : Cell{static_cast<int32_t>(rng() % side_cells),
                                      static_cast<int32_t>(rng() % side_cells)};
      grid.set_cost(c, grid.cost(c) == kLethalCost ? kFreeCost : kLethalCost);
      cells.push_back(c);
    }
    const absl::Time t0 = absl::Now();
    mesh = NavMesh::Advance(*mesh, grid, cells);
    times.push_back(absl::ToDoubleMilliseconds(absl::Now() - t0));
    tiles.push_back(mesh->rebuilt_tiles());
  }
  std::sort(times.begin(), times.end());
  std::sort(tiles.begin(), tiles.end());
  const double median = times[times.size() / 2];
  std::printf("  advance %3d %s cells: median %8.2f ms (%3d tiles), rebuild/advance x%.1f\n",
              changed, clustered ? "clustered" : "scattered", median,
              tiles[tiles.size() / 2], build_ms / median);
}

void BenchAdvance() {
  constexpr int kSide = 1024;
  std::mt19937 rng(42);
  Grid grid = Grid::Create(kSide, kSide).value();
  // Obstacles as scattered blocks of 1..8 cells a side, ~25% of the map.
  while (grid.CountBlocked() < static_cast<int64_t>(grid.size()) / 4) {
    const int x0 = static_cast<int>(rng() % kSide);
    const int y0 = static_cast<int>(rng() % kSide);
    const int w = 1 + static_cast<int>(rng() % 8);
    const int h = 1 + static_cast<int>(rng() % 8);
    for (int y = y0; y < std::min(kSide, y0 + h); ++y) {
      for (int x = x0; x < std::min(kSide, x0 + w); ++x) grid.set_cost(x, y, kLethalCost);
    }
  }
  const absl::Time t0 = absl::Now();
  std::shared_ptr<const NavMesh> mesh =
      NavMesh::Build(grid, false, absl::GetFlag(FLAGS_tile_size));
  const double build_ms = absl::ToDoubleMilliseconds(absl::Now() - t0);
  std::printf("random %dx%d: build %.1f ms, %lld triangles, %lld polygons, %.1f MB, %zu tiles\n",
              kSide, kSide, build_ms, static_cast<long long>(mesh->triangle_count()),
              static_cast<long long>(mesh->polygon_count()), mesh->bytes() / 1048576.0,
              mesh->tiles().size());
  // Scattered cells are the worst case (each may touch its own tile); a
  // square is what a robot's sensor reports.
  for (const bool clustered : {false, true}) {
    for (const int changed : {1, 10, 100}) {
      MeasureAdvance(grid, mesh, rng, changed, clustered, build_ms);
    }
  }
}

}  // namespace
}  // namespace pathd

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage("navigation mesh and Polyanya figures");
  absl::ParseCommandLine(argc, argv);
  const std::filesystem::path root = absl::GetFlag(FLAGS_movingai_dir);
  for (const std::string& map : pathd::bench::MovingAiMaps(root, absl::GetFlag(FLAGS_maps))) {
    pathd::BenchMap(root, map);
  }
  pathd::BenchAdvance();
  return 0;
}
