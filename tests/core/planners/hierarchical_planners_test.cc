// The hierarchical planners (core/planners/hierarchical). hpa_star: paths
// are legal move chains under an independent move check, found exactly when
// an independent Dijkstra reaches the goal, never cheaper than its optimum
// and within the additive bound docs/decisions.md ("HPA*") derives; the
// abstract graph advanced through random update sequences equals a rebuilt
// one node for node and edge for edge, and answers like it; hand-made maps
// whose only passage is at a cluster corner or one cell wide on a border.
// quadtree: complete, legal, never below the optimum; the tree advanced
// through update sequences that split and re-merge big leaves equals a
// rebuilt one leaf for leaf. Both on sampled Moving AI scenarios (skipped,
// saying so, without ../shared/benchmarks/movingai). PATHD_HPA_CASES=N
// caps every randomised count and the scenarios per map at N (the ASan run
// sets 6).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <memory>
#include <queue>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/map_io/map_io.h"
#include "core/planners/hierarchical/hpa_graph.h"
#include "core/planners/hierarchical/hpa_star.h"
#include "core/planners/hierarchical/quadtree.h"
#include "core/search/planner.h"
#include "core/search/registry.h"
#include "gtest/gtest.h"
#include "tests/testing/advancing_store.h"
#include "tests/testing/reference_model.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

namespace fs = std::filesystem;
using testing::Model;
using testing::AdvancingStore;

constexpr double kInf = std::numeric_limits<double>::infinity();

int Cases(int fallback) {
  const char* env = std::getenv("PATHD_HPA_CASES");
  const int scale = env != nullptr ? std::atoi(env) : 0;
  return scale > 0 ? std::min(fallback, scale) : fallback;
}

// Dijkstra from `s` with its own queue and move loop; fills `parent` so an
// optimal path can be traced. With `inside`, only moves into its cells.
std::vector<double> Reference(const Model& m, Cell s, std::vector<int>& parent,
                              const CellRect* inside = nullptr) {
  const int w = m.grid.width();
  std::vector<double> dist(m.grid.size(), kInf);
  parent.assign(m.grid.size(), -1);
  using Item = std::tuple<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  dist[s.y * w + s.x] = 0;
  open.push({0.0, s.y * w + s.x});
  while (!open.empty()) {
    const auto [d, i] = open.top();
    open.pop();
    if (d > dist[i]) continue;
    const Cell a{i % w, i / w};
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const Cell b{a.x + dx, a.y + dy};
        const double step = m.Step(a, b);
        if (step < 0) continue;
        if (inside != nullptr &&
            (b.x < inside->x0 || b.y < inside->y0 || b.x > inside->x1 || b.y > inside->y1)) {
          continue;
        }
        const int j = b.y * w + b.x;
        if (d + step < dist[j]) {
          dist[j] = d + step;
          parent[j] = i;
          open.push({dist[j], j});
        }
      }
    }
  }
  return dist;
}

// Moves of the reference's optimal path to `g` that change cluster.
int Crossings(const Grid& grid, const std::vector<int>& parent, Cell g, int c) {
  int crossings = 0;
  for (int i = static_cast<int>(grid.Index(g)); parent[i] >= 0; i = parent[i]) {
    const int w = grid.width();
    const int j = parent[i];
    if ((i % w) / c != (j % w) / c || (i / w) / c != (j / w) / c) ++crossings;
  }
  return crossings;
}

// The additive bound of docs/decisions.md: each move of an optimal path
// that changes cluster costs HPA* at most 4 (d + 1) F more, d the farthest
// an entrance cell lies from its nearest transition, F the largest factor.
double Bound(double optimum, int crossings, int c, double max_factor) {
  const int d = std::max(2, (c - 1) / 2);
  return optimum + crossings * 4.0 * (d + 1) * max_factor + 1e-5 * (1 + optimum);
}

