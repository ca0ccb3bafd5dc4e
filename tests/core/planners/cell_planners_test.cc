// The `trapezoidal` and `voronoi` planners on thousands of small random maps
// against independent brute forces: reachability by a BFS over free cells,
// the Euclidean shortest path by Dijkstra over a visibility graph of obstacle
// corners (a lower bound for the trapezoidal path), and the best clearance
// bottleneck by a widest-path relaxation over a distance field computed by
// trying every obstacle. Both read their structure through a DerivedStore,
// which must give the same answers when it advances a value instead of
// building it.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "core/geometry/free_space.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/derived.h"
#include "core/search/path_measure.h"
#include "core/search/registry.h"
#include "gtest/gtest.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

absl::StatusOr<PlanResult> Plan(const std::string& name, const Grid& grid,
                                const PlanRequest& request) {
  SearchScratch scratch;
  return PlannerRegistry::Default().Get(name)->Plan(
      grid, request, StopCondition::None(), scratch);
}

bool Free(const Grid& grid, int x, int y, bool unknown_is_free) {
  return grid.InBounds(x, y) && Traversable(grid.cost(x, y), unknown_is_free);
}

Grid RandomGrid(std::mt19937& rng, int w, int h) {
  Grid grid = Grid::Create(w, h).value();
  const int pct = static_cast<int>(rng() % 45);
  for (uint8_t& v : grid.mutable_cells()) {
    const int roll = static_cast<int>(rng() % 100);
    v = roll < pct ? (rng() % 5 == 0 ? kUnknownCost : kLethalCost) : kFreeCost;
  }
  return grid;
}

// Free cells reachable from `start` through shared edges (free space's
// connectivity; a diagonal step without corner cutting is two such steps).
std::vector<bool> Reachable(const Grid& grid, Cell start,
                            bool unknown_is_free) {
  std::vector<bool> seen(grid.size(), false);
  std::vector<Cell> stack{start};
  seen[grid.Index(start)] = true;
  while (!stack.empty()) {
    const Cell c = stack.back();
    stack.pop_back();
    for (const Cell n : {Cell{c.x + 1, c.y}, Cell{c.x - 1, c.y},
                         Cell{c.x, c.y + 1}, Cell{c.x, c.y - 1}}) {
      if (!Free(grid, n.x, n.y, unknown_is_free) || seen[grid.Index(n)])
        continue;
      seen[grid.Index(n)] = true;
      stack.push_back(n);
    }
  }
  return seen;
}

// Euclidean shortest path length between the cell centres in free space:
// Dijkstra over start, goal and every convex obstacle corner, joined where
// the segment is clear.
double EuclideanShortest(const Grid& grid, Cell s, Cell g,
                         bool unknown_is_free) {
  const FreeSpace space(grid, unknown_is_free);
  std::vector<LatticePoint> nodes{CentreOf(s), CentreOf(g)};
  for (const LatticePoint p : space.BendCorners()) nodes.push_back(p);
  std::vector<double> dist(nodes.size(), kInf);
  std::vector<bool> done(nodes.size(), false);
  dist[0] = 0.0;
  while (true) {
    size_t u = nodes.size();
    for (size_t i = 0; i < nodes.size(); ++i) {
      if (!done[i] && !std::isinf(dist[i]) &&
          (u == nodes.size() || dist[i] < dist[u]))
        u = i;
    }
    if (u == nodes.size()) return kInf;
    if (u == 1) return dist[1];
    done[u] = true;
    for (size_t v = 0; v < nodes.size(); ++v) {
      if (done[v] || !space.SegmentClear(nodes[u], nodes[v])) continue;
      dist[v] = std::min(dist[v], dist[u] + Distance(nodes[u], nodes[v]));
    }
  }
}

