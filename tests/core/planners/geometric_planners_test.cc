// The geometric planners against references written apart from them, on
// 5,000 random small maps (random obstacles, checkerboard patches of
// pinches, walls with and without a one-cell gap, diagonal chains of
// corner-touching obstacles, unknown cells, starts and goals beside obstacle
// corners, unreachable goals):
//  - an exact reference: Dijkstra over a visibility graph of the convex
//    obstacle corners (corners with exactly one blocked cell, the only
//    points where a Euclidean shortest path bends) plus start and goal, its
//    edges tested by the independent SegmentChecker
//    (tests/testing/segment_checker.h), and a 4-connected BFS over free
//    cells for "a path exists" (the free space's connectivity);
//  - visibility_graph, minimal_construct, navmesh and euclidean_spm equal
//    the reference to 1e-9 relative (so agree with each other), find a path
//    exactly when the BFS does, are never longer than theta_star nor shorter
//    than the straight line, and every polyline segment is clear under the
//    checker (as are trapezoidal's, which is never shorter than the
//    reference);
//  - voronoi's paths are legal grid moves, its min_clearance is that of its
//    path, never below A*'s path's clearance, and equal to a brute-force
//    maximum-bottleneck search over a brute-force clearance field (octile
//    distance to the nearest blocked or outside cell centre, the voronoi
//    planner's definition; the core's Euclidean transform brackets it);
//  - incremental vs rebuild: through random map-update sequences, every
//    geometric planner answers on structures advanced by
//    tests/testing/advancing_store.h exactly as on fresh builds.
// A planner that is not registered yet is skipped, by name.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <map>
#include <queue>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "core/geometry/free_space.h"
#include "core/map/cost_model.h"
#include "core/map/euclidean_distance.h"
#include "core/search/planner.h"
#include "core/search/registry.h"
#include "gtest/gtest.h"
#include "tests/testing/advancing_store.h"
#include "tests/testing/segment_checker.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

using testing::AdvancingStore;
using testing::PolylineChecker;
using testing::SegmentChecker;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kRandomMaps = 5000;
// Besides, larger maps (16 to 28 cells a side): long segments, many corners.
constexpr int kLargerMaps = 100;

// The planners whose answers are exact Euclidean shortest paths.
const std::vector<std::string>& ExactPlanners() {
  static const auto* names = new std::vector<std::string>{
      "visibility_graph", "minimal_construct", "navmesh", "euclidean_spm"};
  return *names;
}
const std::vector<std::string>& GeometricPlanners() {
  static const auto* names = new std::vector<std::string>{
      "visibility_graph", "minimal_construct", "navmesh", "euclidean_spm",
      "trapezoidal", "voronoi"};
  return *names;
}
bool IsExact(const std::string& name) {
  return std::find(ExactPlanners().begin(), ExactPlanners().end(), name) !=
         ExactPlanners().end();
}

std::string GridText(const Grid& grid) {
  std::string out;
  for (int32_t y = 0; y < grid.height(); ++y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      const uint8_t c = grid.cost(x, y);
      out += c == kLethalCost ? '#' : c == kUnknownCost ? '?' : '.';
    }
    out += '\n';
  }
  return out;
}

std::string PolylineText(const std::vector<CellPoint>& polyline) {
  std::vector<std::string> parts;
  for (const CellPoint& p : polyline) parts.push_back(absl::StrFormat("(%g, %g)", p.x, p.y));
  return absl::StrJoin(parts, " ");
}

double CentreDistance(Cell a, Cell b) {
  return std::hypot(static_cast<double>(a.x - b.x), static_cast<double>(a.y - b.y));
}

// ---------------------------------------------------------------------------
// References.

// 4-connected reachability over traversable cells: exactly when the free
// space joins two cell centres (diagonal neighbours whose two side cells are
// blocked touch at a pinch, which is closed; with one side cell free the
// path goes through it).
bool Reachable(const Grid& grid, bool unknown_is_free, Cell s, Cell g) {
  std::vector<uint8_t> seen(grid.size(), 0);
  std::vector<Cell> queue{s};
  seen[grid.Index(s)] = 1;
  for (size_t head = 0; head < queue.size(); ++head) {
    const Cell c = queue[head];
    if (c == g) return true;
    for (Cell d : {Cell{1, 0}, Cell{-1, 0}, Cell{0, 1}, Cell{0, -1}}) {
      const Cell n{c.x + d.x, c.y + d.y};
      if (!grid.InBounds(n) || seen[grid.Index(n)] ||
          !Traversable(grid.cost(n), unknown_is_free)) {
        continue;
      }
      seen[grid.Index(n)] = 1;
      queue.push_back(n);
    }
  }
  return false;
}