// Checks one answer against the references; returns "" or what is wrong.
std::string Check(const Model& m, const PlanResult& r, Cell s, Cell g, double optimum,
                  int crossings, int c) {
  const bool reachable = std::isfinite(optimum);
  if (r.found() != reachable) {
    return absl::StrFormat("found=%d but reachable=%d (%s)", r.found(), reachable,
                           PlanOutcomeName(r.outcome));
  }
  if (!r.found()) return r.path.empty() ? "" : "a path without an answer";
  if (r.path.empty() || !(r.path.front() == s) || !(r.path.back() == g)) {
    return "the path does not run from start to goal";
  }
  if (r.any_angle) return "an any-angle answer";
  double cost = 0;
  for (size_t i = 1; i < r.path.size(); ++i) {
    const double step = m.Step(r.path[i - 1], r.path[i]);
    if (step < 0) {
      return absl::StrFormat("illegal move %s -> %s", CellToString(r.path[i - 1]),
                             CellToString(r.path[i]));
    }
    cost += step;
  }
  if (std::fabs(cost - r.cost) > 1e-9 * (1 + cost)) {
    return absl::StrFormat("reported cost %.12g, measured %.12g", r.cost, cost);
  }
  if (cost < optimum - 1e-9 * (1 + optimum)) {
    return absl::StrFormat("cost %.12g below the optimum %.12g", cost, optimum);
  }
  // c < 0: no bound to check (quadtree).
  const double bound = c < 0 ? kInf : Bound(optimum, crossings, c, m.MaxFactor());
  if (cost > bound) {
    return absl::StrFormat("cost %.12g over the bound %.12g (optimum %.12g, %d crossings)",
                           cost, bound, optimum, crossings);
  }
  return "";
}

Grid RandomGrid(std::mt19937& rng, int w, int h, int obstacle_pct, bool weighted) {
  Grid grid = Grid::Create(w, h).value();
  for (size_t i = 0; i < grid.size(); ++i) {
    const int roll = static_cast<int>(rng() % 100);
    uint8_t v = kFreeCost;
    if (roll < obstacle_pct) {
      v = rng() % 5 == 0 ? kUnknownCost : kLethalCost;
    } else if (weighted && rng() % 3 == 0) {
      v = static_cast<uint8_t>(rng() % 253);
    }
    grid.mutable_cells()[i] = v;
  }
  return grid;
}

CostParams RandomParams(std::mt19937& rng, int trial) {
  CostParams p;
  p.connectivity = trial % 2 ? Connectivity::kFour : Connectivity::kEight;
  p.cost_weight = trial % 5 == 0 ? 0.0 : static_cast<double>(rng() % 400) / 100.0;
  p.unknown_is_free = trial % 7 == 0;
  return p;
}

Cell RandomCell(std::mt19937& rng, const Grid& grid) {
  return Cell{static_cast<int32_t>(rng() % grid.width()),
              static_cast<int32_t>(rng() % grid.height())};
}

TEST(HpaStar, IsRegisteredCompleteAndNotOptimal) {
  const Planner* p = PlannerRegistry::Default().Get("hpa_star");
  ASSERT_NE(p, nullptr);
  EXPECT_TRUE(p->traits().complete);
  EXPECT_FALSE(p->traits().optimal);
  EXPECT_FALSE(p->traits().bounded);
  EXPECT_FALSE(p->traits().any_angle);
}

// Random weighted maps, 4- and 8-connected, cluster sides that do and do not
// divide the map: complete, legal, never below the optimum, within the bound.
TEST(HpaStar, RandomMapsAgreeWithDijkstra) {
  std::mt19937 rng(20261202);
  const int trials = Cases(600);
  int found = 0;
  for (int trial = 0; trial < trials; ++trial) {
    const int c = 2 + static_cast<int>(rng() % 7);
    const int w = 3 + static_cast<int>(rng() % 30);
    const int h = 3 + static_cast<int>(rng() % 30);
    const Grid grid =
        RandomGrid(rng, w, h, static_cast<int>(rng() % 45), trial % 3 != 0);
    const CostParams params = RandomParams(rng, trial);
    const Model m{grid, params};
    auto planner = MakeHpaStarPlanner(c);
    SearchScratch scratch;
    for (int q = 0; q < 6; ++q) {
      const Cell s = RandomCell(rng, grid);
      const Cell g = RandomCell(rng, grid);
      if (!m.Open(s.x, s.y) || !m.Open(g.x, g.y)) continue;
      std::vector<int> parent;
      const std::vector<double> dist = Reference(m, s, parent);
      const double optimum = dist[grid.Index(g)];
      auto r = planner->Plan(grid, PlanRequest::Between(s, g, params),
                             StopCondition::None(), scratch);
      ASSERT_TRUE(r.ok()) << r.status();
      const int crossings = std::isfinite(optimum) ? Crossings(grid, parent, g, c) : 0;
      const std::string fault = Check(m, *r, s, g, optimum, crossings, c);
      ASSERT_EQ(fault, "") << "trial " << trial << " cluster " << c << " " << w << "x" << h
                           << " " << CellToString(s) << " -> " << CellToString(g);
      found += r->found();
    }
  }
  EXPECT_GT(found, trials);
}

