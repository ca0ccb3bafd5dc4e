// The raster distance transform and the exact (Dijkstra) cost-to-go field
// against Dijkstra's algorithm run forward from every start, the descent
// against the field, and the two variants against each other on a Moving AI
// map.
#include "core/search/registry.h"
#include "core/search/path_measure.h"
#include "core/planners/cost_to_go.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/map_io/map_io.h"
#include "core/search/planner.h"
#include "gtest/gtest.h"

namespace pathd {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

bool Near(double a, double b) {
  if (a == b) return true;  // both +inf
  return std::abs(a - b) <= 1e-9 * std::max(1.0, std::abs(b));
}

const Planner& Get(const char* name) {
  const Planner* p = PlannerRegistry::Default().Get(name);
  EXPECT_NE(p, nullptr) << name;
  return *p;
}

Grid RandomGrid(std::mt19937& rng) {
  const int w = 1 + static_cast<int>(rng() % 12);
  const int h = 1 + static_cast<int>(rng() % 12);
  Grid grid = Grid::Create(w, h).value();
  const int blocked_pct = static_cast<int>(rng() % 40);
  for (uint8_t& v : grid.mutable_cells()) {
    const int roll = static_cast<int>(rng() % 100);
    if (roll < blocked_pct) {
      v = rng() % 4 == 0 ? kUnknownCost : (rng() % 2 == 0 ? kLethalCost : kInscribedCost);
    } else if (rng() % 2 == 0) {
      v = static_cast<uint8_t>(rng() % 253);
    }
  }
  return grid;
}

// Both fields equal the cost Dijkstra finds from every start to the goal
// (forward, so sharing none of the fields' reverse-edge bookkeeping); the
// descended path costs what the field says; both planners return the field
// on request.
TEST(DistanceTransform, FieldsEqualDijkstraFromEveryStart) {
  std::mt19937 rng(566755);
  const Planner& dijkstra = Get("dijkstra");
  const Planner& raster = Get("distance_transform");
  const Planner& exact = Get("distance_transform_exact");
  SearchScratch scratch;
  int grids = 0, reachable = 0;
  for (int trial = 0; trial < 400; ++trial) {
    Grid grid = RandomGrid(rng);
    CostParams cost;
    cost.connectivity = trial % 2 == 0 ? Connectivity::kEight : Connectivity::kFour;
    cost.unknown_is_free = (trial / 2) % 2 == 0;
    cost.cost_weight = trial % 5 == 0 ? 0.0 : 1.0 + (trial % 7);
    const Cell goal{static_cast<int32_t>(rng() % grid.width()),
                    static_cast<int32_t>(rng() % grid.height())};
    grid.set_cost(goal, static_cast<uint8_t>(rng() % 253));
    ++grids;

    const CostToGoField fields[] = {
        RasterDistanceTransform(grid, goal, cost, StopCondition::None()),
        DijkstraCostToGo(grid, goal, cost, StopCondition::None(), scratch)};
    for (const CostToGoField& f : fields) {
      ASSERT_EQ(f.outcome, PlanOutcome::kFound);
      ASSERT_EQ(f.values.size(), grid.size());
    }
    EXPECT_GT(fields[0].expansions, 0);
    EXPECT_LE(fields[0].expansions,
              static_cast<int64_t>(fields[0].passes) * static_cast<int64_t>(grid.size()));
    EXPECT_GE(fields[0].passes, 2);

    for (size_t i = 0; i < grid.size(); ++i) {
      const Cell start = grid.CellAt(i);
      double expected = kInf;
      if (Traversable(grid.cost(start), cost.unknown_is_free)) {
        auto d = dijkstra.Plan(grid, PlanRequest::Between(start, goal, cost),
                               StopCondition::None(), scratch);
        ASSERT_TRUE(d.ok()) << d.status();
        if (d->found()) expected = d->cost;
      }
      for (const CostToGoField& f : fields) {
        ASSERT_TRUE(Near(f.values[i], expected))
            << "trial " << trial << " cell " << CellToString(start) << ": field "
            << f.values[i] << ", dijkstra " << expected;
      }
      if (expected == kInf) continue;
      ++reachable;
      const std::vector<Cell> path = DescendCostToGo(grid, cost, fields[0].values, start);
      ASSERT_FALSE(path.empty());
      EXPECT_EQ(path.front(), start);
      EXPECT_EQ(path.back(), goal);
      const PathMeasure m = MeasurePath(grid, path, cost);
      ASSERT_TRUE(m.valid) << "trial " << trial;
      EXPECT_TRUE(Near(m.cost, fields[0].values[i]))
          << m.cost << " vs " << fields[0].values[i];
    }

    // The planners: same path cost, and the field when asked for.
    const Cell start = grid.CellAt(rng() % grid.size());
    if (!Traversable(grid.cost(start), cost.unknown_is_free)) continue;
    PlanRequest request = PlanRequest::Between(start, goal, cost);
    request.want_cost_to_go = true;
    for (const Planner* planner : {&raster, &exact}) {
      auto r = planner->Plan(grid, request, StopCondition::None(), scratch);
      ASSERT_TRUE(r.ok()) << r.status();
      const double at_start = fields[1].values[grid.Index(start)];
      ASSERT_EQ(r->found(), at_start < kInf) << planner->name();
      ASSERT_EQ(r->cost_to_go.size(), grid.size());
      for (size_t i = 0; i < grid.size(); ++i) {
        ASSERT_TRUE(Near(r->cost_to_go[i], fields[1].values[i]));
      }
      if (!r->found()) continue;
      const PathMeasure m = MeasurePath(grid, r->path, cost);
      ASSERT_TRUE(m.valid);
      EXPECT_DOUBLE_EQ(r->cost, m.cost);
      EXPECT_DOUBLE_EQ(r->length, m.length);
      EXPECT_TRUE(Near(r->cost, at_start)) << planner->name();
    }
  }
  EXPECT_EQ(grids, 400);
  EXPECT_GT(reachable, 5000);
}

// Larger grids with dense obstacles and weighted cells need many passes, so
// skipped rows and rows revisited much later both occur; the raster field
// still equals the exact one.
TEST(DistanceTransform, ManyPassGridsMatchTheExactField) {
  std::mt19937 rng(700);
  SearchScratch scratch;
  int most_passes = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const int w = 20 + static_cast<int>(rng() % 60);
    const int h = 20 + static_cast<int>(rng() % 60);
    Grid grid = Grid::Create(w, h).value();
    for (uint8_t& v : grid.mutable_cells()) {
      const int roll = static_cast<int>(rng() % 100);
      v = roll < 38   ? kLethalCost
          : roll < 70 ? kFreeCost
                      : static_cast<uint8_t>(rng() % 253);
    }
    CostParams cost;
    cost.connectivity = trial % 2 == 0 ? Connectivity::kEight : Connectivity::kFour;
    cost.cost_weight = 3.0;
    const Cell goal{static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h)};
    grid.set_cost(goal, kFreeCost);
    const CostToGoField raster =
        RasterDistanceTransform(grid, goal, cost, StopCondition::None());
    const CostToGoField exact =
        DijkstraCostToGo(grid, goal, cost, StopCondition::None(), scratch);
    ASSERT_EQ(raster.outcome, PlanOutcome::kFound);
    for (size_t i = 0; i < grid.size(); ++i) {
      ASSERT_TRUE(Near(raster.values[i], exact.values[i]))
          << "trial " << trial << " cell " << CellToString(grid.CellAt(i));
    }
    most_passes = std::max(most_passes, raster.passes);
  }
  EXPECT_GT(most_passes, 10);
}

