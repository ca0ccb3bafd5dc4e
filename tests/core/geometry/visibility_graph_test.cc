// The tangent visibility graph, the obstacle numbering of Minimal Construct
// and the Euclidean shortest path map, against brute force on small random
// maps: every pair of bend corners tested with FreeSpace::SegmentClear, and
// every free cell's distance by Dijkstra over the complete graph of bend
// corners, the cell and the goal.
#include "core/geometry/visibility_graph.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "core/geometry/euclidean_spm.h"
#include "core/geometry/free_space.h"
#include "core/geometry/structure.h"
#include "core/search/derived.h"
#include "core/search/registry.h"
#include "core/search/search_scratch.h"
#include "core/search/stop_condition.h"
#include "absl/strings/match.h"
#include "absl/time/clock.h"
#include "gtest/gtest.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// A random map: scattered cells, or rectangles (walls, corner-touching
// blocks, narrow gaps), a fifth of them unknown cells.
Grid RandomMap(std::mt19937& rng) {
  const int w = 2 + static_cast<int>(rng() % 11);
  const int h = 2 + static_cast<int>(rng() % 11);
  Grid grid = Grid::Create(w, h).value();
  auto value = [&] { return rng() % 5 == 0 ? kUnknownCost : kLethalCost; };
  if (rng() % 2 == 0) {
    const int pct = static_cast<int>(rng() % 45);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        if (static_cast<int>(rng() % 100) < pct) grid.set_cost(x, y, value());
      }
    }
  } else {
    const int rects = 1 + static_cast<int>(rng() % 5);
    for (int r = 0; r < rects; ++r) {
      const int x0 = static_cast<int>(rng() % w);
      const int y0 = static_cast<int>(rng() % h);
      const int x1 = std::min(w - 1, x0 + static_cast<int>(rng() % 4));
      const int y1 = std::min(h - 1, y0 + static_cast<int>(rng() % 4));
      const uint8_t v = value();
      for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) grid.set_cost(x, y, v);
      }
    }
  }
  return grid;
}

// The map as text, for failure messages.
std::string Dump(const Grid& grid) {
  std::string out;
  for (int32_t y = 0; y < grid.height(); ++y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      const uint8_t v = grid.cost(x, y);
      out += v == kLethalCost ? '#' : v == kUnknownCost ? '?' : '.';
    }
    out += '\n';
  }
  return out;
}

// Shortest distances from `source` to every point of `points` over the
// complete graph whose edges are the clear segments. O(n^2).
std::vector<double> CompleteGraphDistances(const FreeSpace& space,
                                           const std::vector<LatticePoint>& points,
                                           size_t source) {
  const size_t n = points.size();
  std::vector<double> dist(n, kInf);
  std::vector<char> done(n, 0);
  dist[source] = 0.0;
  for (size_t round = 0; round < n; ++round) {
    size_t u = n;
    for (size_t i = 0; i < n; ++i) {
      if (!done[i] && dist[i] < kInf && (u == n || dist[i] < dist[u])) u = i;
    }
    if (u == n) break;
    done[u] = 1;
    for (size_t v = 0; v < n; ++v) {
      if (done[v]) continue;
      const double d = dist[u] + Distance(points[u], points[v]);
      if (d < dist[v] && space.SegmentClear(points[u], points[v])) dist[v] = d;
    }
  }
  return dist;
}

TEST(TangentTest, OnlyLinesOutsideTheBlockedQuadrant) {
  const LatticePoint p = CornerAt(1, 1);
  const CornerQuadrant lower_left{-1, -1};
  EXPECT_TRUE(Tangent(p, lower_left, CornerAt(3, 0)));   // towards +x, -y
  EXPECT_TRUE(Tangent(p, lower_left, CornerAt(1, 4)));   // straight along x = 1
  EXPECT_TRUE(Tangent(p, lower_left, CornerAt(0, 3)));
  EXPECT_FALSE(Tangent(p, lower_left, CornerAt(0, 0)));  // into the cell
  EXPECT_FALSE(Tangent(p, lower_left, CornerAt(3, 2)));  // its line does
  EXPECT_TRUE(Tangent(p, CornerQuadrant{}, CornerAt(3, 2)));
}

