// Polyanya on the navigation mesh against an independent brute force: the
// visibility graph of bend corners, start and goal, with FreeSpace's exact
// segment test as the edge test, searched by Dijkstra. Thousands of small
// random maps with small tiles, so that paths cross many tile borders.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "absl/time/clock.h"
#include "core/geometry/free_space.h"
#include "core/geometry/funnel.h"
#include "core/geometry/navmesh.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/map_io/map_io.h"
#include "core/planners/geometric/polyanya.h"
#include "core/search/path_measure.h"
#include "core/search/registry.h"
#include "gtest/gtest.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Shortest free-space distance from the centre of `s` to the centre of `g`
// (+inf when unreachable): Dijkstra on the complete graph over bend corners
// and the two centres, an edge wherever SegmentClear holds. Shares nothing
// with the mesh or Polyanya.
double BruteForce(const FreeSpace& space, Cell s, Cell g) {
  std::vector<LatticePoint> nodes{CentreOf(s), CentreOf(g)};
  for (const LatticePoint& p : space.BendCorners()) nodes.push_back(p);
  std::vector<double> dist(nodes.size(), kInf);
  std::vector<bool> done(nodes.size(), false);
  dist[0] = 0.0;
  for (;;) {
    size_t u = nodes.size();
    for (size_t i = 0; i < nodes.size(); ++i) {
      if (!done[i] && dist[i] < kInf && (u == nodes.size() || dist[i] < dist[u])) u = i;
    }
    if (u == nodes.size()) return kInf;
    if (u == 1) return dist[1];
    done[u] = true;
    for (size_t v = 0; v < nodes.size(); ++v) {
      if (done[v]) continue;
      const double d = dist[u] + Distance(nodes[u], nodes[v]);
      if (d < dist[v] && space.SegmentClear(nodes[u], nodes[v])) dist[v] = d;
    }
  }
}

// Random maps with what makes free space hard: scattered cells (corner
// contacts and pinches), rectangles, diagonal staircases (pinch chains and
// paths grazing many corners on one line), one-cell gaps in walls, unknown
// cells.
Grid RandomMap(std::mt19937& rng) {
  const int w = 2 + static_cast<int>(rng() % 15);
  const int h = 2 + static_cast<int>(rng() % 15);
  Grid grid = Grid::Create(w, h).value();
  const int style = static_cast<int>(rng() % 4);
  const int density = static_cast<int>(rng() % 45);
  auto set = [&](int x, int y, uint8_t v) {
    if (grid.InBounds(x, y)) grid.set_cost(x, y, v);
  };
  auto obstacle = [&] { return rng() % 6 == 0 ? kUnknownCost : kLethalCost; };
  if (style == 0 || style == 3) {
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        if (static_cast<int>(rng() % 100) < density) set(x, y, obstacle());
      }
    }
  }
  if (style == 1 || style == 3) {
    const int n = static_cast<int>(rng() % 6);
    for (int i = 0; i < n; ++i) {
      const int x0 = static_cast<int>(rng() % w);
      const int y0 = static_cast<int>(rng() % h);
      const int rw = 1 + static_cast<int>(rng() % 4);
      const int rh = 1 + static_cast<int>(rng() % 4);
      for (int y = y0; y < y0 + rh; ++y) {
        for (int x = x0; x < x0 + rw; ++x) set(x, y, kLethalCost);
      }
    }
  }
  if (style == 2) {
    // Staircases and walls with one-cell gaps.
    const int n = 1 + static_cast<int>(rng() % 3);
    for (int i = 0; i < n; ++i) {
      const int x0 = static_cast<int>(rng() % w);
      const int y0 = static_cast<int>(rng() % h);
      const int step = rng() % 2 ? 1 : -1;
      const int len = 2 + static_cast<int>(rng() % 8);
      for (int k = 0; k < len; ++k) set(x0 + k, y0 + step * k, kLethalCost);
    }
    if (rng() % 2) {
      const int wx = static_cast<int>(rng() % w);
      const int gap = static_cast<int>(rng() % h);
      for (int y = 0; y < h; ++y) {
        if (y != gap) set(wx, y, kLethalCost);
      }
    }
  }
  return grid;
}