// Octile distance from each cell centre to the nearest blocked cell or
// outside cell, trying all of them.
std::vector<double> BruteClearance(const Grid& grid, bool unknown_is_free) {
  std::vector<Cell> obstacles;
  for (int y = -1; y <= grid.height(); ++y) {
    for (int x = -1; x <= grid.width(); ++x) {
      if (!Free(grid, x, y, unknown_is_free)) obstacles.push_back({x, y});
    }
  }
  std::vector<double> d(grid.size(), kInf);
  for (int y = 0; y < grid.height(); ++y) {
    for (int x = 0; x < grid.width(); ++x) {
      for (const Cell& o : obstacles) {
        const double dx = std::abs(x - o.x);
        const double dy = std::abs(y - o.y);
        d[grid.Index(x, y)] = std::min(d[grid.Index(x, y)],
                                       std::max(dx, dy) - std::min(dx, dy) +
                                           std::sqrt(2.0) * std::min(dx, dy));
      }
    }
  }
  return d;
}

// The largest bottleneck (smallest clearance over the path's cells) of any
// legal 8-connected path from s to g, by relaxing until nothing changes; -1
// when g is unreachable.
double BruteWidest(const Grid& grid, const std::vector<double>& clearance,
                   Cell s, Cell g, bool unknown_is_free) {
  std::vector<double> best(grid.size(), -1.0);
  best[grid.Index(s)] = clearance[grid.Index(s)];
  for (bool changed = true; changed;) {
    changed = false;
    for (int y = 0; y < grid.height(); ++y) {
      for (int x = 0; x < grid.width(); ++x) {
        const double b = best[grid.Index(x, y)];
        if (b < 0) continue;
        for (const Move& m : kMoves) {
          const int nx = x + m.dx;
          const int ny = y + m.dy;
          if (!Free(grid, nx, ny, unknown_is_free)) continue;
          if (m.dx != 0 && m.dy != 0 &&
              (!Free(grid, x + m.dx, y, unknown_is_free) ||
               !Free(grid, x, y + m.dy, unknown_is_free))) {
            continue;
          }
          const double nb = std::min(b, clearance[grid.Index(nx, ny)]);
          if (nb > best[grid.Index(nx, ny)] + 1e-12) {
            best[grid.Index(nx, ny)] = nb;
            changed = true;
          }
        }
      }
    }
  }
  return best[grid.Index(g)];
}

double PathClearance(const Grid& grid, const std::vector<double>& clearance,
                     const std::vector<Cell>& path) {
  double lowest = kInf;
  for (const Cell c : path) lowest = std::min(lowest, clearance[grid.Index(c)]);
  return lowest;
}

TEST(TrapezoidalPlanner, RandomMapsAgreeWithBruteForce) {
  std::mt19937 rng(404);
  int found = 0;
  for (int trial = 0; trial < 2500; ++trial) {
    const int w = 1 + static_cast<int>(rng() % 14);
    const int h = 1 + static_cast<int>(rng() % 14);
    const Grid grid = RandomGrid(rng, w, h);
    CostParams params;
    params.unknown_is_free = trial % 3 == 0;
    const Cell s{static_cast<int32_t>(rng() % w),
                 static_cast<int32_t>(rng() % h)};
    const Cell g{static_cast<int32_t>(rng() % w),
                 static_cast<int32_t>(rng() % h)};
    if (!Free(grid, s.x, s.y, params.unknown_is_free) ||
        !Free(grid, g.x, g.y, params.unknown_is_free)) {
      continue;
    }
    const auto r =
        Plan("trapezoidal", grid, PlanRequest::Between(s, g, params));
    ASSERT_TRUE(r.ok()) << r.status();
    const bool reachable =
        Reachable(grid, s, params.unknown_is_free)[grid.Index(g)];
    ASSERT_EQ(r->found(), reachable) << "trial " << trial;
    if (!reachable) {
      EXPECT_EQ(r->outcome, PlanOutcome::kNoPath);
      continue;
    }
    ++found;
    const PathMeasure m = MeasureResultPath(grid, *r, params);
    ASSERT_TRUE(m.valid) << "trial " << trial << " segment " << m.first_invalid;
    EXPECT_NEAR(r->length, m.length, 1e-9);
    EXPECT_GE(r->length,
              EuclideanShortest(grid, s, g, params.unknown_is_free) - 1e-9)
        << "trial " << trial;
    const FreeSpace space(grid, params.unknown_is_free);
    std::vector<LatticePoint> points;
    for (const CellPoint p : r->polyline) points.push_back(*ToLatticePoint(p));
    EXPECT_EQ(points.front(), CentreOf(s));
    EXPECT_EQ(points.back(), CentreOf(g));
    EXPECT_EQ(r->path, CellsAlongPolyline(space, points)) << "trial " << trial;
  }
  EXPECT_GT(found, 1000);
}