TEST(VisibilityGraphTest, OneBlockSquare) {
  const Grid grid = MakeGrid({".....", ".....", "..#..", ".....", "....."});
  const auto graph = GetVisibilityGraph(nullptr, grid, false);
  ASSERT_EQ(graph->vertex_count(), 4u);
  // The four sides of the block; its diagonals cross it.
  EXPECT_EQ(graph->edge_count(), 4);
  const GeometricStructure s = DescribeVisibilityGraph(grid, false);
  EXPECT_EQ(s.kind, "visibility");
  EXPECT_EQ(s.segments.size(), 4u);
  EXPECT_EQ(s.points.size(), 4u);
}

// Every graph edge is clear and tangent at both ends; every clear tangent
// pair is an edge.
TEST(VisibilityGraphTest, EdgesAreExactlyTheClearTangentPairs) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 1500; ++trial) {
    const Grid grid = RandomMap(rng);
    const bool unknown_is_free = trial % 3 == 0;
    const auto graph = GetVisibilityGraph(nullptr, grid, unknown_is_free);
    const FreeSpace space(grid, unknown_is_free);
    ASSERT_EQ(graph->vertex_count(), space.BendCorners().size());
    std::set<std::pair<uint32_t, uint32_t>> edges;
    for (uint32_t v = 0; v < graph->vertex_count(); ++v) {
      for (const auto& e : graph->EdgesOf(v)) {
        edges.insert({v, e.to});
        EXPECT_DOUBLE_EQ(e.length, Distance(graph->vertex(v), graph->vertex(e.to)));
      }
    }
    for (uint32_t a = 0; a < graph->vertex_count(); ++a) {
      for (uint32_t b = 0; b < graph->vertex_count(); ++b) {
        if (a == b) continue;
        const LatticePoint pa = graph->vertex(a);
        const LatticePoint pb = graph->vertex(b);
        const bool want = space.SegmentClear(pa, pb) &&
                          Tangent(pa, QuadrantAt(space, pa), pb) &&
                          Tangent(pb, QuadrantAt(space, pb), pa);
        ASSERT_EQ(edges.count({a, b}) == 1, want) << "trial " << trial;
      }
    }
  }
}

// The edges of a graph as (vertex, vertex, length) triples, comparable.
std::set<std::tuple<int64_t, int64_t, int64_t, int64_t, double>> EdgeSet(
    const VisibilityGraph& graph) {
  std::set<std::tuple<int64_t, int64_t, int64_t, int64_t, double>> edges;
  for (uint32_t v = 0; v < graph.vertex_count(); ++v) {
    for (const auto& e : graph.EdgesOf(v)) {
      const LatticePoint a = graph.vertex(v);
      const LatticePoint b = graph.vertex(e.to);
      edges.insert({a.x2, a.y2, b.x2, b.y2, e.length});
    }
  }
  return edges;
}