std::vector<Cell> FreeCells(const Grid& grid, bool unknown_is_free) {
  std::vector<Cell> cells;
  for (int32_t y = 0; y < grid.height(); ++y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      if (Traversable(grid.cost(x, y), unknown_is_free)) cells.push_back({x, y});
    }
  }
  return cells;
}

// Searches `mesh` and checks the answer against the brute force: found
// exactly when reachable, the same length to 1e-9 relative, a clear
// polyline from centre to centre whose length is the one reported.
void ExpectMatchesBruteForce(const NavMesh& mesh, const Grid& grid,
                             const FreeSpace& space, Cell s, Cell g,
                             SearchScratch& scratch, const std::string& what) {
  const PolyanyaPath path = PolyanyaSearch(mesh, grid, s, g, StopCondition::None(), scratch);
  const double expected = BruteForce(space, s, g);
  ASSERT_EQ(path.outcome == PlanOutcome::kFound, expected < kInf)
      << what << " expected " << expected << " outcome "
      << PlanOutcomeName(path.outcome);
  if (expected == kInf) {
    EXPECT_EQ(path.outcome, PlanOutcome::kNoPath) << what;
    return;
  }
  ASSERT_FALSE(path.polyline.empty()) << what;
  EXPECT_EQ(path.polyline.front(), CentreOf(s)) << what;
  EXPECT_EQ(path.polyline.back(), CentreOf(g)) << what;
  EXPECT_TRUE(space.PolylineClear(path.polyline)) << what;
  for (size_t i = 1; i + 1 < path.polyline.size(); ++i) {
    const LatticePoint p = path.polyline[i];
    EXPECT_TRUE(p.x2 % 2 == 0 && p.y2 % 2 == 0 && space.IsBendCorner(p.x2 / 2, p.y2 / 2))
        << what << " bends off a bend corner at " << p.x2 / 2.0 << "," << p.y2 / 2.0;
    // A grazed corner on a straight run is no vertex of the polyline.
    EXPECT_NE(Orient(path.polyline[i - 1], p, path.polyline[i + 1]), 0)
        << what << " collinear vertex at " << p.x2 / 2.0 << "," << p.y2 / 2.0;
  }
  EXPECT_NEAR(PolylineLength(path.polyline), expected, 1e-9 * (1 + expected)) << what;
}

std::string Describe(const Grid& grid, bool unknown_is_free, int tile, Cell s, Cell g) {
  std::string out = "tile " + std::to_string(tile) + " unknown_is_free " +
                    std::to_string(unknown_is_free) + " start " + CellToString(s) +
                    " goal " + CellToString(g) + "\n";
  for (int32_t y = 0; y < grid.height(); ++y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      const uint8_t c = grid.cost(x, y);
      out += c == kLethalCost ? '#' : c == kUnknownCost ? '?' : '.';
    }
    out += '\n';
  }
  return out;
}

TEST(Polyanya, MatchesTheVisibilityGraphOnRandomMaps) {
  std::mt19937 rng(20261201);
  SearchScratch scratch;
  int found = 0;
  int unreachable = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const Grid grid = RandomMap(rng);
    const bool unknown_is_free = trial % 5 == 0;
    const std::vector<Cell> free = FreeCells(grid, unknown_is_free);
    if (free.empty()) continue;
    static constexpr int kTiles[] = {1, 2, 3, 4, 7, 64};
    const int tile = kTiles[trial % 6];
    const auto mesh = NavMesh::Build(grid, unknown_is_free, tile);
    const FreeSpace space(grid, unknown_is_free);
    for (int q = 0; q < 4; ++q) {
      const Cell s = free[rng() % free.size()];
      const Cell g = free[rng() % free.size()];
      ExpectMatchesBruteForce(*mesh, grid, space, s, g, scratch,
                              "trial " + std::to_string(trial) + " " +
                                  Describe(grid, unknown_is_free, tile, s, g));
      if (HasFatalFailure() || HasNonfatalFailure()) return;
      (BruteForce(space, s, g) < kInf ? found : unreachable)++;
    }
  }
  EXPECT_GT(found, 5000);
  EXPECT_GT(unreachable, 300);
}

