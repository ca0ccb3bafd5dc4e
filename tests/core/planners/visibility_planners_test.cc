// visibility_graph, minimal_construct and euclidean_spm against a brute
// force (Dijkstra over the complete graph of bend corners, start and goal,
// every pair tested with FreeSpace::SegmentClear) on thousands of small
// random maps, against each other, and their stop conditions.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "absl/time/clock.h"
#include "core/geometry/free_space.h"
#include "core/search/registry.h"
#include "gtest/gtest.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

const Planner& Get(const char* name) {
  const Planner* p = PlannerRegistry::Default().Get(name);
  if (p == nullptr) std::abort();
  return *p;
}

// The exact shortest distance between two points: Dijkstra over the complete
// graph of `points` (bend corners plus the two) with clear segments as edges.
double BruteForce(const FreeSpace& space, LatticePoint from, LatticePoint to) {
  std::vector<LatticePoint> points = space.BendCorners();
  points.push_back(from);
  points.push_back(to);
  const size_t n = points.size();
  std::vector<double> dist(n, kInf);
  std::vector<char> done(n, 0);
  dist[n - 2] = 0.0;
  while (true) {
    size_t u = n;
    for (size_t i = 0; i < n; ++i) {
      if (!done[i] && dist[i] < kInf && (u == n || dist[i] < dist[u])) u = i;
    }
    if (u == n) return kInf;
    if (u == n - 1) return dist[u];
    done[u] = 1;
    for (size_t v = 0; v < n; ++v) {
      const double d = dist[u] + Distance(points[u], points[v]);
      if (!done[v] && d < dist[v] && space.SegmentClear(points[u], points[v])) {
        dist[v] = d;
      }
    }
  }
}

Grid RandomMap(std::mt19937& rng) {
  const int w = 2 + static_cast<int>(rng() % 13);
  const int h = 2 + static_cast<int>(rng() % 13);
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
    // Rectangles: walls, blocks touching at corners, one-cell gaps.
    const int rects = 1 + static_cast<int>(rng() % 6);
    for (int r = 0; r < rects; ++r) {
      const int x0 = static_cast<int>(rng() % w);
      const int y0 = static_cast<int>(rng() % h);
      const int x1 = std::min(w - 1, x0 + static_cast<int>(rng() % 5));
      const int y1 = std::min(h - 1, y0 + static_cast<int>(rng() % 5));
      const uint8_t v = value();
      for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) grid.set_cost(x, y, v);
      }
    }
  }
  return grid;
}

// A free cell, preferably next to an obstacle corner.
std::optional<Cell> RandomFreeCell(const FreeSpace& space, std::mt19937& rng,
                                   bool near_obstacle) {
  std::vector<Cell> free;
  std::vector<Cell> near;
  for (int32_t y = 0; y < space.height(); ++y) {
    for (int32_t x = 0; x < space.width(); ++x) {
      if (space.Blocked(x, y)) continue;
      free.push_back({x, y});
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (x + dx >= 0 && y + dy >= 0 && x + dx < space.width() &&
              y + dy < space.height() && space.Blocked(x + dx, y + dy)) {
            near.push_back({x, y});
            dx = dy = 2;
          }
        }
      }
    }
  }
  if (free.empty()) return std::nullopt;
  if (near_obstacle && !near.empty()) return near[rng() % near.size()];
  return free[rng() % free.size()];
}

// The answer checks every planner here must pass: found exactly when the
// brute force reaches the goal, the polyline exact, clear, from centre to
// centre, with the brute force's length.
void ExpectExact(const Planner& planner, const Grid& grid, Cell s, Cell g,
                 const CostParams& params, int trial, PlanResult* out = nullptr) {
  SearchScratch scratch;
  const auto r = planner.Plan(grid, PlanRequest::Between(s, g, params),
                              StopCondition::None(), scratch);
  ASSERT_TRUE(r.ok()) << r.status();
  const FreeSpace space(grid, params.unknown_is_free);
  const double want = BruteForce(space, CentreOf(s), CentreOf(g));
  ASSERT_EQ(r->found(), want < kInf)
      << planner.name() << " trial " << trial << " " << CellToString(s) << " -> "
      << CellToString(g);
  if (out != nullptr) *out = *r;
  if (!r->found()) {
    EXPECT_EQ(r->outcome, PlanOutcome::kNoPath);
    return;
  }
  std::vector<LatticePoint> polyline;
  for (CellPoint p : r->polyline) {
    const std::optional<LatticePoint> lp = ToLatticePoint(p);
    ASSERT_TRUE(lp.has_value());
    polyline.push_back(*lp);
  }
  ASSERT_FALSE(polyline.empty());
  EXPECT_EQ(polyline.front(), CentreOf(s));
  EXPECT_EQ(polyline.back(), CentreOf(g));
  EXPECT_TRUE(space.PolylineClear(polyline)) << planner.name() << " trial " << trial;
  EXPECT_NEAR(r->length, want, 1e-9 * (1 + want))
      << planner.name() << " trial " << trial << " " << CellToString(s) << " -> "
      << CellToString(g);
  EXPECT_NEAR(r->length, PolylineLength(polyline), 1e-12 * (1 + want));
  EXPECT_EQ(r->path.front(), s);
  EXPECT_EQ(r->path.back(), g);
  EXPECT_FALSE(r->any_angle);
}