TEST(DistanceTransform, ReportsItsRasterPasses) {
  // Open ground, goal in the top-left corner: every path runs W, N or NW,
  // exactly what the forward pass reads, so the first pass is final and the
  // backward pass confirms it.
  Grid open = Grid::Create(20, 10).value();
  const CostToGoField easy =
      RasterDistanceTransform(open, Cell{0, 0}, CostParams{}, StopCondition::None());
  EXPECT_EQ(easy.passes, 2);
  EXPECT_EQ(easy.expansions, 2 * 200);
  // Goal in the bottom-right corner: the forward pass finds nothing to do
  // (the goal is its last cell), the backward pass does it all, a third
  // confirms.
  EXPECT_EQ(
      RasterDistanceTransform(open, Cell{19, 9}, CostParams{}, StopCondition::None())
          .passes,
      3);

  // A serpentine corridor turns against the raster direction at every bend:
  // each bend costs passes, so the count grows with the number of walls.
  Grid snake = Grid::Create(9, 9).value();
  for (int wall = 1; wall < 9; wall += 2) {
    for (int x = 0; x < 9; ++x) snake.set_cost(x, wall, kLethalCost);
    snake.set_cost(wall % 4 == 1 ? 8 : 0, wall, kFreeCost);
  }
  const CostToGoField hard =
      RasterDistanceTransform(snake, Cell{0, 0}, CostParams{}, StopCondition::None());
  EXPECT_EQ(hard.outcome, PlanOutcome::kFound);
  EXPECT_GT(hard.passes, easy.passes);
  SearchScratch scratch;
  const CostToGoField exact =
      DijkstraCostToGo(snake, Cell{0, 0}, CostParams{}, StopCondition::None(), scratch);
  for (size_t i = 0; i < snake.size(); ++i) {
    EXPECT_TRUE(Near(hard.values[i], exact.values[i])) << i;
  }
  // The planner's expansions are the cells of the rows swept; rows whose
  // inputs did not change are skipped, so fewer than passes x cells here.
  auto r = Get("distance_transform")
               .Plan(snake, PlanRequest::Between(Cell{0, 8}, Cell{0, 0}),
                     StopCondition::None(), scratch);
  ASSERT_TRUE(r.ok() && r->found());
  EXPECT_EQ(r->expansions, hard.expansions);
  EXPECT_LT(r->expansions, static_cast<int64_t>(hard.passes) * 81);
}