// Maps whose obstacles all reach the border through 8-connected chains, so
// the free space has no holes. Meshed as one tile, every vertex is then on
// the boundary, so between two polygons there is exactly one channel (the
// dual graph of a convex partition of a simple polygon is a tree) and the funnel
// through it is the shortest path.
Grid HoleFreeMap(std::mt19937& rng) {
  const int w = 3 + static_cast<int>(rng() % 14);
  const int h = 3 + static_cast<int>(rng() % 14);
  Grid grid = Grid::Create(w, h).value();
  const int walls = static_cast<int>(rng() % 6);
  for (int i = 0; i < walls; ++i) {
    int x = 0;
    int y = 0;
    switch (rng() % 4) {
      case 0: x = static_cast<int>(rng() % w); break;
      case 1: x = static_cast<int>(rng() % w); y = h - 1; break;
      case 2: y = static_cast<int>(rng() % h); break;
      default: y = static_cast<int>(rng() % h); x = w - 1; break;
    }
    const int len = 1 + static_cast<int>(rng() % 10);
    for (int k = 0; k < len && grid.InBounds(x, y); ++k) {
      grid.set_cost(x, y, kLethalCost);
      x += static_cast<int>(rng() % 3) - 1;
      y += static_cast<int>(rng() % 3) - 1;
    }
  }
  return grid;
}

// The portals from a start polygon to a goal polygon (breadth-first over
// the mesh), each seen walking towards the goal; nullopt when none joins.
std::optional<std::vector<Portal>> Channel(const NavMesh& mesh,
                                           const std::vector<NavRef>& from,
                                           const std::vector<NavRef>& to) {
  struct Step {
    NavRef at;
    int parent;
    int edge;  // of the parent's polygon, crossed to get here
  };
  std::vector<Step> steps;
  for (const NavRef& r : from) steps.push_back({r, -1, -1});
  auto seen = [&](NavRef r) {
    return std::any_of(steps.begin(), steps.end(), [&](const Step& s) { return s.at == r; });
  };
  for (size_t i = 0; i < steps.size(); ++i) {
    if (std::find(to.begin(), to.end(), steps[i].at) != to.end()) {
      std::vector<Portal> portals;
      for (int k = static_cast<int>(i); steps[k].parent >= 0; k = steps[k].parent) {
        const NavPolygonView t = mesh.polygon(steps[steps[k].parent].at);
        // Leaving a counter-clockwise polygon through corner e -> e + 1:
        // the far end is on the left.
        portals.push_back(Portal{ToCellPoint(t.corner(steps[k].edge + 1)),
                                 ToCellPoint(t.corner(steps[k].edge))});
      }
      std::reverse(portals.begin(), portals.end());
      return portals;
    }
    for (int e = 0; e < mesh.polygon(steps[i].at).size; ++e) {
      const NavRef n = mesh.Across(steps[i].at, e);
      if (n.valid() && !seen(n)) steps.push_back({n, static_cast<int>(i), e});
    }
  }
  return std::nullopt;
}

TEST(Funnel, ThroughMeshChannelsIsTheShortestPath) {
  std::mt19937 rng(99);
  int compared = 0;
  for (int trial = 0; trial < 1500; ++trial) {
    const Grid grid = HoleFreeMap(rng);
    const std::vector<Cell> free = FreeCells(grid, false);
    if (free.empty()) continue;
    const auto mesh = NavMesh::Build(grid, false, NavMesh::kMaxTileSize);
    const FreeSpace space(grid, false);
    const Cell s = free[rng() % free.size()];
    const Cell g = free[rng() % free.size()];
    const auto portals = Channel(*mesh, mesh->Locate(s), mesh->Locate(g));
    const double expected = BruteForce(space, s, g);
    ASSERT_EQ(portals.has_value(), expected < kInf) << "trial " << trial;
    if (!portals) continue;
    const std::vector<CellPoint> path =
        FunnelPath(ToCellPoint(CentreOf(s)), *portals, ToCellPoint(CentreOf(g)));
    std::vector<LatticePoint> lattice;
    for (const CellPoint& p : path) lattice.push_back(*ToLatticePoint(p));
    EXPECT_TRUE(space.PolylineClear(lattice))
        << "trial " << trial << " " << Describe(grid, false, NavMesh::kMaxTileSize, s, g);
    EXPECT_NEAR(PolylineLength(lattice), expected, 1e-9 * (1 + expected))
        << "trial " << trial << " " << Describe(grid, false, NavMesh::kMaxTileSize, s, g);
    if (HasFailure()) return;
    ++compared;
  }
  EXPECT_GT(compared, 1000);
}