TEST(TrapezoidalPlanner, GoesStraightThroughOpenSpace) {
  const Grid grid = Grid::Create(20, 10).value();
  const auto r =
      Plan("trapezoidal", grid, PlanRequest::Between({0, 0}, {19, 9}));
  ASSERT_TRUE(r.ok() && r->found());
  EXPECT_EQ(r->polyline.size(), 2u);
  EXPECT_DOUBLE_EQ(r->length, std::hypot(19.0, 9.0));
}

TEST(TrapezoidalPlanner, BendsAtTheCornerOfAWall) {
  // Around the wall's lower end: the funnel bends at its corner (5, 4).
  const Grid grid = MakeGrid({".....#....", ".....#....", ".....#....",
                              ".....#....", "..........", ".........."});
  const auto r =
      Plan("trapezoidal", grid, PlanRequest::Between({1, 1}, {8, 1}));
  ASSERT_TRUE(r.ok() && r->found());
  ASSERT_EQ(r->polyline.size(), 4u);
  EXPECT_DOUBLE_EQ(r->polyline[1].x, 5.0);
  EXPECT_DOUBLE_EQ(r->polyline[1].y, 4.0);
  EXPECT_DOUBLE_EQ(r->polyline[2].x, 6.0);
  EXPECT_DOUBLE_EQ(r->polyline[2].y, 4.0);
  EXPECT_NEAR(r->length, std::hypot(3.5, 2.5) + 1.0 + std::hypot(2.5, 2.5),
              1e-12);
}

TEST(VoronoiPlanner, RandomMapsReachTheBestBottleneck) {
  std::mt19937 rng(2024);
  int found = 0;
  int wider_than_astar = 0;
  for (int trial = 0; trial < 2500; ++trial) {
    const int w = 1 + static_cast<int>(rng() % 16);
    const int h = 1 + static_cast<int>(rng() % 16);
    const Grid grid = RandomGrid(rng, w, h);
    CostParams params;
    params.unknown_is_free = trial % 3 == 0;
    const Cell s{static_cast<int32_t>(rng() % w),
                 static_cast<int32_t>(rng() % h)};
    const Cell g{static_cast<int32_t>(rng() % w),
                 static_cast<int32_t>(rng() % h)};
    if (!Free(grid, s.x, s.y, params.unknown_is_free) ||
        !Free(grid, g.x, g.y, params.unknown_is_free)) {
      continue;
    }
    const PlanRequest request = PlanRequest::Between(s, g, params);
    const auto r = Plan("voronoi", grid, request);
    ASSERT_TRUE(r.ok()) << r.status();
    const bool reachable =
        Reachable(grid, s, params.unknown_is_free)[grid.Index(g)];
    ASSERT_EQ(r->found(), reachable) << "trial " << trial;
    if (!reachable) {
      EXPECT_EQ(r->outcome, PlanOutcome::kNoPath);
      continue;
    }
    ++found;
    const PathMeasure m = MeasurePath(grid, r->path, params);
    ASSERT_TRUE(m.valid) << "trial " << trial << " step " << m.first_invalid;
    EXPECT_FALSE(r->any_angle);
    EXPECT_NEAR(r->length, m.length, 1e-9);
    ASSERT_EQ(r->path.front(), s);
    ASSERT_EQ(r->path.back(), g);
    const std::vector<double> clearance =
        BruteClearance(grid, params.unknown_is_free);
    const double best =
        BruteWidest(grid, clearance, s, g, params.unknown_is_free);
    EXPECT_NEAR(r->min_clearance, best, 1e-9) << "trial " << trial;
    EXPECT_NEAR(PathClearance(grid, clearance, r->path), best, 1e-9)
        << "trial " << trial;
    const auto a = Plan("astar", grid, request);
    ASSERT_TRUE(a.ok() && a->found());
    const double astar = PathClearance(grid, clearance, a->path);
    EXPECT_GE(r->min_clearance, astar - 1e-9) << "trial " << trial;
    if (r->min_clearance > astar + 1e-9) ++wider_than_astar;
  }
  EXPECT_GT(found, 1000);
  EXPECT_GT(wider_than_astar, 20);  // the property is not vacuous
}