// Exact Euclidean shortest path lengths on one grid: A* (Euclidean
// heuristic) over the convex obstacle corners plus start and goal, edges
// tested lazily with the SegmentChecker and remembered between queries.
class ReferencePaths {
 public:
  ReferencePaths(const Grid& grid, bool unknown_is_free)
      : checker_(grid, unknown_is_free) {
    for (int64_t y = 0; y <= grid.height(); ++y) {
      for (int64_t x = 0; x <= grid.width(); ++x) {
        const int blocked = checker_.Blocked(x - 1, y - 1) + checker_.Blocked(x, y - 1) +
                            checker_.Blocked(x - 1, y) + checker_.Blocked(x, y);
        if (blocked == 1) corners_.push_back(CornerAt(x, y));
      }
    }
    const size_t n = corners_.size();
    clear_.assign(n * n, -1);
  }

  const SegmentChecker& checker() const { return checker_; }
  size_t corner_count() const { return corners_.size(); }

  double Shortest(Cell start, Cell goal) {
    const size_t n = corners_.size();
    // Vertices: corners 0..n-1, start n, goal n+1.
    auto point = [&](size_t v) {
      return v < n ? corners_[v] : CentreOf(v == n ? start : goal);
    };
    auto clear = [&](size_t u, size_t v) {
      if (u < n && v < n) {
        int8_t& memo = clear_[u * n + v];
        if (memo < 0) memo = clear_[v * n + u] = checker_.Clear(point(u), point(v)) ? 1 : 0;
        return memo == 1;
      }
      return checker_.Clear(point(u), point(v));
    };
    const LatticePoint target = CentreOf(goal);
    std::vector<double> g(n + 2, kInf);
    std::vector<uint8_t> closed(n + 2, 0);
    using Item = std::pair<double, size_t>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
    g[n] = 0.0;
    open.push({Distance(point(n), target), n});
    while (!open.empty()) {
      const size_t u = open.top().second;
      open.pop();
      if (closed[u]) continue;
      closed[u] = 1;
      if (u == n + 1) return g[u];
      for (size_t v = 0; v < n + 2; ++v) {
        if (closed[v] || v == n) continue;
        const double w = Distance(point(u), point(v));
        if (g[u] + w >= g[v]) continue;
        if (!clear(u, v)) continue;
        g[v] = g[u] + w;
        open.push({g[v] + Distance(point(v), target), v});
      }
    }
    return kInf;
  }

 private:
  SegmentChecker checker_;
  std::vector<LatticePoint> corners_;
  std::vector<int8_t> clear_;
};

// The clearance field of the voronoi planner (core/geometry/voronoi.h): per
// cell, the octile distance (straight steps 1, diagonal sqrt(2)) from its
// centre to the nearest centre of a blocked cell or of the ring of cells
// around the map, by brute force over every such cell; 0 on blocked cells.
std::vector<double> ClearanceField(const Grid& grid, bool unknown_is_free) {
  std::vector<Cell> obstacles;
  for (int y = -1; y <= grid.height(); ++y) {
    for (int x = -1; x <= grid.width(); ++x) {
      if (!grid.InBounds(x, y) || !Traversable(grid.cost(x, y), unknown_is_free)) {
        obstacles.push_back({x, y});
      }
    }
  }
  std::vector<double> field(grid.size(), 0.0);
  for (int y = 0; y < grid.height(); ++y) {
    for (int x = 0; x < grid.width(); ++x) {
      if (!Traversable(grid.cost(x, y), unknown_is_free)) continue;
      double best = kInf;
      for (Cell o : obstacles) {
        const int dx = std::abs(o.x - x), dy = std::abs(o.y - y);
        best = std::min(best, std::max(dx, dy) - std::min(dx, dy) +
                                  std::min(dx, dy) * std::sqrt(2.0));
      }
      field[grid.Index(x, y)] = best;
    }
  }
  return field;
}

// Clearance of a cell path: the smallest field value over its cells.
double PathClearance(const std::vector<double>& field, const Grid& grid,
                     const std::vector<Cell>& path) {
  double worst = kInf;
  for (Cell c : path) worst = std::min(worst, field[grid.Index(c)]);
  return worst;
}

// The largest clearance any legal 8-connected grid path from s to g can
// keep, by brute force: for each distinct field value, highest first, a BFS
// over the cells with at least that value; the first that reaches g.
// -1 when g is unreachable.
double MaxBottleneck(const std::vector<double>& field, const Grid& grid,
                     bool unknown_is_free, Cell s, Cell g) {
  std::vector<double> levels;
  for (size_t i = 0; i < grid.size(); ++i) {
    if (Traversable(grid.cells()[i], unknown_is_free)) levels.push_back(field[i]);
  }
  std::sort(levels.begin(), levels.end(), std::greater<>());
  levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
  auto free_cell = [&](int x, int y) {
    return grid.InBounds(x, y) && Traversable(grid.cost(x, y), unknown_is_free);
  };
  for (double level : levels) {
    if (field[grid.Index(s)] < level || field[grid.Index(g)] < level) continue;
    std::vector<uint8_t> seen(grid.size(), 0);
    std::vector<Cell> queue{s};
    seen[grid.Index(s)] = 1;
    for (size_t head = 0; head < queue.size(); ++head) {
      const Cell c = queue[head];
      if (c == g) return level;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = c.x + dx, ny = c.y + dy;
          if ((dx == 0 && dy == 0) || !free_cell(nx, ny)) continue;
          if (dx != 0 && dy != 0 && (!free_cell(c.x + dx, c.y) || !free_cell(c.x, c.y + dy))) {
            continue;
          }
          const size_t i = grid.Index(nx, ny);
          if (seen[i] || field[i] < level) continue;
          seen[i] = 1;
          queue.push_back({nx, ny});
        }
      }
    }
  }
  return -1.0;
}

