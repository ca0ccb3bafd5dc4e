// The trapezoidal decomposition against its definition, built independently
// on small random maps: vertical extensions walked from every obstacle vertex
// cut the free cells into regions that must be exactly the trapezoids, and
// every pair of regions sharing a unit edge must be joined by exactly one
// portal. The funnel against a brute-force shortest path in its channel.
#include "core/geometry/trapezoidal.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "core/geometry/free_space.h"
#include "core/geometry/structure.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/stop_condition.h"
#include "absl/time/clock.h"
#include "gtest/gtest.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

Grid RandomGrid(std::mt19937& rng, int w, int h, int obstacle_pct) {
  Grid grid = Grid::Create(w, h).value();
  for (uint8_t& v : grid.mutable_cells()) {
    v = static_cast<int>(rng() % 100) < obstacle_pct ? kLethalCost : kFreeCost;
  }
  return grid;
}

// Region labels of the free cells (-1 blocked): 4-connected components once
// every vertical extension is a wall. An extension starts at a grid corner
// with exactly one blocked cell among its four and runs up or down along the
// grid line while both cells beside it are free.
std::vector<int> BruteRegions(const Grid& grid, int& regions) {
  const int w = grid.width();
  const int h = grid.height();
  auto free = [&](int x, int y) {
    return grid.InBounds(x, y) && grid.cost(x, y) == kFreeCost;
  };
  // cut[y * (w + 1) + x]: the unit edge between (x-1, y) and (x, y) is cut.
  std::vector<bool> cut(static_cast<size_t>(w + 1) * h, false);
  for (int y = 0; y <= h; ++y) {
    for (int x = 0; x <= w; ++x) {
      const int blocked =
          !free(x - 1, y - 1) + !free(x, y - 1) + !free(x - 1, y) + !free(x, y);
      if (blocked != 1) continue;
      for (int r = y; free(x - 1, r) && free(x, r); ++r)
        cut[r * (w + 1) + x] = true;
      for (int r = y - 1; free(x - 1, r) && free(x, r); --r)
        cut[r * (w + 1) + x] = true;
    }
  }
  std::vector<int> label(grid.size(), -1);
  regions = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (!free(x, y) || label[grid.Index(x, y)] >= 0) continue;
      std::vector<Cell> stack{{x, y}};
      label[grid.Index(x, y)] = regions;
      while (!stack.empty()) {
        const Cell c = stack.back();
        stack.pop_back();
        const std::pair<Cell, bool> next[4] = {
            {{c.x + 1, c.y}, !cut[c.y * (w + 1) + c.x + 1]},
            {{c.x - 1, c.y}, !cut[c.y * (w + 1) + c.x]},
            {{c.x, c.y + 1}, true},
            {{c.x, c.y - 1}, true}};
        for (const auto& [n, open] : next) {
          if (!open || !free(n.x, n.y) || label[grid.Index(n)] >= 0) continue;
          label[grid.Index(n)] = regions;
          stack.push_back(n);
        }
      }
      ++regions;
    }
  }
  return label;
}