TEST(VoronoiPlanner, KeepsToTheMiddleOfAHall) {
  // A hall five cells high below a room reached through a slot: from one end
  // of the hall to the other the path climbs to the hall's middle row (the
  // diagram, clearance 3) and stays on it.
  const Grid grid = MakeGrid({
      "###############",
      "#.............#",
      "#######.#######",
      "#######.#######",
      "#######.#######",
      "#.............#",
      "#.............#",
      "#.............#",
      "#.............#",
      "#.............#",
      "###############",
  });
  const auto hall =
      Plan("voronoi", grid, PlanRequest::Between({1, 9}, {13, 5}));
  ASSERT_TRUE(hall.ok() && hall->found());
  EXPECT_DOUBLE_EQ(hall->min_clearance, 1.0);  // the corner cells bound it
  int on_middle_row = 0;
  for (const Cell c : hall->path) on_middle_row += c.y == 7 ? 1 : 0;
  EXPECT_GE(on_middle_row, 7);
  const auto inside =
      Plan("voronoi", grid, PlanRequest::Between({4, 7}, {10, 7}));
  ASSERT_TRUE(inside.ok() && inside->found());
  EXPECT_DOUBLE_EQ(inside->min_clearance, 3.0);
  for (const Cell c : inside->path) EXPECT_EQ(c.y, 7) << c.x;
}

TEST(VoronoiPlanner, PrefersTheWiderOfTwoCorridors) {
  // Two ways from the left room to the right one: a corridor one cell wide
  // (row 1, short) and one three cells wide (rows 5-7, longer).
  const Grid grid = MakeGrid({
      "#################",
      "#...............#",
      "#...#########...#",
      "#...#########...#",
      "#...#########...#",
      "#...............#",
      "#...............#",
      "#...............#",
      "#...............#",
      "#################",
  });
  const auto v = Plan("voronoi", grid, PlanRequest::Between({2, 2}, {14, 2}));
  ASSERT_TRUE(v.ok() && v->found());
  EXPECT_GE(v->min_clearance, 2.0);
  for (const Cell c : v->path) EXPECT_NE(c.y, 1) << c.x;
  const auto a = Plan("astar", grid, PlanRequest::Between({2, 2}, {14, 2}));
  ASSERT_TRUE(a.ok() && a->found());
  EXPECT_LT(a->length, v->length);
}