// The first illegal step of a grid path (8-connected, no corner cutting,
// every cell traversable), or -1.
int FirstIllegalStep(const Grid& grid, bool unknown_is_free, const std::vector<Cell>& path) {
  auto free_cell = [&](int x, int y) {
    return grid.InBounds(x, y) && Traversable(grid.cost(x, y), unknown_is_free);
  };
  for (size_t i = 0; i < path.size(); ++i) {
    if (!free_cell(path[i].x, path[i].y)) return static_cast<int>(i);
    if (i == 0) continue;
    const int dx = path[i].x - path[i - 1].x, dy = path[i].y - path[i - 1].y;
    if (std::abs(dx) > 1 || std::abs(dy) > 1 || (dx == 0 && dy == 0)) return static_cast<int>(i);
    if (dx != 0 && dy != 0 &&
        (!free_cell(path[i - 1].x + dx, path[i - 1].y) ||
         !free_cell(path[i - 1].x, path[i - 1].y + dy))) {
      return static_cast<int>(i);
    }
  }
  return -1;
}

// ---------------------------------------------------------------------------
// Cases.

struct Query {
  Cell start;
  Cell goal;
  // References, filled once.
  bool reachable = false;
  double shortest = kInf;
};

struct Case {
  std::string name;
  Grid grid;
  bool unknown_is_free = false;
  std::vector<Query> queries;
};

void Block(Grid& grid, int x, int y) {
  if (grid.InBounds(x, y)) grid.set_cost(x, y, kLethalCost);
}

Grid RandomGrid(std::mt19937_64& rng, int index, int min_side = 2, int max_side = 11) {
  std::uniform_int_distribution<int> dim(min_side, max_side);
  const int w = dim(rng), h = dim(rng);
  Grid grid = *Grid::Create(w, h);
  const double density = std::uniform_real_distribution<double>(0.0, 0.4)(rng);
  std::bernoulli_distribution blocked(density);
  std::bernoulli_distribution unknown(0.1);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (blocked(rng)) grid.set_cost(x, y, unknown(rng) ? kUnknownCost : kLethalCost);
    }
  }
  auto rx = [&] { return static_cast<int>(rng() % w); };
  auto ry = [&] { return static_cast<int>(rng() % h); };
  switch (index % 6) {
    case 0: {  // A checkerboard patch: pinches at every inner corner.
      const int x0 = rx(), y0 = ry();
      for (int y = y0; y < std::min(h, y0 + 4); ++y) {
        for (int x = x0; x < std::min(w, x0 + 4); ++x) {
          grid.set_cost(x, y, (x + y) % 2 == 0 ? kLethalCost : kFreeCost);
        }
      }
      break;
    }
    case 1:    // A wall with a one-cell gap.
    case 2: {  // A wall without one: the two sides are apart.
      const bool horizontal = rng() % 2 == 0;
      const int at = horizontal ? ry() : rx();
      const int len = horizontal ? w : h;
      const int gap = index % 6 == 1 ? static_cast<int>(rng() % len) : -1;
      for (int i = 0; i < len; ++i) {
        if (i == gap) {
          if (horizontal) grid.set_cost(i, at, kFreeCost);
          else grid.set_cost(at, i, kFreeCost);
          continue;
        }
        if (horizontal) Block(grid, i, at);
        else Block(grid, at, i);
      }
      break;
    }
    case 3: {  // A diagonal chain of corner-touching blocked cells.
      const int x0 = rx(), y0 = ry();
      const int sx = rng() % 2 == 0 ? 1 : -1;
      for (int k = 0; k < std::max(w, h); ++k) Block(grid, x0 + sx * k, y0 + k);
      break;
    }
    case 4: {  // A few rectangles that may touch at corners.
      for (int r = 0; r < 3; ++r) {
        const int x0 = rx(), y0 = ry();
        const int rw = 1 + static_cast<int>(rng() % 3), rh = 1 + static_cast<int>(rng() % 3);
        for (int y = y0; y < y0 + rh; ++y) {
          for (int x = x0; x < x0 + rw; ++x) Block(grid, x, y);
        }
      }
      break;
    }
    default:
      break;
  }
  return grid;
}