TEST(TrapezoidalDecomposition, MatchesTheVerticalExtensionsOnRandomMaps) {
  std::mt19937 rng(1984);
  for (int trial = 0; trial < 3000; ++trial) {
    const int w = 1 + static_cast<int>(rng() % 16);
    const int h = 1 + static_cast<int>(rng() % 16);
    const Grid grid = RandomGrid(rng, w, h, static_cast<int>(rng() % 55));
    const TrapezoidalDecomposition d(grid, false);
    int regions = 0;
    const std::vector<int> label = BruteRegions(grid, regions);
    ASSERT_EQ(static_cast<int>(d.trapezoids().size()), regions)
        << "trial " << trial;
    // Each region is one rectangle, the trapezoid covering its cells.
    std::map<int, int> region_of;  // trapezoid -> region
    std::vector<int> cells_in(regions, 0);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const int t = d.TrapezoidOf({x, y});
        ASSERT_EQ(t < 0, label[grid.Index(x, y)] < 0) << "trial " << trial;
        if (t < 0) continue;
        const Trapezoid& r = d.trapezoids()[t];
        ASSERT_TRUE(x >= r.x0 && x < r.x1 && y >= r.y0 && y < r.y1)
            << "trial " << trial;
        const auto [it, inserted] =
            region_of.emplace(t, label[grid.Index(x, y)]);
        ASSERT_EQ(it->second, label[grid.Index(x, y)]) << "trial " << trial;
        ++cells_in[t];
      }
    }
    for (size_t t = 0; t < d.trapezoids().size(); ++t) {
      const Trapezoid& r = d.trapezoids()[t];
      ASSERT_EQ(cells_in[t], (r.x1 - r.x0) * (r.y1 - r.y0))
          << "trial " << trial;
    }
    // Portals: one per pair of regions sharing unit edges on a grid line x,
    // spanning exactly those edges.
    std::map<std::pair<int, int>, std::pair<int, int>>
        expected;  // (x, left) -> rows
    std::set<std::tuple<int, int, int>> pairs;
    for (int y = 0; y < h; ++y) {
      for (int x = 1; x < w; ++x) {
        const int a = d.TrapezoidOf({x - 1, y});
        const int b = d.TrapezoidOf({x, y});
        if (a < 0 || b < 0 || a == b) continue;
        pairs.insert({x, a, b});
      }
    }
    ASSERT_EQ(d.portals().size(), pairs.size()) << "trial " << trial;
    for (size_t p = 0; p < d.portals().size(); ++p) {
      const CellBoundary& portal = d.portals()[p];
      ASSERT_TRUE(pairs.count({portal.x, portal.left, portal.right}))
          << "trial " << trial;
      ASSERT_LT(portal.y0, portal.y1);
      for (int y = portal.y0 - 1; y <= portal.y1; ++y) {
        const bool inside = y >= portal.y0 && y < portal.y1;
        const bool shared = grid.InBounds(portal.x - 1, y) &&
                            grid.InBounds(portal.x, y) &&
                            d.TrapezoidOf({portal.x - 1, y}) == portal.left &&
                            d.TrapezoidOf({portal.x, y}) == portal.right;
        ASSERT_EQ(inside, shared) << "trial " << trial << " row " << y;
      }
      const auto left = d.PortalsOf(portal.left);
      const auto right = d.PortalsOf(portal.right);
      EXPECT_NE(std::find(left.begin(), left.end(), static_cast<int32_t>(p)),
                left.end());
      EXPECT_NE(std::find(right.begin(), right.end(), static_cast<int32_t>(p)),
                right.end());
    }
  }
}

TEST(TrapezoidalDecomposition, DescribesItsCellsAsOutlines) {
  // One blocked cell in the middle: four cells (the left column, above it,
  // below it, the right column), each joined to two others.
  const Grid grid = MakeGrid({"...", ".#.", "..."});
  const auto s = DescribeStructure("decomposition", grid, false);
  ASSERT_TRUE(s.ok()) << s.status();
  EXPECT_EQ(s->kind, "decomposition");
  ASSERT_EQ(s->counts.size(), 2u);
  EXPECT_EQ(s->counts[0], (std::pair<std::string, int64_t>{"cells", 4}));
  EXPECT_EQ(s->counts[1], (std::pair<std::string, int64_t>{"adjacencies", 4}));
  EXPECT_EQ(s->segments.size(), 16u);
  EXPECT_GT(s->bytes, 0u);
}

TEST(TrapezoidalDecomposition, PinchesDoNotConnect) {
  const Grid grid = MakeGrid({".#", "#."});
  const TrapezoidalDecomposition d(grid, false);
  EXPECT_EQ(d.trapezoids().size(), 2u);
  EXPECT_TRUE(d.portals().empty());
}

TEST(TrapezoidalDecomposition, UnknownCellsFollowTheOption) {
  const Grid grid = MakeGrid({"...", ".?.", "..."});
  EXPECT_EQ(TrapezoidalDecomposition(grid, false).trapezoids().size(), 4u);
  EXPECT_EQ(TrapezoidalDecomposition(grid, true).trapezoids().size(), 1u);
}