// The only way between two clusters is a cell pair at their shared corner,
// or a diagonal step across the corner of four clusters.
TEST(HpaStar, PassagesAtClusterCorners) {
  // Cluster side 4: clusters meet at x = 4 and y = 4. A wall along both
  // borders with a gap only at the corner cells (3, 3) | (4, 3).
  const Grid straight = MakeGrid({
      "...#....",
      "...#....",
      "...#....",
      "........",
      "####.###",
      "....#...",
      "....#...",
      "....#...",
  });
  // Four clusters meeting at one corner: the top-left and bottom-right ones
  // connect only through the corner cells (3, 3), (4, 3), (3, 4), (4, 4):
  // diagonally across the corner, or around it through a side cell.
  const Grid corner = MakeGrid({
      "...#####",
      "...#####",
      "...#####",
      ".....###",
      "###.....",
      "###.....",
      "###.....",
      "###.....",
  });
  // One side cell blocked: the diagonal would cut a corner, the way around
  // the other side cell remains.
  Grid one_side = corner;
  one_side.set_cost(4, 3, kLethalCost);
  // Both blocked: the diagonal alone would connect, and it cuts corners.
  Grid cut = one_side;
  cut.set_cost(3, 4, kLethalCost);
  auto planner = MakeHpaStarPlanner(4);
  SearchScratch scratch;
  for (const Grid* grid : std::vector<const Grid*>{&straight, &corner, &one_side, &cut}) {
    for (const Connectivity conn : {Connectivity::kEight, Connectivity::kFour}) {
      CostParams params;
      params.connectivity = conn;
      const Model m{*grid, params};
      for (const auto& [s, g] : {std::pair{Cell{0, 0}, Cell{7, 7}},
                                 std::pair{Cell{7, 7}, Cell{0, 0}},
                                 std::pair{Cell{0, 7}, Cell{7, 0}}}) {
        if (!m.Open(s.x, s.y) || !m.Open(g.x, g.y)) continue;
        std::vector<int> parent;
        const double optimum = Reference(m, s, parent)[grid->Index(g)];
        auto r = planner->Plan(*grid, PlanRequest::Between(s, g, params),
                               StopCondition::None(), scratch);
        ASSERT_TRUE(r.ok()) << r.status();
        const int crossings = std::isfinite(optimum) ? Crossings(*grid, parent, g, 4) : 0;
        EXPECT_EQ(Check(m, *r, s, g, optimum, crossings, 4), "")
            << CellToString(s) << " -> " << CellToString(g) << " connectivity "
            << static_cast<int>(conn);
      }
    }
  }
  // The corner maps are solvable until both side cells are blocked.
  CostParams eight;
  for (const Grid* grid : std::vector<const Grid*>{&corner, &one_side}) {
    auto r = planner->Plan(*grid, PlanRequest::Between({0, 0}, {7, 7}, eight),
                           StopCondition::None(), scratch);
    ASSERT_TRUE(r.ok());
    EXPECT_TRUE(r->found());
  }
  auto r = planner->Plan(corner, PlanRequest::Between({0, 0}, {7, 7}, eight),
                         StopCondition::None(), scratch);
  ASSERT_TRUE(r.ok());
  // (2, 2) -> (3, 3) would cut (3, 2): 9 moves, the optimum, through the side cell.
  EXPECT_LE(r->path.size(), 10u) << [&] { std::string s; for (Cell c : r->path) s += CellToString(c); return s; }();
  r = planner->Plan(cut, PlanRequest::Between({0, 0}, {7, 7}, eight), StopCondition::None(),
                    scratch);
  ASSERT_TRUE(r.ok());
  EXPECT_FALSE(r->found());
  EXPECT_EQ(r->outcome, PlanOutcome::kNoPath);
}