// A random traversable cell; with `near_corner`, preferably one diagonal to
// a blocked cell (beside an obstacle corner). nullopt when none is free.
std::optional<Cell> RandomFreeCell(std::mt19937_64& rng, const Grid& grid,
                                   bool unknown_is_free, bool near_corner) {
  std::vector<Cell> free, beside;
  for (int y = 0; y < grid.height(); ++y) {
    for (int x = 0; x < grid.width(); ++x) {
      if (!Traversable(grid.cost(x, y), unknown_is_free)) continue;
      free.push_back({x, y});
      for (Cell d : {Cell{1, 1}, Cell{1, -1}, Cell{-1, 1}, Cell{-1, -1}}) {
        const Cell n{x + d.x, y + d.y};
        if (grid.InBounds(n) && !Traversable(grid.cost(n), unknown_is_free)) {
          beside.push_back({x, y});
          break;
        }
      }
    }
  }
  if (free.empty()) return std::nullopt;
  const std::vector<Cell>& pool = near_corner && !beside.empty() ? beside : free;
  return pool[rng() % pool.size()];
}

void AddQueries(std::mt19937_64& rng, Case& c, int count) {
  for (int q = 0; q < count; ++q) {
    const auto s = RandomFreeCell(rng, c.grid, c.unknown_is_free, q % 2 == 0);
    const auto g = RandomFreeCell(rng, c.grid, c.unknown_is_free, q % 3 == 0);
    if (!s || !g) return;
    c.queries.push_back({*s, *g});
  }
}

// Hand-made cases whose answers are easy to see.
std::vector<Case> DesignedCases() {
  std::vector<Case> cases;
  auto add = [&](std::string name, std::vector<std::string> rows,
                 std::vector<std::pair<Cell, Cell>> queries) {
    Case c{std::move(name), MakeGrid(rows), false, {}};
    for (auto [s, g] : queries) c.queries.push_back({s, g});
    cases.push_back(std::move(c));
  };
  add("open", {".....", ".....", "....."}, {{{0, 0}, {4, 2}}, {{2, 1}, {2, 1}}});
  add("one cell touched at a corner", {"...", ".#.", "..."},
      {{{0, 0}, {2, 2}}, {{0, 1}, {1, 0}}, {{0, 0}, {2, 1}}});
  add("pinch closes the only way", {".#", "#."}, {{{0, 0}, {1, 1}}});
  add("pinch in a corridor", {"..#..", "...#.", "....."}, {{{4, 0}, {0, 0}}});
  add("one-cell gap", {".....", "##.##", "....."}, {{{0, 0}, {0, 2}}, {{4, 0}, {0, 2}}});
  add("wall without a gap", {".....", "#####", "....."}, {{{0, 0}, {4, 2}}});
  add("corner-touching chain", {"....", ".#..", "..#.", "...."},
      {{{0, 3}, {3, 0}}, {{0, 0}, {3, 3}}, {{3, 0}, {0, 3}}});
  add("start beside a corner", {"......", "..##..", "..##..", "......"},
      {{{1, 0}, {4, 3}}, {{1, 3}, {4, 0}}, {{0, 1}, {5, 2}}});
  add("along the map border", {"#....#", "......", "#....#"}, {{{0, 1}, {5, 1}}, {{1, 0}, {4, 2}}});
  add("unknown cells", {"..?..", "..?..", "....."}, {{{0, 0}, {4, 0}}});
  Case unknown_free{"unknown cells, free", MakeGrid({"..?..", "..?..", "?????"}), true, {}};
  unknown_free.queries.push_back({{0, 0}, {4, 2}});
  cases.push_back(std::move(unknown_free));
  return cases;
}

// The designed cases, then kRandomMaps small random maps and kLargerMaps
// larger ones; references filled.
const std::vector<Case>& Cases() {
  static const std::vector<Case>* const cases = [] {
    auto* out = new std::vector<Case>(DesignedCases());
    std::mt19937_64 rng(20261201);
    for (int i = 0; i < kRandomMaps; ++i) {
      Case c{absl::StrFormat("random map %d", i), RandomGrid(rng, i), rng() % 4 == 0, {}};
      AddQueries(rng, c, 3);
      out->push_back(std::move(c));
    }
    for (int i = 0; i < kLargerMaps; ++i) {
      Case c{absl::StrFormat("larger map %d", i), RandomGrid(rng, i, 16, 28), rng() % 4 == 0,
             {}};
      AddQueries(rng, c, 3);
      out->push_back(std::move(c));
    }
    for (Case& c : *out) {
      ReferencePaths reference(c.grid, c.unknown_is_free);
      for (Query& q : c.queries) {
        q.reachable = Reachable(c.grid, c.unknown_is_free, q.start, q.goal);
        q.shortest = reference.Shortest(q.start, q.goal);
      }
    }
    return out;
  }();
  return *cases;
}

PlanRequest GeometricRequest(Cell s, Cell g, bool unknown_is_free) {
  CostParams cost;
  cost.cost_weight = 0.0;
  cost.connectivity = Connectivity::kEight;
  cost.unknown_is_free = unknown_is_free;
  return PlanRequest::Between(s, g, cost);
}

std::string Where(const std::string& planner, const Case& c, size_t qi, const Query& q) {
  return absl::StrFormat("%s on %s, query %d (%d, %d) -> (%d, %d)%s:\n%s", planner, c.name, qi,
                         q.start.x, q.start.y, q.goal.x, q.goal.y,
                         c.unknown_is_free ? " unknown_is_free" : "", GridText(c.grid));
}