// A store that keeps the latest value per key and, when told the map
// changed, advances it with the changed cells instead of building anew.
class AdvancingStore final : public DerivedStore {
 public:
  std::shared_ptr<const void> Get(const std::string& key, const DerivedRecipe& recipe,
                                  DerivedStop& stop) override {
    auto it = values_.find(key);
    if (it == values_.end()) {
      ++builds_;
      return values_[key] = recipe.build(*grid_, stop);
    }
    if (!changed_.empty()) {
      std::shared_ptr<const void> next =
          recipe.advance(it->second.get(), *grid_, changed_, stop);
      if (next == nullptr) {
        ++builds_;
        next = recipe.build(*grid_, stop);
      } else {
        ++advances_;
      }
      it->second = next;
    }
    return it->second;
  }
  void SetGrid(const Grid* grid, std::vector<Cell> changed) {
    grid_ = grid;
    changed_ = std::move(changed);
  }
  int builds_ = 0;
  int advances_ = 0;

 private:
  const Grid* grid_ = nullptr;
  std::vector<Cell> changed_;
  std::map<std::string, std::shared_ptr<const void>> values_;
};

TEST(CellPlanners, AdvancedStructuresAnswerLikeFreshOnes) {
  std::mt19937 rng(99);
  for (const std::string name : {"voronoi", "trapezoidal"}) {
    AdvancingStore store;
    Grid grid = RandomGrid(rng, 24, 18);
    for (int step = 0; step < 200; ++step) {
      std::vector<Cell> changed;
      for (int k = 0; k < 1 + static_cast<int>(rng() % 4); ++k) {
        const Cell c{static_cast<int32_t>(rng() % 24),
                     static_cast<int32_t>(rng() % 18)};
        grid.set_cost(c, rng() % 2 ? kLethalCost : kFreeCost);
        changed.push_back(c);
      }
      store.SetGrid(&grid, step == 0 ? std::vector<Cell>{} : changed);
      const Cell s{static_cast<int32_t>(rng() % 24),
                   static_cast<int32_t>(rng() % 18)};
      const Cell g{static_cast<int32_t>(rng() % 24),
                   static_cast<int32_t>(rng() % 18)};
      grid.set_cost(s, kFreeCost);
      grid.set_cost(g, kFreeCost);
      // The endpoints were freed after the store was told: tell it too.
      changed.push_back(s);
      changed.push_back(g);
      store.SetGrid(&grid, step == 0 ? std::vector<Cell>{} : changed);
      PlanRequest request = PlanRequest::Between(s, g);
      const auto fresh = Plan(name, grid, request);
      request.derived = &store;
      const auto cached = Plan(name, grid, request);
      ASSERT_TRUE(fresh.ok() && cached.ok());
      ASSERT_EQ(fresh->outcome, cached->outcome) << name << " step " << step;
      EXPECT_EQ(fresh->path, cached->path) << name << " step " << step;
      EXPECT_EQ(fresh->min_clearance, cached->min_clearance)
          << name << " step " << step;
    }
    EXPECT_EQ(store.builds_ + store.advances_, 200) << name;
    if (std::string(name) == "voronoi") {
      EXPECT_EQ(store.advances_, 199);
    }
  }
}

TEST(CellPlanners, RefuseWhatTheyCannotHonour) {
  const Grid grid = MakeGrid({"..5..", "....."});
  CostParams four;
  four.cost_weight = 0.0;
  four.connectivity = Connectivity::kFour;
  for (const std::string name : {"voronoi", "trapezoidal"}) {
    const auto r = Plan(name, grid, PlanRequest::Between({0, 0}, {4, 1}, four));
    EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition) << name;
  }
  // A polyline's cost is its length times one cell factor: uniform maps only.
  auto r = Plan("trapezoidal", grid, PlanRequest::Between({0, 0}, {4, 1}));
  EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition);
  // Clearance, not cost, steers voronoi; the cost of its path is measured.
  r = Plan("voronoi", grid, PlanRequest::Between({0, 0}, {4, 0}));
  ASSERT_TRUE(r.ok() && r->found()) << r.status();
  const PathMeasure m = MeasurePath(grid, r->path, {});
  EXPECT_DOUBLE_EQ(r->cost, m.cost);
}

}  // namespace
}  // namespace pathd