TEST(VisibilityPlannersTest, ExactOnRandomMaps) {
  std::mt19937 rng(2026);
  int found = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Grid grid = RandomMap(rng);
    CostParams params;
    params.unknown_is_free = trial % 5 == 0;
    const FreeSpace space(grid, params.unknown_is_free);
    const auto s = RandomFreeCell(space, rng, trial % 2 == 0);
    const auto g = RandomFreeCell(space, rng, trial % 3 == 0);
    if (!s || !g) continue;
    PlanResult vg;
    ExpectExact(Get("visibility_graph"), grid, *s, *g, params, trial, &vg);
    ExpectExact(Get("minimal_construct"), grid, *s, *g, params, trial);
    ExpectExact(Get("euclidean_spm"), grid, *s, *g, params, trial);
    if (HasFatalFailure()) return;
    found += vg.found() ? 1 : 0;
  }
  EXPECT_GT(found, 800);
}

// minimal_construct and visibility_graph agree (length) on larger maps the
// brute force would be slow on.
TEST(VisibilityPlannersTest, MinimalConstructEqualsVisibilityGraph) {
  std::mt19937 rng(99);
  SearchScratch scratch;
  for (int trial = 0; trial < 150; ++trial) {
    const int w = 20 + static_cast<int>(rng() % 30);
    const int h = 20 + static_cast<int>(rng() % 30);
    Grid grid = Grid::Create(w, h).value();
    for (int r = 0; r < 25; ++r) {
      const int x0 = static_cast<int>(rng() % w);
      const int y0 = static_cast<int>(rng() % h);
      const int x1 = std::min(w - 1, x0 + static_cast<int>(rng() % 6));
      const int y1 = std::min(h - 1, y0 + static_cast<int>(rng() % 6));
      for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) grid.set_cost(x, y, kLethalCost);
      }
    }
    const FreeSpace space(grid, false);
    const auto s = RandomFreeCell(space, rng, false);
    const auto g = RandomFreeCell(space, rng, false);
    if (!s || !g) continue;
    const PlanRequest request = PlanRequest::Between(*s, *g);
    const auto vg = Get("visibility_graph").Plan(grid, request, StopCondition::None(), scratch);
    const auto mc = Get("minimal_construct").Plan(grid, request, StopCondition::None(), scratch);
    ASSERT_TRUE(vg.ok() && mc.ok());
    ASSERT_EQ(vg->found(), mc->found()) << "trial " << trial;
    if (!vg->found()) continue;
    EXPECT_NEAR(vg->length, mc->length, 1e-9 * (1 + vg->length)) << "trial " << trial;
  }
}

// Every start on a map against one goal's shortest path map.
TEST(VisibilityPlannersTest, EuclideanSpmEqualsVisibilityGraphForEveryStart) {
  const Grid grid = MakeGrid({"..........", "..##......", "..##...#..",
                              "......#...", ".#...#....", "..#.......",
                              "....####..", ".......#..", "..?....#..",
                              ".........."});
  SearchScratch scratch;
  for (bool unknown_is_free : {false, true}) {
    CostParams params;
    params.unknown_is_free = unknown_is_free;
    const FreeSpace space(grid, unknown_is_free);
    const Cell goal{9, 0};
    for (int32_t y = 0; y < grid.height(); ++y) {
      for (int32_t x = 0; x < grid.width(); ++x) {
        if (space.Blocked(x, y)) continue;
        const PlanRequest request = PlanRequest::Between({x, y}, goal, params);
        const auto vg = Get("visibility_graph").Plan(grid, request, StopCondition::None(), scratch);
        const auto spm = Get("euclidean_spm").Plan(grid, request, StopCondition::None(), scratch);
        ASSERT_TRUE(vg.ok() && spm.ok());
        ASSERT_EQ(vg->found(), spm->found());
        if (vg->found()) {
          EXPECT_NEAR(vg->length, spm->length, 1e-9) << x << "," << y;
        }
      }
    }
  }
}

TEST(VisibilityPlannersTest, PathsTouchCornersButNeverPassPinches) {
  // Straight past a block's corner, touching it.
  const Grid touch = MakeGrid({"....", ".#..", "....", "...."});
  // The only gap is a pinch between two blocks: no path.
  const Grid pinch = MakeGrid({"..#.", "..#.", "##..", "...."});
  for (const char* name : {"visibility_graph", "minimal_construct", "euclidean_spm"}) {
    SearchScratch scratch;
    auto r = Get(name).Plan(touch, PlanRequest::Between({0, 0}, {3, 3}),
                            StopCondition::None(), scratch);
    ASSERT_TRUE(r.ok());
    ASSERT_TRUE(r->found()) << name;
    // The diagonal crosses the block; the path bends at its corner (2, 1)
    // or (1, 2), touching the block there.
    EXPECT_NEAR(r->length, std::sqrt(2.5) + std::sqrt(8.5), 1e-12) << name;
    EXPECT_EQ(r->polyline.size(), 3u) << name;
    r = Get(name).Plan(pinch, PlanRequest::Between({0, 0}, {3, 3}),
                       StopCondition::None(), scratch);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->outcome, PlanOutcome::kNoPath) << name;
  }
}