// The polyline runs from the start centre to the goal centre and every
// segment is clear under the independent checker.
void ExpectValidPolyline(const PlanResult& r, const SegmentChecker& checker, Cell s, Cell g,
                         const std::string& where) {
  ASSERT_FALSE(r.polyline.empty()) << where;
  EXPECT_DOUBLE_EQ(r.polyline.front().x, s.x + 0.5) << where;
  EXPECT_DOUBLE_EQ(r.polyline.front().y, s.y + 0.5) << where;
  EXPECT_DOUBLE_EQ(r.polyline.back().x, g.x + 0.5) << where;
  EXPECT_DOUBLE_EQ(r.polyline.back().y, g.y + 0.5) << where;
  const auto defect = PolylineChecker(checker).FirstDefect(r.polyline);
  EXPECT_FALSE(defect.has_value()) << where << "polyline " << PolylineText(r.polyline)
                                   << ": " << defect->ToString();
  const double measured = testing::LatticePolylineLength(r.polyline);
  EXPECT_NEAR(r.length, measured, 1e-9 * (1 + measured))
      << where << "reported length vs the polyline's, " << PolylineText(r.polyline);
  ASSERT_FALSE(r.path.empty()) << where;
  EXPECT_EQ(r.path.front(), s) << where;
  EXPECT_EQ(r.path.back(), g) << where;
}

// ---------------------------------------------------------------------------
// Tests.

// The reference itself, on cases whose lengths are known by hand, so the
// planners are held to something right.
TEST(GeometricReference, KnownLengths) {
  {
    ReferencePaths r(MakeGrid({"...", ".#.", "..."}), false);
    // Around the blocked centre through corner (1, 2) or (2, 1).
    EXPECT_NEAR(r.Shortest({0, 0}, {2, 2}), 2 * std::sqrt(2.5), 1e-12);
    // Diagonal neighbours touching its corner: straight.
    EXPECT_NEAR(r.Shortest({0, 1}, {1, 0}), std::sqrt(2.0), 1e-12);
  }
  {
    ReferencePaths r(MakeGrid({".....", "##.##", "....."}), false);
    // Through the gap: (0.5, 0.5) -> (2, 1) -> (2, 2) -> (0.5, 2.5).
    EXPECT_NEAR(r.Shortest({0, 0}, {0, 2}), 1 + 2 * std::sqrt(2.5), 1e-12);
  }
  {
    ReferencePaths r(MakeGrid({".#", "#."}), false);
    EXPECT_EQ(r.Shortest({0, 0}, {1, 1}), kInf);
  }
  {
    // The straight line (0.5, 3.5) -> (3.5, 0.5) passes the pinch at
    // (2, 2): around (1,1)'s free corner (1, 2)... whichever way, longer.
    ReferencePaths r(MakeGrid({"....", ".#..", "..#.", "...."}), false);
    EXPECT_GT(r.Shortest({0, 3}, {3, 0}), 3 * std::sqrt(2.0) + 1e-6);
    // (0.5, 0.5) -> (3.5, 3.5) crosses both blocked cells: around them
    // through corners (2, 1) and (3, 2): sqrt(2.5) + sqrt(2) + sqrt(2.5).
    EXPECT_NEAR(r.Shortest({0, 0}, {3, 3}), 2 * std::sqrt(2.5) + std::sqrt(2.0), 1e-12);
  }
}

TEST(GeometricReference, AgreesWithReachability) {
  int reachable = 0, unreachable = 0;
  for (const Case& c : Cases()) {
    for (size_t i = 0; i < c.queries.size(); ++i) {
      const Query& q = c.queries[i];
      ASSERT_EQ(q.reachable, q.shortest < kInf) << Where("reference", c, i, q);
      (q.reachable ? reachable : unreachable)++;
      if (q.reachable) {
        ASSERT_GE(q.shortest, CentreDistance(q.start, q.goal) - 1e-12);
      }
    }
  }
  std::printf("%zu cases: %d reachable queries, %d unreachable\n", Cases().size(),
              reachable, unreachable);
  EXPECT_GT(unreachable, 500);
  EXPECT_GT(reachable, 5000);
}

// The brute-force octile clearance against the core's exact Euclidean
// distance transform (core/map/euclidean_distance.h, blocked cells and the
// outside as sources): never below it and at most 8.3% above it
// (octile / Euclidean <= sqrt(4 - 2 sqrt(2))), on every cell of every case.
TEST(GeometricReference, OctileClearanceBracketsTheEuclideanField) {
  EuclideanDistanceField edt;
  for (const Case& c : Cases()) {
    DistanceSources sources;
    for (int v = 0; v < 256; ++v) {
      sources.by_cost[v] = !Traversable(static_cast<uint8_t>(v), c.unknown_is_free);
    }
    sources.border = true;
    const std::vector<int64_t>& squared = edt.Compute(c.grid, sources);
    const std::vector<double> field = ClearanceField(c.grid, c.unknown_is_free);
    for (size_t i = 0; i < c.grid.size(); ++i) {
      const double euclidean = std::sqrt(static_cast<double>(squared[i]));
      ASSERT_GE(field[i], euclidean - 1e-12) << c.name << " cell " << i;
      ASSERT_LE(field[i], euclidean * 1.0824 + 1e-12) << c.name << " cell " << i;
    }
  }
}