TEST(DistanceTransform, StopConditionEndsBothSweeps) {
  Grid grid = Grid::Create(64, 64).value();
  SearchScratch scratch;
  const StopCondition budget(absl::InfiniteFuture(), nullptr, 1000);
  const CostToGoField raster =
      RasterDistanceTransform(grid, Cell{0, 0}, CostParams{}, budget);
  EXPECT_EQ(raster.outcome, PlanOutcome::kExpansionLimit);
  EXPECT_LE(raster.expansions, 1000);
  EXPECT_TRUE(raster.values.empty());
  const CostToGoField exact =
      DijkstraCostToGo(grid, Cell{0, 0}, CostParams{}, budget, scratch);
  EXPECT_EQ(exact.outcome, PlanOutcome::kExpansionLimit);
  EXPECT_EQ(exact.expansions, 1000);

  const StopCondition expired(absl::Now() - absl::Seconds(1), nullptr, 0);
  EXPECT_EQ(RasterDistanceTransform(grid, Cell{0, 0}, CostParams{}, expired).outcome,
            PlanOutcome::kTimeout);
  EXPECT_EQ(DijkstraCostToGo(grid, Cell{0, 0}, CostParams{}, expired, scratch).outcome,
            PlanOutcome::kTimeout);
}

TEST(DistanceTransform, DescentRefusesAFieldThatDoesNotFall) {
  Grid grid = Grid::Create(3, 1).value();
  EXPECT_TRUE(DescendCostToGo(grid, CostParams{}, {kInf, kInf, 0.0}, Cell{0, 0}).empty());
  // Not a field of this grid: the middle cell is no lower than the start.
  EXPECT_TRUE(DescendCostToGo(grid, CostParams{}, {2.0, 2.0, 0.0}, Cell{0, 0}).empty());
  EXPECT_EQ(DescendCostToGo(grid, CostParams{}, {2.0, 1.0, 0.0}, Cell{0, 0}).size(), 3u);
}

// The Moving AI benchmarks live beside the repository; skipped without them.
TEST(DistanceTransform, VariantsAgreeOnMovingAiArena2) {
  const std::string path = "../shared/benchmarks/movingai/dao/arena2.map";
  if (!std::filesystem::exists(path)) {
    GTEST_SKIP() << path << " not found (run from the repository root with the "
                 << "benchmarks in ../shared)";
  }
  absl::StatusOr<Grid> grid = ReadMovingAiMapFile(path);
  ASSERT_TRUE(grid.ok()) << grid.status();
  absl::StatusOr<ScenarioFile> file = ReadMovingAiScenarioFileWithVersion(path + ".scen");
  ASSERT_TRUE(file.ok()) << file.status();
  const std::vector<Scenario>* scenarios = &file->scenarios;
  ASSERT_GT(scenarios->size(), 500u);
  SearchScratch scratch;
  for (size_t k = 0; k < scenarios->size(); k += scenarios->size() / 5) {
    const Scenario& s = (*scenarios)[k];
    for (Connectivity connectivity : {Connectivity::kEight, Connectivity::kFour}) {
      CostParams cost;
      cost.connectivity = connectivity;
      const CostToGoField raster =
          RasterDistanceTransform(*grid, s.goal, cost, StopCondition::None());
      const CostToGoField exact =
          DijkstraCostToGo(*grid, s.goal, cost, StopCondition::None(), scratch);
      ASSERT_EQ(raster.outcome, PlanOutcome::kFound);
      ASSERT_EQ(exact.outcome, PlanOutcome::kFound);
      for (size_t i = 0; i < grid->size(); ++i) {
        ASSERT_TRUE(Near(raster.values[i], exact.values[i]))
            << "goal " << CellToString(s.goal) << " cell "
            << CellToString(grid->CellAt(i));
      }
      if (connectivity == Connectivity::kEight) {
        // The benchmark's optimal length is the octile cost on this 0/254 map.
        EXPECT_NEAR(raster.values[grid->Index(s.start)], s.optimal_length,
                    ScenarioTolerance(s, file->version))
            << "scenario line " << s.line;
      }
      std::printf("arena2 goal %s (%s-connected): %d raster passes\n",
                  CellToString(s.goal).c_str(),
                  connectivity == Connectivity::kEight ? "8" : "4", raster.passes);
    }
  }
}

}  // namespace
}  // namespace pathd