// A one-cell-wide gap in a wall that runs along a cluster border, at every
// position of the border: a single transition each time.
TEST(HpaStar, OneCellGapsAlongABorder) {
  auto planner = MakeHpaStarPlanner(8);
  SearchScratch scratch;
  for (int gap = 0; gap < 16; ++gap) {
    Grid grid = Grid::Create(16, 16).value();
    for (int y = 0; y < 16; ++y) {
      if (y != gap) grid.set_cost(8, y, kLethalCost);
    }
    const Model m{grid, {}};
    std::vector<int> parent;
    const double optimum = Reference(m, {0, 15 - gap}, parent)[grid.Index(15, gap)];
    auto r = planner->Plan(grid, PlanRequest::Between({0, 15 - gap}, {15, gap}),
                           StopCondition::None(), scratch);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(Check(m, *r, {0, 15 - gap}, {15, gap}, optimum,
                    Crossings(grid, parent, {15, gap}, 8), 8),
              "")
        << "gap at row " << gap;
  }
}

// Random update sequences: the graph advanced version by version equals the
// graph built from scratch, node for node and edge for edge, advances share
// the clusters nothing touched, and the planner answers the same through an
// advancing store, a scratch that advances its own copy, and a fresh build.
TEST(HpaStar, AdvancedGraphEqualsRebuiltOne) {
  std::mt19937 rng(7);
  const int sequences = Cases(40);
  for (int seq = 0; seq < sequences; ++seq) {
    const int c = 3 + static_cast<int>(rng() % 6);
    const int w = 10 + static_cast<int>(rng() % 40);
    const int h = 10 + static_cast<int>(rng() % 40);
    Grid grid = RandomGrid(rng, w, h, static_cast<int>(rng() % 35), seq % 2 == 0);
    HpaParams params;
    params.cluster_size = c;
    params.cost = RandomParams(rng, seq);
    DerivedStop never;
    std::shared_ptr<const HpaGraph> advanced = HpaGraph::Build(grid, params, never);
    ASSERT_NE(advanced, nullptr);
    auto planner = MakeHpaStarPlanner(c);
    AdvancingStore store;
    SearchScratch with_store, own_copy;
    for (int step = 0; step < 12; ++step) {
      const Grid before = grid;
      // Half the steps change a few scattered cells, half a block (which
      // may straddle borders and corners).
      if (step % 2 == 0) {
        const int n = 1 + static_cast<int>(rng() % 6);
        for (int k = 0; k < n; ++k) {
          grid.set_cost(RandomCell(rng, grid), rng() % 2 ? kLethalCost
                                                         : static_cast<uint8_t>(rng() % 253));
        }
      } else {
        const Cell at = RandomCell(rng, grid);
        const int bw = 1 + static_cast<int>(rng() % 5), bh = 1 + static_cast<int>(rng() % 5);
        const uint8_t v = rng() % 2 ? kLethalCost : kFreeCost;
        for (int y = at.y; y < std::min(h, at.y + bh); ++y) {
          for (int x = at.x; x < std::min(w, at.x + bw); ++x) grid.set_cost(x, y, v);
        }
      }
      const std::vector<Cell> changed = AdvancingStore::Diff(before, grid);
      std::shared_ptr<const HpaGraph> next = advanced->Advance(grid, changed, never);
      ASSERT_NE(next, nullptr);
      const std::shared_ptr<const HpaGraph> rebuilt = HpaGraph::Build(grid, params, never);
      ASSERT_EQ(HpaGraph::FirstDifference(*next, *rebuilt), "")
          << "sequence " << seq << " step " << step << " cluster " << c;
      // A changed cell dirties its cluster and at most the four across the
      // borders it lies on.
      int rebuilt_clusters = 0;
      for (int32_t id = 0; id < next->clusters_x() * next->clusters_y(); ++id) {
        rebuilt_clusters += !next->SharesCluster(*advanced, id);
      }
      EXPECT_LE(rebuilt_clusters, 5 * static_cast<int>(changed.size()));
      advanced = next;

      store.SetGrid(grid);
      const Model m{grid, params.cost};
      for (int q = 0; q < 3; ++q) {
        const Cell s = RandomCell(rng, grid);
        const Cell g = RandomCell(rng, grid);
        if (!m.Open(s.x, s.y) || !m.Open(g.x, g.y)) continue;
        PlanRequest request = PlanRequest::Between(s, g, params.cost);
        SearchScratch fresh;
        auto expected = planner->Plan(grid, request, StopCondition::None(), fresh);
        auto own = planner->Plan(grid, request, StopCondition::None(), own_copy);
        request.derived = &store;
        auto stored = planner->Plan(grid, request, StopCondition::None(), with_store);
        ASSERT_TRUE(expected.ok() && own.ok() && stored.ok());
        EXPECT_EQ(expected->outcome, stored->outcome);
        EXPECT_EQ(expected->path, stored->path) << "sequence " << seq << " step " << step;
        EXPECT_EQ(expected->path, own->path) << "sequence " << seq << " step " << step;
        EXPECT_EQ(expected->cost, stored->cost);
      }
    }
    EXPECT_GT(store.stats().advances, 0);
  }
}