class GeometricPlanner : public ::testing::TestWithParam<std::string> {};

#define PLANNER_OR_SKIP(var, name)                                                 \
  const Planner* var = PlannerRegistry::Default().Get(name);                       \
  if (var == nullptr) {                                                            \
    GTEST_SKIP() << "planner '" << (name) << "' is not registered (not merged yet)"; \
  }

// Every answer on every case against the references (see the file comment
// for what each kind of planner is held to).
TEST_P(GeometricPlanner, RandomAndDesignedMaps) {
  const std::string name = GetParam();
  PLANNER_OR_SKIP(planner, name);
  PLANNER_OR_SKIP(theta, "theta_star");
  PLANNER_OR_SKIP(astar, "astar");
  const bool exact = IsExact(name);
  const bool is_voronoi = name == "voronoi";
  ASSERT_TRUE(planner->traits().geometric || is_voronoi) << name;
  SearchScratch scratch;
  int found = 0, checked = 0;
  for (const Case& c : Cases()) {
    const SegmentChecker checker(c.grid, c.unknown_is_free);
    std::vector<double> field;
    if (is_voronoi) field = ClearanceField(c.grid, c.unknown_is_free);
    for (size_t qi = 0; qi < c.queries.size(); ++qi) {
      const Query& q = c.queries[qi];
      const std::string where = Where(name, c, qi, q);
      const PlanRequest request = GeometricRequest(q.start, q.goal, c.unknown_is_free);
      auto r = planner->Plan(c.grid, request, StopCondition::None(), scratch);
      ASSERT_TRUE(r.ok()) << where << r.status();
      ++checked;
      if (planner->traits().complete || exact) {
        ASSERT_EQ(r->found(), q.reachable)
            << where << "found " << r->found() << " (" << PlanOutcomeName(r->outcome)
            << "), a path exists " << q.reachable;
      } else if (!q.reachable) {
        ASSERT_FALSE(r->found()) << where;
      }
      if (!r->found()) continue;
      ++found;
      if (is_voronoi) {
        const int bad = FirstIllegalStep(c.grid, c.unknown_is_free, r->path);
        ASSERT_EQ(bad, -1) << where << "illegal step at path index " << bad;
        ASSERT_EQ(r->path.front(), q.start) << where;
        ASSERT_EQ(r->path.back(), q.goal) << where;
        const double clearance = PathClearance(field, c.grid, r->path);
        EXPECT_NEAR(r->min_clearance, clearance, 1e-9)
            << where << "reported min_clearance vs its path's";
        const double best =
            MaxBottleneck(field, c.grid, c.unknown_is_free, q.start, q.goal);
        EXPECT_NEAR(r->min_clearance, best, 1e-9)
            << where << "min_clearance vs the brute-force maximum bottleneck";
        auto a = astar->Plan(c.grid, request, StopCondition::None(), scratch);
        ASSERT_TRUE(a.ok() && a->found()) << where;
        EXPECT_GE(r->min_clearance, PathClearance(field, c.grid, a->path) - 1e-9)
            << where << "voronoi's clearance below A*'s path's";
        if (!r->polyline.empty()) {
          const auto defect = PolylineChecker(checker).FirstDefect(r->polyline);
          EXPECT_FALSE(defect.has_value()) << where << defect->ToString();
        }
        continue;
      }
      ExpectValidPolyline(*r, checker, q.start, q.goal, where);
      if (HasFatalFailure()) return;
      const double straight = CentreDistance(q.start, q.goal);
      EXPECT_GE(r->length, straight - 1e-9) << where << "shorter than the straight line";
      if (exact) {
        EXPECT_NEAR(r->length, q.shortest, 1e-9 * (1 + q.shortest))
            << where << "length " << r->length << " vs reference " << q.shortest
            << ", polyline " << PolylineText(r->polyline);
        auto t = theta->Plan(c.grid, request, StopCondition::None(), scratch);
        ASSERT_TRUE(t.ok() && t->found()) << where << "theta_star";
        EXPECT_LE(r->length, t->length + 1e-9)
            << where << "longer than theta_star's " << t->length;
      } else {
        EXPECT_GE(r->length, q.shortest - 1e-9 * (1 + q.shortest))
            << where << "shorter than the exact shortest path " << q.shortest;
      }
      if (HasFailure()) return;  // one map's worth of messages is enough
    }
  }
  std::printf("%s: %d queries, %d found\n", name.c_str(), checked, found);
}