TEST(Polyanya, PinchCornersAreClosed) {
  // Two blocked cells touching at a corner separate their free neighbours.
  const Grid grid = MakeGrid({"..#", ".#.", "#.."});
  const auto mesh = NavMesh::Build(grid, false);
  SearchScratch scratch;
  const PolyanyaPath path =
      PolyanyaSearch(*mesh, grid, {0, 0}, {2, 2}, StopCondition::None(), scratch);
  EXPECT_EQ(path.outcome, PlanOutcome::kNoPath);
  const Grid open_diagonal = MakeGrid({"..#", "...", "#.."});
  const auto mesh2 = NavMesh::Build(open_diagonal, false);
  const PolyanyaPath through = PolyanyaSearch(*mesh2, open_diagonal, {0, 0}, {2, 2},
                                              StopCondition::None(), scratch);
  ASSERT_EQ(through.outcome, PlanOutcome::kFound);
  EXPECT_NEAR(PolylineLength(through.polyline), 2 * kSqrt2, 1e-12);
}

TEST(Polyanya, GrazesCornersOnAStraightLine) {
  // The diagonal from (0, 0) to (5, 5) touches the corners of the blocked
  // staircase below it: a straight path through four corners.
  const Grid grid = MakeGrid({"......", "#.....", ".#....", "..#...", "...#..",
                              "....#."});
  const auto mesh = NavMesh::Build(grid, false, 2);
  SearchScratch scratch;
  const PolyanyaPath path =
      PolyanyaSearch(*mesh, grid, {0, 0}, {5, 5}, StopCondition::None(), scratch);
  ASSERT_EQ(path.outcome, PlanOutcome::kFound);
  EXPECT_NEAR(PolylineLength(path.polyline), 5 * kSqrt2, 1e-12);
  EXPECT_TRUE(FreeSpace(grid, false).PolylineClear(path.polyline));
  // One segment: the corners it grazes are not vertices of the polyline.
  EXPECT_EQ(path.polyline.size(), 2u);
}

TEST(NavMeshPlanner, AnswersWithAnExactPolylineAndItsCells) {
  const Planner* planner = PlannerRegistry::Default().Get("navmesh");
  ASSERT_NE(planner, nullptr);
  EXPECT_TRUE(planner->traits().geometric);
  // Around a wall: bends at the wall's bottom corner (3, 3).
  const Grid grid = MakeGrid({"..#..", "..#..", "..#..", ".....", "....."});
  SearchScratch scratch;
  auto r = planner->Plan(grid, PlanRequest::Between({0, 0}, {4, 0}),
                         StopCondition::None(), scratch);
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_TRUE(r->found());
  ASSERT_EQ(r->polyline.size(), 4u);
  EXPECT_EQ(r->polyline[1].x, 2.0);
  EXPECT_EQ(r->polyline[1].y, 3.0);
  EXPECT_EQ(r->polyline[2].x, 3.0);
  EXPECT_EQ(r->polyline[2].y, 3.0);
  const double expected = 2 * std::hypot(1.5, 2.5) + 1.0;
  EXPECT_NEAR(r->length, expected, 1e-12);
  EXPECT_EQ(r->cost, r->length);
  EXPECT_FALSE(r->any_angle);
  EXPECT_EQ(r->path.front(), (Cell{0, 0}));
  EXPECT_EQ(r->path.back(), (Cell{4, 0}));
  const PathMeasure m = MeasureResultPath(grid, *r, {});
  EXPECT_TRUE(m.valid);
  EXPECT_NEAR(m.length, expected, 1e-12);
}

TEST(NavMeshPlanner, UniformNonZeroCostScalesTheCost) {
  const Planner* planner = PlannerRegistry::Default().Get("navmesh");
  ASSERT_NE(planner, nullptr);
  SearchScratch scratch;
  const Grid grid = MakeGrid({"3333", "3#33", "3333"});
  auto r = planner->Plan(grid, PlanRequest::Between({0, 0}, {3, 2}),
                         StopCondition::None(), scratch);
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_TRUE(r->found());
  const PathMeasure m = MeasureResultPath(grid, *r, {});
  ASSERT_TRUE(m.valid);
  EXPECT_NEAR(r->cost, m.cost, 1e-12);
  EXPECT_NEAR(r->cost, r->length * (1 + 84.0 / 252), 1e-12);
}