TEST(VisibilityGraphTest, AdvanceEqualsRebuild) {
  std::mt19937 rng(17);
  for (int trial = 0; trial < 1500; ++trial) {
    Grid grid = RandomMap(rng);
    auto space = std::make_shared<const FreeSpace>(grid, false);
    auto graph = VisibilityGraph::Build(space);
    for (int step = 0; step < 3; ++step) {
      // A few cells flipped, clustered or anywhere.
      std::vector<Cell> changed;
      const int count = static_cast<int>(rng() % 4);
      const Cell near{static_cast<int32_t>(rng() % grid.width()),
                      static_cast<int32_t>(rng() % grid.height())};
      for (int k = 0; k < count; ++k) {
        Cell c{static_cast<int32_t>(rng() % grid.width()),
               static_cast<int32_t>(rng() % grid.height())};
        if (trial % 2 == 0) {
          c = {std::min(grid.width() - 1, near.x + static_cast<int32_t>(rng() % 2)),
               std::min(grid.height() - 1, near.y + static_cast<int32_t>(rng() % 2))};
        }
        grid.set_cost(c, grid.cost(c) == kFreeCost ? kLethalCost : kFreeCost);
        changed.push_back(c);
      }
      auto next_space = std::make_shared<FreeSpace>(*space);
      next_space->Update(grid, changed);
      auto advanced = VisibilityGraph::Advance(*graph, next_space, changed);
      ASSERT_NE(advanced, nullptr);
      const auto rebuilt = VisibilityGraph::Build(std::make_shared<const FreeSpace>(grid, false));
      ASSERT_EQ(advanced->vertex_count(), rebuilt->vertex_count()) << "trial " << trial;
      ASSERT_EQ(EdgeSet(*advanced), EdgeSet(*rebuilt)) << "trial " << trial << "\n" << Dump(grid);
      space = next_space;
      graph = advanced;
    }
  }
}

TEST(ObstacleCornersTest, BlockersAndCornersByObstacle) {
  // Two separate blocks and a wall on the border, which the outside does
  // not join to anything.
  const Grid grid = MakeGrid({"......", ".#....", "......", "....#.", "##...."});
  const auto obstacles = GetObstacleCorners(nullptr, grid, false);
  ASSERT_EQ(obstacles->obstacle_count(), 3);
  EXPECT_EQ(obstacles->CornersOf(0).size(), 4u);
  EXPECT_EQ(obstacles->CornersOf(1).size(), 4u);
  // The wall's corners on the border are enclosed by the outside.
  EXPECT_EQ(obstacles->CornersOf(2).size(), 1u);
  EXPECT_EQ(obstacles->Blocker(CentreOf({0, 0}), CentreOf({2, 2})), 0);
  EXPECT_EQ(obstacles->Blocker(CentreOf({3, 3}), CentreOf({5, 3})), 1);
  EXPECT_EQ(obstacles->Blocker(CentreOf({0, 2}), CentreOf({5, 2})), std::nullopt);
  // Along the border line under the wall: the outside and the wall close it.
  EXPECT_EQ(obstacles->Blocker(CornerAt(0, 5), CornerAt(3, 5)), 2);
}

TEST(ObstacleCornersTest, PinchesAndWallsBlockThroughOneObstacle) {
  // Two cells touching at a corner are one obstacle; a segment through the
  // pinch is blocked by it.
  const Grid grid = MakeGrid({"....", ".#..", "..#.", "...."});
  const auto obstacles = GetObstacleCorners(nullptr, grid, false);
  ASSERT_EQ(obstacles->obstacle_count(), 1);
  EXPECT_EQ(obstacles->Blocker(CentreOf({2, 1}), CentreOf({1, 2})), 0);
  EXPECT_EQ(obstacles->Blocker(CornerAt(1, 1), CornerAt(3, 3)), 0);
  // Corners of both cells except the pinch.
  EXPECT_EQ(obstacles->CornersOf(0).size(), 6u);
}

TEST(ObstacleCornersTest, RandomBlockersAgreeWithSegmentClear) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 500; ++trial) {
    const Grid grid = RandomMap(rng);
    const auto obstacles = GetObstacleCorners(nullptr, grid, false);
    const FreeSpace& space = obstacles->space();
    for (int k = 0; k < 40; ++k) {
      const LatticePoint a{static_cast<int64_t>(rng() % (2 * grid.width() + 1)),
                           static_cast<int64_t>(rng() % (2 * grid.height() + 1))};
      const LatticePoint b{static_cast<int64_t>(rng() % (2 * grid.width() + 1)),
                           static_cast<int64_t>(rng() % (2 * grid.height() + 1))};
      if (!space.PointFree(a) || !space.PointFree(b)) continue;
      const std::optional<int32_t> blocker = obstacles->Blocker(a, b);
      ASSERT_EQ(blocker.has_value(), !space.SegmentClear(a, b));
      if (blocker.has_value()) {
        ASSERT_GE(*blocker, 0);
        ASSERT_LT(*blocker, obstacles->obstacle_count());
      }
    }
  }
}