// Every cluster's costs between its nodes are the reference Dijkstra's
// inside the cluster (the graph has its own move graph, FIFO queues on
// clusters of one factor, early stops and mirrored halves), to float
// precision; +infinity exactly where the reference finds no way.
TEST(HpaStar, IntraClusterCostsAreTheReferencesInsideEachCluster) {
  std::mt19937 rng(11);
  const int trials = Cases(80);
  int uniform_pairs = 0, weighted_pairs = 0;
  for (int trial = 0; trial < trials; ++trial) {
    const int c = 3 + static_cast<int>(rng() % 14);
    const int w = 8 + static_cast<int>(rng() % 40);
    const int h = 8 + static_cast<int>(rng() % 40);
    const Grid grid = RandomGrid(rng, w, h, static_cast<int>(rng() % 35), trial % 2 == 0);
    HpaParams params;
    params.cluster_size = c;
    params.cost = RandomParams(rng, trial);
    const Model m{grid, params.cost};
    DerivedStop never;
    const std::shared_ptr<const HpaGraph> graph = HpaGraph::Build(grid, params, never);
    ASSERT_NE(graph, nullptr);
    for (int32_t id = 0; id < graph->clusters_x() * graph->clusters_y(); ++id) {
      CellRect rect;
      graph->Bounds(id, rect.x0, rect.y0, rect.x1, rect.y1);
      --rect.x1;  // Bounds is half-open, CellRect inclusive
      --rect.y1;
      const HpaCluster& cluster = graph->cluster(id);
      const size_t k = cluster.nodes.size();
      for (size_t i = 0; i < k; ++i) {
        std::vector<int> parent;
        const std::vector<double> dist =
            Reference(m, grid.CellAt(cluster.nodes[i]), parent, &rect);
        for (size_t j = 0; j < k; ++j) {
          const double expected = dist[cluster.nodes[j]];
          const double got = cluster.intra[i * k + j];
          const std::string where =
              absl::StrFormat("trial %d cluster %d node %d -> %d", trial, id, i, j);
          if (std::isinf(expected)) {
            ASSERT_TRUE(std::isinf(got)) << where << ": " << got;
          } else {
            ASSERT_NEAR(got, expected, 1e-6 * (1 + expected)) << where;
          }
          (params.cost.cost_weight == 0 || trial % 2 != 0 ? uniform_pairs : weighted_pairs) +=
              i != j;
        }
      }
    }
  }
  EXPECT_GT(uniform_pairs, 100);
  EXPECT_GT(weighted_pairs, 100);
}

TEST(HpaStar, ExpiredDeadlineStopsTheBuild) {
  const Grid grid = Grid::Create(200, 200).value();
  auto planner = MakeHpaStarPlanner(8);
  SearchScratch scratch;
  const StopCondition stop(absl::Now() - absl::Seconds(1), nullptr, 0);
  auto r = planner->Plan(grid, PlanRequest::Between({0, 0}, {199, 199}), stop, scratch);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kTimeout);
}

TEST(Quadtree, IsRegisteredCompleteAndNotOptimal) {
  const Planner* p = PlannerRegistry::Default().Get("quadtree");
  ASSERT_NE(p, nullptr);
  EXPECT_TRUE(p->traits().complete);
  EXPECT_FALSE(p->traits().optimal);
}