// Exact test that segment a-b stays in the channel `cells` (closed
// rectangles in crossing order, consecutive ones sharing a portal): split at
// every rectangle side, each piece lies in a rectangle holding both its ends
// (rectangles are convex; two over the same x range never share a horizontal
// side), and consecutive pieces lie in the same or consecutive rectangles, so
// the segment passes from one to the next only through their portal, never
// through a point where two others merely touch.
bool InsideChannel(LatticePoint a, LatticePoint b,
                   const std::vector<Trapezoid>& cells) {
  const int n = static_cast<int>(cells.size());
  auto holds = [&](const Trapezoid& t, int64_t x2, int64_t num, int64_t den) {
    return x2 >= 2 * t.x0 && x2 <= 2 * t.x1 && num >= 2 * t.y0 * den &&
           num <= 2 * t.y1 * den;
  };
  // reach[i]: the part walked so far can end in rectangle i.
  std::vector<bool> reach(n, true);
  auto step = [&](const std::vector<bool>& holding) {
    std::vector<bool> next(n, false);
    bool any = false;
    for (int i = 0; i < n; ++i) {
      if (!holding[i]) continue;
      for (int j = std::max(0, i - 1); j <= std::min(n - 1, i + 1); ++j) {
        if (reach[j]) next[i] = true;
      }
      any = any || next[i];
    }
    reach = next;
    return any;
  };
  if (a.x2 == b.x2) {
    // Vertical: overlapping y spans of the same or consecutive rectangles on
    // that line, from one end to the other.
    const int64_t lo = std::min(a.y2, b.y2);
    const int64_t hi = std::max(a.y2, b.y2);
    std::vector<bool> in(n, false);
    for (int i = 0; i < n; ++i) {
      in[i] = a.x2 >= 2 * cells[i].x0 && a.x2 <= 2 * cells[i].x1 &&
              2 * cells[i].y0 <= lo && lo <= 2 * cells[i].y1;
    }
    for (bool grew = true; grew;) {
      grew = false;
      for (int i = 0; i < n; ++i) {
        if (!in[i]) continue;
        if (2 * cells[i].y0 <= lo && hi <= 2 * cells[i].y1) return true;
        for (int j = std::max(0, i - 1); j <= std::min(n - 1, i + 1); ++j) {
          const bool on_line =
              a.x2 >= 2 * cells[j].x0 && a.x2 <= 2 * cells[j].x1;
          const int64_t top = std::max(cells[i].y0, cells[j].y0);
          const int64_t bottom = std::min(cells[i].y1, cells[j].y1);
          if (!in[j] && on_line && bottom > top && 2 * bottom > lo) {
            in[j] = true;
            grew = true;
          }
        }
      }
    }
    for (int i = 0; i < n; ++i) {
      if (in[i] && 2 * cells[i].y0 <= hi && hi <= 2 * cells[i].y1) return true;
    }
    return false;
  }
  std::vector<int64_t> xs{a.x2, b.x2};
  for (const Trapezoid& t : cells) {
    for (const int64_t x :
         {2 * static_cast<int64_t>(t.x0), 2 * static_cast<int64_t>(t.x1)}) {
      if (x > std::min(a.x2, b.x2) && x < std::max(a.x2, b.x2)) xs.push_back(x);
    }
  }
  std::sort(xs.begin(), xs.end());
  // The point at doubled x has doubled y = num / den exactly.
  auto y_at = [&](int64_t x2) -> std::pair<int64_t, int64_t> {
    int64_t den = b.x2 - a.x2;
    int64_t num = a.y2 * den + (x2 - a.x2) * (b.y2 - a.y2);
    if (den < 0) {
      den = -den;
      num = -num;
    }
    return {num, den};
  };
  for (size_t k = 1; k < xs.size(); ++k) {
    const auto [n0, d0] = y_at(xs[k - 1]);
    const auto [n1, d1] = y_at(xs[k]);
    std::vector<bool> holding(n, false);
    for (int i = 0; i < n; ++i) {
      holding[i] =
          holds(cells[i], xs[k - 1], n0, d0) && holds(cells[i], xs[k], n1, d1);
    }
    if (!step(holding)) return false;
  }
  return true;
}

// Shortest path from start to goal inside the union of `cells` by Dijkstra
// over the visibility graph of start, goal and every portal end.
double BruteChannelShortest(LatticePoint start, LatticePoint goal,
                            const std::vector<Trapezoid>& cells,
                            const std::vector<Gate>& gates) {
  std::vector<LatticePoint> nodes{start, goal};
  for (const Gate& g : gates) {
    nodes.push_back(g.left);
    nodes.push_back(g.right);
  }
  std::vector<double> dist(nodes.size(),
                           std::numeric_limits<double>::infinity());
  std::vector<bool> done(nodes.size(), false);
  dist[0] = 0.0;
  for (size_t round = 0; round < nodes.size(); ++round) {
    size_t u = nodes.size();
    for (size_t i = 0; i < nodes.size(); ++i) {
      if (!done[i] && (u == nodes.size() || dist[i] < dist[u])) u = i;
    }
    if (u == nodes.size() || std::isinf(dist[u])) break;
    done[u] = true;
    for (size_t v = 0; v < nodes.size(); ++v) {
      if (done[v] || !InsideChannel(nodes[u], nodes[v], cells)) continue;
      dist[v] = std::min(dist[v], dist[u] + Distance(nodes[u], nodes[v]));
    }
  }
  return dist[1];
}