// Regression: cells whose root region holds no neighbouring cell centre
// got the wrong root (or none) from propagation alone.
TEST(EuclideanSpmTest, CellsInSliversGetTheirRoot) {
  // (7, 0) lies in the shadow of the wall's corner (7, 2); its neighbours
  // see the goal past that corner.
  const Grid wedge = MakeGrid({"......#....", "......#....", "...........",
                               "...........", "........###", "........###",
                               "...........", "...........", "...........",
                               ".........##"});
  auto spm = GetEuclideanSpm(nullptr, wedge, {0, 8}, false);
  EXPECT_NEAR(spm->DistanceFrom({7, 0}), 10.773526985509307, 1e-12);
  EXPECT_EQ(spm->RootPoint(spm->RootOf({7, 0})), CornerAt(7, 2));
  // (3, 0) is the one centre of corner (4, 4)'s region that the regions of
  // its neighbours' roots cut off.
  const Grid sliver = MakeGrid({"......#..", "##..##...", "#.#.#..#.", "..#.#..##",
                                "##.......", "....#....", ".##......", "...##.#..",
                                "...##....", "..#.#..#.", "..#..#..."});
  spm = GetEuclideanSpm(nullptr, sliver, {5, 9}, false);
  EXPECT_NEAR(spm->DistanceFrom({3, 0}), 9.4774400373745422, 1e-12);
  EXPECT_EQ(spm->RootPoint(spm->RootOf({3, 0})), CornerAt(4, 4));
}

// The shortest path map's distance from every free cell equals Dijkstra's
// over the complete graph of bend corners, that cell and the goal, and the
// roots chain to the goal through clear segments.
TEST(EuclideanSpmTest, EveryCellMatchesTheCompleteGraph) {
  std::mt19937 rng(3);
  int checked = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const Grid grid = RandomMap(rng);
    const bool unknown_is_free = trial % 4 == 0;
    const FreeSpace space(grid, unknown_is_free);
    std::vector<Cell> free;
    for (int32_t y = 0; y < grid.height(); ++y) {
      for (int32_t x = 0; x < grid.width(); ++x) {
        if (!space.Blocked(x, y)) free.push_back({x, y});
      }
    }
    if (free.empty()) continue;
    const Cell goal = free[rng() % free.size()];
    const auto spm = GetEuclideanSpm(nullptr, grid, goal, unknown_is_free);
    // Distances to the goal: Dijkstra from it over corners + every centre.
    std::vector<LatticePoint> points = space.BendCorners();
    const size_t corners = points.size();
    for (Cell c : free) points.push_back(CentreOf(c));
    points.push_back(CentreOf(goal));
    const std::vector<double> want =
        CompleteGraphDistances(space, points, points.size() - 1);
    for (size_t i = 0; i < free.size(); ++i) {
      const double d = want[corners + i];
      const double got = spm->DistanceFrom(free[i]);
      if (std::isinf(d)) {
        ASSERT_TRUE(std::isinf(got)) << "trial " << trial << " cell "
                                     << CellToString(free[i]) << "\n" << Dump(grid);
        continue;
      }
      ASSERT_NEAR(got, d, 1e-9 * (1 + d))
          << "trial " << trial << " cell " << CellToString(free[i]) << " goal "
          << CellToString(goal) << "\n" << Dump(grid);
      ++checked;
    }
  }
  EXPECT_GT(checked, 10000);
}