TEST(NavMeshPlanner, RefusesWeightedAndFourConnectedRequests) {
  const Planner* planner = PlannerRegistry::Default().Get("navmesh");
  ASSERT_NE(planner, nullptr);
  SearchScratch scratch;
  const Grid weighted = MakeGrid({"..3..", "....."});
  auto r = planner->Plan(weighted, PlanRequest::Between({0, 0}, {4, 0}),
                         StopCondition::None(), scratch);
  EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_NE(r.status().message().find("navmesh"), std::string::npos);
  CostParams four;
  four.connectivity = Connectivity::kFour;
  r = planner->Plan(MakeGrid({"....."}), PlanRequest::Between({0, 0}, {4, 0}, four),
                    StopCondition::None(), scratch);
  EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition);
}

// An advanced mesh answers exactly like a rebuilt one.
TEST(Polyanya, AdvancedMeshAnswersLikeARebuiltOne) {
  std::mt19937 rng(7);
  SearchScratch scratch;
  for (int run = 0; run < 20; ++run) {
    Grid grid = Grid::Create(23 + run % 5, 19 + run % 3).value();
    for (size_t i = 0; i < grid.size(); ++i) {
      if (rng() % 100 < 25) grid.mutable_cells()[i] = kLethalCost;
    }
    std::shared_ptr<const NavMesh> mesh = NavMesh::Build(grid, false, 5);
    for (int step = 0; step < 10; ++step) {
      std::vector<Cell> changed;
      const int n = 1 + static_cast<int>(rng() % 6);
      for (int k = 0; k < n; ++k) {
        const Cell c{static_cast<int32_t>(rng() % grid.width()),
                     static_cast<int32_t>(rng() % grid.height())};
        grid.set_cost(c, rng() % 2 ? kLethalCost : kFreeCost);
        changed.push_back(c);
      }
      mesh = NavMesh::Advance(*mesh, grid, changed);
      ASSERT_NE(mesh, nullptr);
      const auto rebuilt = NavMesh::Build(grid, false, 5);
      const std::vector<Cell> free = FreeCells(grid, false);
      if (free.empty()) continue;
      for (int q = 0; q < 5; ++q) {
        const Cell s = free[rng() % free.size()];
        const Cell g = free[rng() % free.size()];
        const PolyanyaPath a = PolyanyaSearch(*mesh, grid, s, g, StopCondition::None(), scratch);
        const PolyanyaPath b =
            PolyanyaSearch(*rebuilt, grid, s, g, StopCondition::None(), scratch);
        ASSERT_EQ(a.outcome, b.outcome) << "run " << run << " step " << step;
        if (a.outcome == PlanOutcome::kFound) {
          EXPECT_EQ(PolylineLength(a.polyline), PolylineLength(b.polyline));
        }
      }
    }
  }
}

TEST(Polyanya, StopsOnTheBudget) {
  Grid grid = Grid::Create(100, 100).value();
  for (int32_t y = 4; y < 100; y += 4) {
    for (int32_t x = 0; x < 100; ++x) grid.set_cost(x, y, kLethalCost);
    grid.set_cost((y / 4) % 2 == 0 ? 99 : 0, y, kFreeCost);
  }
  const auto mesh = NavMesh::Build(grid, false);
  SearchScratch scratch;
  const PolyanyaPath capped = PolyanyaSearch(
      *mesh, grid, {0, 0}, {99, 99}, StopCondition(absl::InfiniteFuture(), nullptr, 10),
      scratch);
  EXPECT_EQ(capped.outcome, PlanOutcome::kExpansionLimit);
  EXPECT_LE(capped.expansions, 10);
  const PolyanyaPath full =
      PolyanyaSearch(*mesh, grid, {0, 0}, {99, 99}, StopCondition::None(), scratch);
  ASSERT_EQ(full.outcome, PlanOutcome::kFound);
  EXPECT_TRUE(FreeSpace(grid, false).PolylineClear(full.polyline));
}

}  // namespace
}  // namespace pathd