// quadtree on the random maps: complete, legal, never below the optimum
// (it promises no bound).
TEST(Quadtree, RandomMapsAgreeWithDijkstra) {
  std::mt19937 rng(20261203);
  const int trials = Cases(600);
  const Planner* planner = PlannerRegistry::Default().Get("quadtree");
  SearchScratch scratch;
  int found = 0;
  for (int trial = 0; trial < trials; ++trial) {
    const int w = 2 + static_cast<int>(rng() % 40);
    const int h = 2 + static_cast<int>(rng() % 40);
    // Half the maps mostly open, so leaves grow past single cells.
    const int obstacle_pct = trial % 2 ? static_cast<int>(rng() % 45) : 3;
    const Grid grid = RandomGrid(rng, w, h, obstacle_pct, trial % 3 == 0);
    const CostParams params = RandomParams(rng, trial);
    const Model m{grid, params};
    for (int q = 0; q < 6; ++q) {
      const Cell s = RandomCell(rng, grid);
      const Cell g = RandomCell(rng, grid);
      if (!m.Open(s.x, s.y) || !m.Open(g.x, g.y)) continue;
      std::vector<int> parent;
      const double optimum = Reference(m, s, parent)[grid.Index(g)];
      auto r = planner->Plan(grid, PlanRequest::Between(s, g, params), StopCondition::None(),
                             scratch);
      ASSERT_TRUE(r.ok()) << r.status();
      ASSERT_EQ(Check(m, *r, s, g, optimum, 0, -1), "")
          << "trial " << trial << " " << w << "x" << h << " " << CellToString(s) << " -> "
          << CellToString(g);
      found += r->found();
    }
  }
  EXPECT_GT(found, trials);
}

// Random update sequences on mostly open maps (big leaves that updates
// split, and blocks that merge back): the advanced tree equals a rebuilt
// one leaf for leaf, and the planner answers alike through an advancing
// store, the scratch's own copy and a fresh build.
TEST(Quadtree, AdvancedTreeEqualsRebuiltOne) {
  std::mt19937 rng(11);
  const int sequences = Cases(24);
  const Planner* planner = PlannerRegistry::Default().Get("quadtree");
  for (int seq = 0; seq < sequences; ++seq) {
    // Every eighth map spans several of the tree's 256-cell tiles.
    const int w = (seq % 8 == 1 ? 260 : 10) + static_cast<int>(rng() % 90);
    const int h = (seq % 8 == 1 ? 260 : 10) + static_cast<int>(rng() % 90);
    // Two in three maps start empty, so leaves are large, split under
    // updates and merge back when a step restores the first map.
    Grid grid = seq % 3 == 0 ? RandomGrid(rng, w, h, 20, seq % 2 == 0)
                             : Grid::Create(w, h).value();
    const Grid first = grid;
    const bool unknown_is_free = seq % 4 == 0;
    DerivedStop never;
    std::shared_ptr<const Quadtree> advanced = Quadtree::Build(grid, unknown_is_free, never);
    ASSERT_NE(advanced, nullptr);
    AdvancingStore store;
    SearchScratch with_store, own_copy;
    CostParams params = RandomParams(rng, seq);
    params.unknown_is_free = unknown_is_free;
    for (int step = 0; step < 15; ++step) {
      const Grid before = grid;
      if (step % 5 == 4) {
        grid = first;
      } else if (step % 3 == 0) {
        const int n = 1 + static_cast<int>(rng() % 6);
        for (int k = 0; k < n; ++k) {
          grid.set_cost(RandomCell(rng, grid), rng() % 2 ? kLethalCost : kFreeCost);
        }
      } else {
        // Blocks, half of them cleared to free (merging leaves again).
        const Cell at = RandomCell(rng, grid);
        const int bw = 1 + static_cast<int>(rng() % 20), bh = 1 + static_cast<int>(rng() % 20);
        const uint8_t v = rng() % 2 ? kLethalCost : kFreeCost;
        for (int y = at.y; y < std::min(h, at.y + bh); ++y) {
          for (int x = at.x; x < std::min(w, at.x + bw); ++x) grid.set_cost(x, y, v);
        }
      }
      const std::vector<Cell> changed = AdvancingStore::Diff(before, grid);
      std::shared_ptr<const Quadtree> next = advanced->Advance(grid, changed);
      ASSERT_NE(next, nullptr);
      const std::shared_ptr<const Quadtree> rebuilt =
          Quadtree::Build(grid, unknown_is_free, never);
      ASSERT_EQ(Quadtree::FirstDifference(*next, *rebuilt), "")
          << "sequence " << seq << " step " << step;
      advanced = next;
      store.SetGrid(grid);
      const Model m{grid, params};
      for (int q = 0; q < 3; ++q) {
        const Cell s = RandomCell(rng, grid);
        const Cell g = RandomCell(rng, grid);
        if (!m.Open(s.x, s.y) || !m.Open(g.x, g.y)) continue;
        PlanRequest request = PlanRequest::Between(s, g, params);
        SearchScratch fresh;
        auto expected = planner->Plan(grid, request, StopCondition::None(), fresh);
        auto own = planner->Plan(grid, request, StopCondition::None(), own_copy);
        request.derived = &store;
        auto stored = planner->Plan(grid, request, StopCondition::None(), with_store);
        ASSERT_TRUE(expected.ok() && own.ok() && stored.ok());
        EXPECT_EQ(expected->path, stored->path) << "sequence " << seq << " step " << step;
        EXPECT_EQ(expected->path, own->path) << "sequence " << seq << " step " << step;
      }
    }
    EXPECT_GT(store.stats().advances, 0);
  }
}