// Maps of several vertex tiles (RootTiles groups vertices by 16 x 16 cells),
// every cell against the complete graph.
TEST(EuclideanSpmTest, LargerMapsMatchTheCompleteGraph) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 4; ++trial) {
    const int w = 30 + static_cast<int>(rng() % 15);
    const int h = 30 + static_cast<int>(rng() % 15);
    Grid grid = Grid::Create(w, h).value();
    for (int r = 0; r < 30; ++r) {
      const int x0 = static_cast<int>(rng() % w);
      const int y0 = static_cast<int>(rng() % h);
      const int x1 = std::min(w - 1, x0 + static_cast<int>(rng() % 6));
      const int y1 = std::min(h - 1, y0 + static_cast<int>(rng() % 6));
      for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) grid.set_cost(x, y, kLethalCost);
      }
    }
    const FreeSpace space(grid, false);
    std::vector<Cell> free;
    for (int32_t y = 0; y < h; ++y) {
      for (int32_t x = 0; x < w; ++x) {
        if (!space.Blocked(x, y)) free.push_back({x, y});
      }
    }
    const Cell goal = free[rng() % free.size()];
    const auto spm = GetEuclideanSpm(nullptr, grid, goal, false);
    std::vector<LatticePoint> points = space.BendCorners();
    const size_t corners = points.size();
    for (Cell c : free) points.push_back(CentreOf(c));
    const std::vector<double> want = CompleteGraphDistances(
        space, points, corners + static_cast<size_t>(
                                     std::find(free.begin(), free.end(), goal) -
                                     free.begin()));
    for (size_t i = 0; i < free.size(); ++i) {
      const double d = want[corners + i];
      const double got = spm->DistanceFrom(free[i]);
      if (std::isinf(d)) {
        ASSERT_TRUE(std::isinf(got)) << "trial " << trial;
        continue;
      }
      ASSERT_NEAR(got, d, 1e-9 * (1 + d))
          << "trial " << trial << " cell " << CellToString(free[i]) << "\n" << Dump(grid);
    }
  }
}

// width x height with a quarter of the cells blocked at random, row 0 and
// the last column open (so a path joins their ends): at 512 x 512 about
// 49,000 bend corners, like Moving AI's random512-25, whose visibility graph
// takes minutes.
Grid QuarterBlocked(int width, int height, uint32_t seed) {
  std::mt19937 rng(seed);
  Grid grid = Grid::Create(width, height).value();
  for (int y = 1; y < height; ++y) {
    for (int x = 0; x + 1 < width; ++x) {
      if (rng() % 4 == 0) grid.set_cost(x, y, kLethalCost);
    }
  }
  return grid;
}

StopCondition Expired() {
  return StopCondition(absl::Now() - absl::Seconds(1), nullptr, 0);
}

TEST(DerivedStopTest, AVisibilityGraphBuildPastItsDeadlineReturnsNothing) {
  const Grid grid = QuarterBlocked(512, 512, 7);
  const StopCondition expired = Expired();
  DerivedStop stop(expired);
  EXPECT_EQ(GetVisibilityGraph(nullptr, grid, false, stop), nullptr);
  EXPECT_EQ(stop.Outcome(), PlanOutcome::kTimeout);
  EXPECT_TRUE(absl::StartsWith(stop.stopped_while(),
                               "building the visibility graph of this map version ("))
      << stop.stopped_while();
  EXPECT_TRUE(absl::EndsWith(stop.stopped_while(), " vertices)")) << stop.stopped_while();

  std::atomic<bool> cancelled{true};
  const StopCondition cancel(absl::InfiniteFuture(), &cancelled, 0);
  DerivedStop cancelled_stop(cancel);
  EXPECT_EQ(VisibilityGraph::Build(SharedFreeSpace(nullptr, grid, false), cancelled_stop),
            nullptr);
  EXPECT_EQ(cancelled_stop.Outcome(), PlanOutcome::kCancelled);
}

// Minutes of pairs if the build ignored its stop; it polls once per vertex.
TEST(DerivedStopTest, AVisibilityGraphBuildStopsAtADeadlineThatPassesDuringIt) {
  const Grid grid = QuarterBlocked(512, 512, 11);
  const StopCondition soon(absl::Now() + absl::Milliseconds(100), nullptr, 0);
  DerivedStop stop(soon);
  EXPECT_EQ(GetVisibilityGraph(nullptr, grid, false, stop), nullptr);
  EXPECT_EQ(stop.Outcome(), PlanOutcome::kTimeout);
}