TEST(PullString, IsTheShortestPathInItsChannel) {
  std::mt19937 rng(31);
  int channels = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const int w = 2 + static_cast<int>(rng() % 14);
    const int h = 2 + static_cast<int>(rng() % 14);
    const Grid grid = RandomGrid(rng, w, h, static_cast<int>(rng() % 45));
    const TrapezoidalDecomposition d(grid, false);
    const Cell s{static_cast<int32_t>(rng() % w),
                 static_cast<int32_t>(rng() % h)};
    const Cell g{static_cast<int32_t>(rng() % w),
                 static_cast<int32_t>(rng() % h)};
    const int ts = d.TrapezoidOf(s);
    const int tg = d.TrapezoidOf(g);
    if (ts < 0 || tg < 0 || ts == tg) continue;
    // A channel: the trapezoids of a BFS path over portals (no repeats).
    std::vector<int> via(d.trapezoids().size(), -2);  // portal that reached it
    std::vector<int> queue{ts};
    via[ts] = -1;
    for (size_t head = 0; head < queue.size(); ++head) {
      const int t = queue[head];
      for (int32_t p : d.PortalsOf(t)) {
        const CellBoundary& portal = d.portals()[p];
        const int next = portal.left == t ? portal.right : portal.left;
        if (via[next] != -2) continue;
        via[next] = p;
        queue.push_back(next);
      }
    }
    if (via[tg] == -2) continue;
    std::vector<Gate> gates;
    std::vector<Trapezoid> cells{d.trapezoids()[tg]};
    for (int t = tg; t != ts;) {
      const CellBoundary& portal = d.portals()[via[t]];
      const int prev = portal.left == t ? portal.right : portal.left;
      gates.push_back(GateOf(portal, portal.left == prev));
      cells.push_back(d.trapezoids()[prev]);
      t = prev;
    }
    std::reverse(gates.begin(), gates.end());
    const std::vector<LatticePoint> path =
        PullString(CentreOf(s), CentreOf(g), gates);
    ASSERT_GE(path.size(), 2u);
    EXPECT_EQ(path.front(), CentreOf(s));
    EXPECT_EQ(path.back(), CentreOf(g));
    EXPECT_TRUE(d.space().PolylineClear(path)) << "trial " << trial;
    for (size_t i = 1; i < path.size(); ++i) {
      EXPECT_TRUE(InsideChannel(path[i - 1], path[i], cells))
          << "trial " << trial;
    }
    EXPECT_NEAR(PolylineLength(path),
                BruteChannelShortest(CentreOf(s), CentreOf(g), cells, gates),
                1e-9)
        << "trial " << trial;
    ++channels;
  }
  EXPECT_GT(channels, 1000);
}

TEST(TrapezoidalDecomposition, ABuildUnderAStopThatFiredReturnsNothing) {
  std::mt19937 rng(23);
  const Grid grid = RandomGrid(rng, 200, 150, 20);
  const StopCondition expired(absl::Now() - absl::Seconds(1), nullptr, 0);
  DerivedStop stop(expired);
  EXPECT_EQ(TrapezoidalDecomposition::Build(grid, false, stop), nullptr);
  std::atomic<bool> cancelled{true};
  const StopCondition cancel(absl::InfiniteFuture(), &cancelled, 0);
  DerivedStop cancelled_stop(cancel);
  EXPECT_EQ(TrapezoidalDecomposition::Build(grid, false, cancelled_stop), nullptr);
  EXPECT_EQ(cancelled_stop.Outcome(), PlanOutcome::kCancelled);
  // Not stopped, it is the decomposition the constructor builds.
  DerivedStop never;
  const auto built = TrapezoidalDecomposition::Build(grid, false, never);
  ASSERT_NE(built, nullptr);
  const TrapezoidalDecomposition direct(grid, false);
  EXPECT_EQ(built->trapezoids().size(), direct.trapezoids().size());
  EXPECT_EQ(built->portals(), direct.portals());
}

}  // namespace
}  // namespace pathd