fs::path BenchmarkDir() {
  if (const char* env = std::getenv("PATHD_MOVINGAI_DIR")) return env;
  return "../shared/benchmarks/movingai";
}

// One map of each Moving AI type, scenarios spread over the whole file:
// complete, legal, never below Dijkstra, within the bound.
TEST(HpaStar, SampledMovingAiScenarios) {
  const std::vector<std::string> maps = {
      "dao/arena2.map",        "bg512/AR0011SR.map",    "maze/maze512-4-0.map",
      "random/random512-25-0.map", "room/32room_000.map", "street/Berlin_0_512.map"};
  if (!fs::is_directory(BenchmarkDir())) {
    GTEST_SKIP() << "Moving AI benchmarks not found at " << BenchmarkDir();
  }
  const int per_map = Cases(20);
  const Planner* hpa = PlannerRegistry::Default().Get("hpa_star");
  const Planner* quadtree = PlannerRegistry::Default().Get("quadtree");
  // A*, checked against Dijkstra and the files' optima by
  // movingai_conformance_test, at a fraction of Dijkstra's time.
  const Planner* dijkstra = PlannerRegistry::Default().Get("astar");
  SearchScratch scratch;
  int checked = 0;
  for (const std::string& name : maps) {
    const fs::path path = BenchmarkDir() / name;
    if (!fs::exists(path)) continue;
    auto grid = ReadMovingAiMapFile(path.string());
    ASSERT_TRUE(grid.ok()) << grid.status();
    auto file = ReadMovingAiScenarioFileWithVersion(path.string() + ".scen");
    ASSERT_TRUE(file.ok()) << file.status();
    const size_t count = file->scenarios.size();
    const Model m{*grid, {}};
    double ratio_sum = 0, worst = 1, quad_sum = 0;
    int n = 0;
    for (int k = 0; k < per_map; ++k) {
      // Spread over the file, skipping its (short) beginning.
      const Scenario& s = file->scenarios[(2 * k + 1) * count / (2 * per_map)];
      const PlanRequest request = PlanRequest::Between(s.start, s.goal);
      auto d = dijkstra->Plan(*grid, request, StopCondition::None(), scratch);
      auto r = hpa->Plan(*grid, request, StopCondition::None(), scratch);
      ASSERT_TRUE(d.ok() && r.ok());
      ASSERT_TRUE(d->found());
      std::vector<int> parent(grid->size(), -1);
      for (size_t i = 1; i < d->path.size(); ++i) {
        parent[grid->Index(d->path[i])] = static_cast<int>(grid->Index(d->path[i - 1]));
      }
      const int crossings = Crossings(*grid, parent, s.goal, kHpaDefaultClusterSize);
      ASSERT_EQ(Check(m, *r, s.start, s.goal, d->cost, crossings, kHpaDefaultClusterSize),
                "")
          << name << " line " << s.line;
      auto quad = quadtree->Plan(*grid, request, StopCondition::None(), scratch);
      ASSERT_TRUE(quad.ok());
      ASSERT_EQ(Check(m, *quad, s.start, s.goal, d->cost, 0, -1), "")
          << "quadtree " << name << " line " << s.line;
      quad_sum += quad->cost / std::max(d->cost, 1e-9);
      if (d->cost > 0) {
        ratio_sum += r->cost / d->cost;
        worst = std::max(worst, r->cost / d->cost);
        ++n;
      }
      ++checked;
    }
    std::printf("%-28s %3d scenarios, hpa_star cost / optimum mean %.4f max %.4f, "
                "quadtree mean %.4f\n",
                name.c_str(), n, n > 0 ? ratio_sum / n : 0.0, worst,
                n > 0 ? quad_sum / n : 0.0);
  }
  if (checked == 0) GTEST_SKIP() << "none of the sampled maps is present";
}

}  // namespace
}  // namespace pathd