// The exact planners agree with each other on every query (a consequence
// of each matching the reference; checked directly so a missing reference
// case cannot hide a disagreement).
TEST(ExactPlanners, AgreeWithEachOther) {
  std::vector<const Planner*> planners;
  std::vector<std::string> missing;
  for (const std::string& name : ExactPlanners()) {
    if (const Planner* p = PlannerRegistry::Default().Get(name)) {
      planners.push_back(p);
    } else {
      missing.push_back(name);
    }
  }
  SearchScratch scratch;
  int compared = 0;
  for (const Case& c : Cases()) {
    for (size_t qi = 0; qi < c.queries.size() && planners.size() >= 2; ++qi) {
      const Query& q = c.queries[qi];
      const PlanRequest request = GeometricRequest(q.start, q.goal, c.unknown_is_free);
      std::vector<PlanResult> results;
      for (const Planner* p : planners) {
        auto r = p->Plan(c.grid, request, StopCondition::None(), scratch);
        ASSERT_TRUE(r.ok()) << Where(std::string(p->name()), c, qi, q) << r.status();
        results.push_back(*std::move(r));
      }
      for (size_t k = 1; k < results.size(); ++k) {
        const std::string where = Where(
            absl::StrFormat("%s vs %s", planners[0]->name(), planners[k]->name()), c, qi, q);
        ASSERT_EQ(results[0].found(), results[k].found()) << where;
        if (!results[0].found()) continue;
        ASSERT_NEAR(results[0].length, results[k].length, 1e-6 * results[0].length + 1e-12)
            << where << PolylineText(results[0].polyline) << " vs "
            << PolylineText(results[k].polyline);
      }
      ++compared;
    }
  }
  std::printf("%zu exact planners compared on %d queries\n", planners.size(), compared);
  if (!missing.empty()) {
    GTEST_SKIP() << "not registered (not merged yet): " << absl::StrJoin(missing, ", ");
  }
}

// Random map-update sequences: after every update the planner answers on a
// structure the AdvancingStore advanced from the previous version exactly
// as on a fresh build (a null store): the same found, the same length to
// 1e-9, and a clear polyline.
TEST_P(GeometricPlanner, AdvancedStructuresAnswerLikeFreshBuilds) {
  const std::string name = GetParam();
  PLANNER_OR_SKIP(planner, name);
  std::mt19937_64 rng(99);
  SearchScratch scratch;
  AdvancingStore::Stats total;
  int compared = 0;
  for (int sequence = 0; sequence < 400; ++sequence) {
    Grid grid = RandomGrid(rng, sequence);
    const bool unknown_is_free = sequence % 5 == 0;
    AdvancingStore store(AdvancingStore::Options{sequence % 2 == 1});
    for (int step = 0; step < 12; ++step) {
      if (step > 0) {
        // 1-4 cells flipped, sometimes a small rectangle.
        const int flips = 1 + static_cast<int>(rng() % 4);
        for (int k = 0; k < flips; ++k) {
          const Cell c{static_cast<int32_t>(rng() % grid.width()),
                       static_cast<int32_t>(rng() % grid.height())};
          grid.set_cost(c, Traversable(grid.cost(c), false) ? kLethalCost : kFreeCost);
        }
        if (rng() % 4 == 0) {
          const int x0 = static_cast<int>(rng() % grid.width());
          const int y0 = static_cast<int>(rng() % grid.height());
          const uint8_t v = rng() % 2 == 0 ? kLethalCost : kFreeCost;
          for (int y = y0; y < std::min(grid.height(), y0 + 2); ++y) {
            for (int x = x0; x < std::min(grid.width(), x0 + 3); ++x) grid.set_cost(x, y, v);
          }
        }
      }
      store.SetGrid(grid);
      const SegmentChecker checker(grid, unknown_is_free);
      for (int q = 0; q < 3; ++q) {
        const auto s = RandomFreeCell(rng, grid, unknown_is_free, q == 0);
        const auto g = RandomFreeCell(rng, grid, unknown_is_free, false);
        if (!s || !g) break;
        PlanRequest fresh_request = GeometricRequest(*s, *g, unknown_is_free);
        PlanRequest advanced_request = fresh_request;
        advanced_request.derived = &store;
        auto fresh = planner->Plan(grid, fresh_request, StopCondition::None(), scratch);
        auto advanced = planner->Plan(grid, advanced_request, StopCondition::None(), scratch);
        const Case here{absl::StrFormat("sequence %d step %d", sequence, step), grid,
                        unknown_is_free, {}};
        const std::string where = Where(name, here, q, Query{*s, *g});
        ASSERT_TRUE(fresh.ok()) << where << fresh.status();
        ASSERT_TRUE(advanced.ok()) << where << advanced.status();
        ASSERT_EQ(advanced->found(), fresh->found()) << where << "advanced vs fresh";
        ++compared;
        if (!fresh->found()) continue;
        ASSERT_NEAR(advanced->length, fresh->length, 1e-9 * (1 + fresh->length))
            << where << "advanced " << PolylineText(advanced->polyline) << " vs fresh "
            << PolylineText(fresh->polyline);
        if (name == "voronoi") {
          ASSERT_NEAR(advanced->min_clearance, fresh->min_clearance, 1e-9) << where;
          ASSERT_EQ(FirstIllegalStep(grid, unknown_is_free, advanced->path), -1) << where;
        } else {
          const auto defect = PolylineChecker(checker).FirstDefect(advanced->polyline);
          ASSERT_FALSE(defect.has_value()) << where << defect->ToString();
        }
      }
    }
    const AdvancingStore::Stats st = store.stats();
    total.builds += st.builds;
    total.advances += st.advances;
    total.rebuilds += st.rebuilds;
    total.hits += st.hits;
  }
  std::printf(
      "%s: %d answers compared; store: %lld builds (%lld of them rebuilds), %lld "
      "advances, %lld hits\n",
      name.c_str(), compared, static_cast<long long>(total.builds),
      static_cast<long long>(total.rebuilds), static_cast<long long>(total.advances),
      static_cast<long long>(total.hits));
  // Every geometric planner keeps a derived structure; one that never asks
  // the store compares nothing here.
  EXPECT_GT(total.builds + total.advances + total.hits, 0)
      << name << " never asked PlanRequest::derived for a structure";
}