TEST(DerivedStopTest, AVisibilityGraphAdvancePastItsDeadlineReturnsNothing) {
  Grid grid = QuarterBlocked(48, 48, 3);
  const auto graph = VisibilityGraph::Build(SharedFreeSpace(nullptr, grid, false));
  grid.set_cost(20, 20, grid.cost(20, 20) == kLethalCost ? 0 : kLethalCost);
  const StopCondition expired = Expired();
  DerivedStop stop(expired);
  EXPECT_EQ(VisibilityGraph::Advance(*graph, SharedFreeSpace(nullptr, grid, false),
                                     std::vector<Cell>{{20, 20}}, stop),
            nullptr);
  EXPECT_TRUE(absl::StartsWith(stop.stopped_while(),
                               "advancing the visibility graph to this map version ("))
      << stop.stopped_while();
  // Not stopped, the same advance answers.
  DerivedStop never;
  EXPECT_NE(VisibilityGraph::Advance(*graph, SharedFreeSpace(nullptr, grid, false),
                                     std::vector<Cell>{{20, 20}}, never),
            nullptr);
}

TEST(DerivedStopTest, AEuclideanSpmBuildPastItsDeadlineReturnsNothing) {
  // On the large map the graph under the map gives up first, and says so.
  const Grid large = QuarterBlocked(512, 512, 7);
  const StopCondition expired = Expired();
  DerivedStop stop(expired);
  EXPECT_EQ(GetEuclideanSpm(nullptr, large, Cell{0, 0}, false, stop), nullptr);
  EXPECT_TRUE(absl::StartsWith(stop.stopped_while(), "building the visibility graph"))
      << stop.stopped_while();
  // Over a graph already built, the map's own build gives up.
  const Grid small = QuarterBlocked(48, 48, 3);
  const auto graph = GetVisibilityGraph(nullptr, small, false);
  std::atomic<bool> cancelled{true};
  const StopCondition cancel(absl::InfiniteFuture(), &cancelled, 0);
  DerivedStop cancelled_stop(cancel);
  EXPECT_EQ(EuclideanSpm::Build(graph, Cell{0, 0}, cancelled_stop), nullptr);
  EXPECT_EQ(cancelled_stop.Outcome(), PlanOutcome::kCancelled);
  EXPECT_TRUE(absl::StartsWith(cancelled_stop.stopped_while(),
                               "building the Euclidean shortest path map of goal (0, 0)"))
      << cancelled_stop.stopped_while();
}

// The planners end the query with the stop's outcome and name the structure.
TEST(DerivedStopTest, PlannersAnswerTheStopNamingTheStructure) {
  const Grid grid = QuarterBlocked(512, 512, 7);
  const PlanRequest request = PlanRequest::Between({0, 0}, {511, 511});
  SearchScratch scratch;
  const StopCondition soon(absl::Now() + absl::Milliseconds(100), nullptr, 0);
  const absl::StatusOr<PlanResult> vg =
      PlannerRegistry::Default().Get("visibility_graph")->Plan(grid, request, soon, scratch);
  ASSERT_TRUE(vg.ok()) << vg.status();
  EXPECT_EQ(vg->outcome, PlanOutcome::kTimeout);
  EXPECT_TRUE(absl::StartsWith(vg->stopped_while, "building the visibility graph"))
      << vg->stopped_while;
  std::atomic<bool> cancelled{true};
  const StopCondition cancel(absl::InfiniteFuture(), &cancelled, 0);
  const absl::StatusOr<PlanResult> spm =
      PlannerRegistry::Default().Get("euclidean_spm")->Plan(grid, request, cancel, scratch);
  ASSERT_TRUE(spm.ok()) << spm.status();
  EXPECT_EQ(spm->outcome, PlanOutcome::kCancelled);
  EXPECT_FALSE(spm->stopped_while.empty());
}

}  // namespace
}  // namespace pathd