TEST(VisibilityPlannersTest, WeightedAndFourConnectedRequestsAreRefused) {
  const Grid grid = MakeGrid({"...", ".5.", "..."});
  CostParams four;
  four.connectivity = Connectivity::kFour;
  for (const char* name : {"visibility_graph", "minimal_construct", "euclidean_spm"}) {
    SearchScratch scratch;
    auto r = Get(name).Plan(grid, PlanRequest::Between({0, 0}, {2, 2}),
                            StopCondition::None(), scratch);
    EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition) << name;
    EXPECT_NE(r.status().message().find(name), std::string::npos) << r.status();
    r = Get(name).Plan(MakeGrid({"..", ".."}), PlanRequest::Between({0, 0}, {1, 1}, four),
                       StopCondition::None(), scratch);
    EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition) << name;
  }
}

TEST(VisibilityPlannersTest, StopConditions) {
  // Staggered blocks so every planner bends many times.
  Grid grid = Grid::Create(60, 60).value();
  for (int32_t y = 3; y < 60; y += 6) {
    for (int32_t x = 0; x < 57; ++x) grid.set_cost((y / 6) % 2 == 0 ? x : x + 3, y, kLethalCost);
  }
  for (const char* name : {"visibility_graph", "minimal_construct", "euclidean_spm"}) {
    SearchScratch scratch;
    const PlanRequest request = PlanRequest::Between({0, 0}, {59, 59});
    auto r = Get(name).Plan(grid, request,
                            StopCondition(absl::InfiniteFuture(), nullptr, 5), scratch);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->outcome, PlanOutcome::kExpansionLimit) << name;
    EXPECT_LE(r->expansions, 5) << name;
    EXPECT_TRUE(r->polyline.empty());
    r = Get(name).Plan(grid, request, StopCondition(absl::Now() - absl::Seconds(1), nullptr, 0),
                       scratch);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->outcome, PlanOutcome::kTimeout) << name;
    std::atomic<bool> cancelled{true};
    r = Get(name).Plan(grid, request, StopCondition(absl::InfiniteFuture(), &cancelled, 0),
                       scratch);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->outcome, PlanOutcome::kCancelled) << name;
    r = Get(name).Plan(grid, request, StopCondition::None(), scratch);
    ASSERT_TRUE(r.ok());
    EXPECT_TRUE(r->found()) << name;
    EXPECT_GT(r->expansions, 5) << name;
  }
}

// A store like the server's: one value per key for one grid, counting builds.
class CountingStore final : public DerivedStore {
 public:
  explicit CountingStore(const Grid& grid) : grid_(grid) {}
  std::shared_ptr<const void> Get(const std::string& key, const DerivedRecipe& recipe,
                                  DerivedStop& stop) override {
    auto it = values_.find(key);
    if (it != values_.end()) return it->second;
    ++builds[key];
    return values_[key] = recipe.build(grid_, stop);
  }
  std::map<std::string, int> builds;

 private:
  const Grid& grid_;
  std::map<std::string, std::shared_ptr<const void>> values_;
};

TEST(VisibilityPlannersTest, DerivedValuesAreBuiltOncePerKey) {
  const Grid grid = MakeGrid({"........", "..##....", "..##..#.", "......#.", "........"});
  CountingStore store(grid);
  SearchScratch scratch;
  for (const Cell start : {Cell{0, 0}, Cell{0, 4}, Cell{7, 4}}) {
    for (const Cell goal : {Cell{7, 0}, Cell{4, 2}}) {
      PlanRequest request = PlanRequest::Between(start, goal);
      request.derived = &store;
      for (const char* name : {"visibility_graph", "minimal_construct", "euclidean_spm"}) {
        const auto with_store = Get(name).Plan(grid, request, StopCondition::None(), scratch);
        request.derived = nullptr;
        const auto without = Get(name).Plan(grid, request, StopCondition::None(), scratch);
        request.derived = &store;
        ASSERT_TRUE(with_store.ok() && without.ok());
        ASSERT_TRUE(with_store->found()) << name;
        EXPECT_EQ(with_store->polyline.size(), without->polyline.size()) << name;
        EXPECT_DOUBLE_EQ(with_store->length, without->length) << name;
      }
    }
  }
  EXPECT_EQ(store.builds["free_space unknown_is_free=0"], 1);
  EXPECT_EQ(store.builds["visibility_graph unknown_is_free=0"], 1);
  EXPECT_EQ(store.builds["obstacle_corners unknown_is_free=0"], 1);
  EXPECT_EQ(store.builds["euclidean_spm goal=7,0 unknown_is_free=0"], 1);
  EXPECT_EQ(store.builds["euclidean_spm goal=4,2 unknown_is_free=0"], 1);
  EXPECT_EQ(store.builds.size(), 5u);
}

}  // namespace
}  // namespace pathd