INSTANTIATE_TEST_SUITE_P(Registry, GeometricPlanner, ::testing::ValuesIn(GeometricPlanners()),
                         [](const auto& info) { return info.param; });

// The test store itself, on a counting recipe: builds once, hits on the
// same cells, advances with exactly the cells that differ (and, padded,
// their unchanged neighbours), rebuilds when advance declines.
TEST(AdvancingStoreTest, AdvancesWithTheChangedCells) {
  struct Value {
    int builds = 0;
    int advances = 0;
    std::vector<Cell> last_changed;
  };
  DerivedRecipe recipe;
  bool decline = false;
  recipe.build = [](const Grid&, DerivedStop&) -> std::shared_ptr<const void> {
    return std::make_shared<const Value>(Value{1, 0, {}});
  };
  recipe.advance = [&](const void* previous, const Grid&, absl::Span<const Cell> changed,
                       DerivedStop&) -> std::shared_ptr<const void> {
    if (decline) return nullptr;
    const auto* p = static_cast<const Value*>(previous);
    return std::make_shared<const Value>(
        Value{p->builds, p->advances + 1, std::vector<Cell>(changed.begin(), changed.end())});
  };
  recipe.bytes = [](const void*) { return size_t{1}; };
  Grid grid = MakeGrid({"....", "....", "...."});
  AdvancingStore store;
  store.SetGrid(grid);
  auto v0 = std::static_pointer_cast<const Value>(store.Get("k", recipe));
  EXPECT_EQ(v0->builds, 1);
  store.SetGrid(grid);
  EXPECT_EQ(store.Get("k", recipe), v0);
  grid.set_cost(1, 2, kLethalCost);
  grid.set_cost(3, 0, 9);
  store.SetGrid(grid);
  auto v1 = std::static_pointer_cast<const Value>(store.Get("k", recipe));
  EXPECT_EQ(v1->advances, 1);
  ASSERT_EQ(v1->last_changed.size(), 2u);
  EXPECT_EQ(v1->last_changed[0], (Cell{3, 0}));
  EXPECT_EQ(v1->last_changed[1], (Cell{1, 2}));
  // Another key is built, not advanced.
  EXPECT_EQ(std::static_pointer_cast<const Value>(store.Get("other", recipe))->advances, 0);
  decline = true;
  grid.set_cost(0, 0, kLethalCost);
  store.SetGrid(grid);
  EXPECT_EQ(std::static_pointer_cast<const Value>(store.Get("k", recipe))->advances, 0);
  const AdvancingStore::Stats st = store.stats();
  EXPECT_EQ(st.builds, 3);
  EXPECT_EQ(st.rebuilds, 1);
  EXPECT_EQ(st.advances, 1);
  EXPECT_EQ(st.hits, 1);
  // Builds and advances are logged in order, hits are not.
  const std::vector<AdvancingStore::Event> events = store.events();
  ASSERT_EQ(events.size(), 4u);
  EXPECT_FALSE(events[0].advanced);
  EXPECT_TRUE(events[1].advanced);
  EXPECT_EQ(events[1].changed, 2u);
  EXPECT_EQ(events[2].key, "other");
  EXPECT_FALSE(events[3].advanced);
  EXPECT_EQ(events[3].bytes, 1u);

  AdvancingStore padded(AdvancingStore::Options{true});
  decline = false;
  Grid g2 = MakeGrid({"....", "....", "...."});
  padded.SetGrid(g2);
  padded.Get("k", recipe);
  g2.set_cost(0, 0, kLethalCost);
  padded.SetGrid(g2);
  auto p1 = std::static_pointer_cast<const Value>(padded.Get("k", recipe));
  // (0, 0) and its in-bounds neighbours (1, 0) and (0, 1).
  EXPECT_EQ(p1->last_changed.size(), 3u);
}

}  // namespace
}  // namespace pathd
