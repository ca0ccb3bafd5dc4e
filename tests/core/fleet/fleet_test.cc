// core/fleet against checkers written apart from it: table entries against
// the registry's A* run per pair, trip orders against every permutation,
// the nearest cell against a scan of the whole map, isochrone polygons
// against a Dijkstra search of the test's own and Boost.Geometry's
// point-in-polygon on every cell centre. Random cases: PATHD_FLEET_CASES
// (default 30; the ASan run takes fewer).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <numeric>
#include <queue>
#include <random>
#include <vector>

#include <boost/geometry.hpp>
#include <boost/geometry/geometries/point_xy.hpp>
#include <boost/geometry/geometries/polygon.hpp>

#include "core/fleet/isochrone.h"
#include "core/fleet/nearest.h"
#include "core/fleet/table.h"
#include "core/fleet/trip.h"
#include "core/kinematics/footprint.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/map/inflation.h"
#include "core/search/registry.h"
#include "core/search/search_scratch.h"
#include "gtest/gtest.h"

namespace pathd {
namespace {

namespace bg = boost::geometry;
constexpr double kInf = std::numeric_limits<double>::infinity();

int Cases() {
  if (const char* env = std::getenv("PATHD_FLEET_CASES")) return std::max(1, std::atoi(env));
  return 30;
}

bool Near(double a, double b) { return std::abs(a - b) <= 1e-6 * std::max(1.0, std::abs(b)); }

Grid RandomGrid(std::mt19937& rng, int w, int h, int blocked_pct, bool weighted) {
  Grid grid = Grid::Create(w, h).value();
  for (uint8_t& v : grid.mutable_cells()) {
    if (static_cast<int>(rng() % 100) < blocked_pct) {
      v = kLethalCost;
    } else if (weighted && rng() % 3 == 0) {
      v = static_cast<uint8_t>(rng() % 253);
    }
  }
  return grid;
}

std::vector<Cell> FreeCells(const Grid& grid, std::mt19937& rng, size_t count) {
  std::vector<Cell> out;
  for (int tries = 0; out.size() < count && tries < 10000; ++tries) {
    const Cell c{static_cast<int32_t>(rng() % grid.width()),
                 static_cast<int32_t>(rng() % grid.height())};
    if (Traversable(grid.cost(c), false)) out.push_back(c);
  }
  return out;
}

// ---- Table: every entry is what A* finds for that pair alone ----

TEST(FleetTable, EntriesEqualAStarForBothMethods) {
  std::mt19937 rng(21);
  const Planner* astar = PlannerRegistry::Default().Get("astar");
  ASSERT_NE(astar, nullptr);
  SearchScratch scratch;
  for (int n = 0; n < Cases(); ++n) {
    const bool weighted = n % 2 == 1;
    auto grid = std::make_shared<const Grid>(
        RandomGrid(rng, 8 + rng() % 20, 8 + rng() % 20, 25, weighted));
    CostParams cost;
    cost.connectivity = n % 3 == 0 ? Connectivity::kFour : Connectivity::kEight;
    const std::vector<Cell> sources = FreeCells(*grid, rng, 1 + rng() % 5);
    const std::vector<Cell> dests = FreeCells(*grid, rng, 1 + rng() % 5);
    if (sources.empty() || dests.empty()) continue;
    for (const TableMethod method : {TableMethod::kForward, TableMethod::kBackward}) {
      absl::StatusOr<CostTable> table =
          ComputeTable(grid, cost, sources, dests, method, {}, StopCondition::None());
      ASSERT_TRUE(table.ok()) << table.status();
      ASSERT_EQ(table->outcome, PlanOutcome::kFound);
      for (size_t i = 0; i < sources.size(); ++i) {
        for (size_t j = 0; j < dests.size(); ++j) {
          PlanRequest request;
          request.start = sources[i];
          request.goal = dests[j];
          request.cost = cost;
          absl::StatusOr<PlanResult> plan =
              astar->Plan(*grid, request, StopCondition::None(), scratch);
          ASSERT_TRUE(plan.ok()) << plan.status();
          const TableCell& e = table->at(i, j);
          SCOPED_TRACE(testing::Message() << "case " << n << " method "
                                          << static_cast<int>(method) << " pair " << i
                                          << "," << j);
          ASSERT_EQ(e.reachable, plan->found());
          if (!e.reachable) continue;
          EXPECT_TRUE(Near(e.cost, plan->cost)) << e.cost << " vs " << plan->cost;
          EXPECT_GE(e.length + 1e-9, GridDistance(sources[i], dests[j], cost.connectivity));
          // Without cell costs a path's cost is its length.
          if (!weighted) {
            EXPECT_TRUE(Near(e.length, e.cost));
          }
        }
      }
    }
  }
}

TEST(FleetTable, AutoChoosesBackwardForFewDestinations) {
  EXPECT_EQ(ChooseTableMethod(10, 3), TableMethod::kBackward);
  EXPECT_EQ(ChooseTableMethod(5, 5), TableMethod::kBackward);
  EXPECT_EQ(ChooseTableMethod(2, 9), TableMethod::kForward);
}

TEST(FleetTable, ExpansionBudgetStopsTheTable) {
  auto grid = std::make_shared<const Grid>(Grid::Create(64, 64).value());
  const std::vector<Cell> s{{0, 0}, {63, 63}};
  const std::vector<Cell> d{{63, 0}, {0, 63}, {32, 32}};
  for (const TableMethod method : {TableMethod::kForward, TableMethod::kBackward}) {
    const StopCondition stop(absl::InfiniteFuture(), nullptr, 100);
    absl::StatusOr<CostTable> table = ComputeTable(grid, CostParams{}, s, d, method, {}, stop);
    ASSERT_TRUE(table.ok()) << table.status();
    EXPECT_EQ(table->outcome, PlanOutcome::kExpansionLimit);
  }
}

// ---- Trip: optimal against every permutation; heuristics valid and bounded ----

CostMatrix RandomMatrix(std::mt19937& rng, size_t n, bool holes) {
  CostMatrix c(n, std::vector<double>(n, 0.0));
  // Points in the plane plus asymmetric noise: triangle-ish but not
  // symmetric, as pathd's costs are.
  std::vector<std::pair<double, double>> p(n);
  for (auto& q : p) q = {static_cast<double>(rng() % 100), static_cast<double>(rng() % 100)};
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = 0; j < n; ++j) {
      if (i == j) continue;
      c[i][j] = std::hypot(p[i].first - p[j].first, p[i].second - p[j].second) +
                static_cast<double>(rng() % 20);
      if (holes && rng() % 7 == 0) c[i][j] = kInf;
    }
  }
  return c;
}

// The cheapest order by trying them all: 0 first, the last fixed for
// kFixedLast.
double BruteForce(const CostMatrix& c, TripEnd end) {
  const size_t n = c.size();
  std::vector<int32_t> middle;
  for (size_t i = 1; i < n; ++i) {
    if (end == TripEnd::kFixedLast && i == n - 1) continue;
    middle.push_back(static_cast<int32_t>(i));
  }
  double best = kInf;
  do {
    std::vector<int32_t> order{0};
    order.insert(order.end(), middle.begin(), middle.end());
    if (end == TripEnd::kFixedLast) order.push_back(static_cast<int32_t>(n - 1));
    double sum = 0.0;
    for (size_t k = 0; k + 1 < order.size(); ++k) sum += c[order[k]][order[k + 1]];
    if (end == TripEnd::kRoundTrip) sum += c[order.back()][0];
    best = std::min(best, sum);
  } while (std::next_permutation(middle.begin(), middle.end()));
  return best;
}

// A permutation of 0..n-1 starting at 0 (and ending at n-1 for kFixedLast)
// whose cost, summed here, is `cost`.
void ExpectValidOrder(const CostMatrix& c, TripEnd end, const TripOrder& t) {
  const size_t n = c.size();
  ASSERT_EQ(t.order.size(), n);
  EXPECT_EQ(t.order.front(), 0);
  if (end == TripEnd::kFixedLast) {
    EXPECT_EQ(t.order.back(), static_cast<int32_t>(n - 1));
  }
  std::vector<int32_t> sorted = t.order;
  std::sort(sorted.begin(), sorted.end());
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(sorted[i], static_cast<int32_t>(i));
  double sum = 0.0;
  for (size_t k = 0; k + 1 < n; ++k) sum += c[t.order[k]][t.order[k + 1]];
  if (end == TripEnd::kRoundTrip) sum += c[t.order.back()][0];
  EXPECT_TRUE(Near(sum, t.cost)) << sum << " vs " << t.cost;
  EXPECT_LE(t.lower_bound, t.cost + 1e-9);
}

TEST(FleetTrip, HeldKarpIsOptimalAgainstAllPermutations) {
  std::mt19937 rng(7);
  for (int n = 0; n < Cases(); ++n) {
    const size_t stops = 2 + rng() % 7;  // 2..8
    const CostMatrix c = RandomMatrix(rng, stops, n % 4 == 3);
    for (const TripEnd end : {TripEnd::kRoundTrip, TripEnd::kFixedLast, TripEnd::kAny}) {
      SCOPED_TRACE(testing::Message() << "case " << n << " stops " << stops << " end "
                                      << static_cast<int>(end));
      const double best = BruteForce(c, end);
      absl::StatusOr<TripOrder> exact = SolveTrip(c, end);
      if (!std::isfinite(best)) {
        EXPECT_FALSE(exact.ok());
        continue;
      }
      ASSERT_TRUE(exact.ok()) << exact.status();
      EXPECT_TRUE(exact->exact);
      EXPECT_TRUE(Near(exact->cost, best)) << exact->cost << " vs " << best;
      ExpectValidOrder(c, end, *exact);
      // The assignment bound is a bound; the heuristic a valid order no
      // better than the optimum.
      EXPECT_LE(AssignmentBound(c, end), best + 1e-9);
      absl::StatusOr<TripOrder> heuristic = LocalSearchTrip(c, end);
      if (heuristic.ok()) {
        ExpectValidOrder(c, end, *heuristic);
        EXPECT_GE(heuristic->cost, best - 1e-9);
      }
    }
  }
}

TEST(FleetTrip, HeuristicAboveTheExactLimitIsValidAndBounded) {
  std::mt19937 rng(11);
  for (int n = 0; n < std::max(2, Cases() / 5); ++n) {
    const size_t stops = 13 + rng() % 40;
    const CostMatrix c = RandomMatrix(rng, stops, false);
    for (const TripEnd end : {TripEnd::kRoundTrip, TripEnd::kFixedLast, TripEnd::kAny}) {
      absl::StatusOr<TripOrder> t = SolveTrip(c, end);
      ASSERT_TRUE(t.ok()) << t.status();
      EXPECT_FALSE(t->exact);
      EXPECT_EQ(t->bound_method, "assignment");
      ExpectValidOrder(c, end, *t);
    }
  }
  // At 13 stops Held-Karp still runs here: the heuristic is no better.
  const CostMatrix c = RandomMatrix(rng, 13, false);
  const absl::StatusOr<TripOrder> exact = HeldKarp(c, TripEnd::kRoundTrip);
  const absl::StatusOr<TripOrder> heuristic = SolveTrip(c, TripEnd::kRoundTrip);
  ASSERT_TRUE(exact.ok() && heuristic.ok());
  EXPECT_GE(heuristic->cost, exact->cost - 1e-9);
  EXPECT_LE(heuristic->lower_bound, exact->cost + 1e-9);
}

// ---- Nearest: the ring search equals a scan of every cell ----

std::optional<Cell> ScanNearest(const Grid& grid, Cell target, double max_d,
                                const std::function<bool(Cell)>& ok) {
  std::optional<Cell> best;
  int64_t best_d2 = 0;
  for (int32_t y = 0; y < grid.height(); ++y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      const int64_t dx = x - target.x, dy = y - target.y;
      const int64_t d2 = dx * dx + dy * dy;
      if (static_cast<double>(d2) > max_d * max_d || !ok(Cell{x, y})) continue;
      if (!best.has_value() || d2 < best_d2) {  // row-major: ties keep the first
        best = Cell{x, y};
        best_d2 = d2;
      }
    }
  }
  return best;
}

TEST(FleetNearest, EqualsABruteForceScan) {
  std::mt19937 rng(3);
  for (int n = 0; n < Cases(); ++n) {
    const Grid stored = RandomGrid(rng, 6 + rng() % 30, 6 + rng() % 30, 30, false);
    const double radius = static_cast<double>(rng() % 3);
    const Grid inflated = radius > 0 ? InflateObstacles(stored, radius).value() : stored;
    const Cell target{static_cast<int32_t>(rng() % (stored.width() + 6)) - 3,
                      static_cast<int32_t>(rng() % (stored.height() + 6)) - 3};
    const double max_d = n % 3 == 0 ? 3.5 : 1000.0;
    const auto free_cell = [&](Cell c) { return Traversable(inflated.cost(c), false); };
    const std::optional<NearestCell> got =
        NearestAllowedCell(inflated, target, max_d, free_cell);
    const std::optional<Cell> want = ScanNearest(inflated, target, max_d, free_cell);
    ASSERT_EQ(got.has_value(), want.has_value()) << "case " << n;
    if (!want) continue;
    EXPECT_EQ(got->cell, *want) << "case " << n;
    EXPECT_DOUBLE_EQ(got->distance, std::hypot(want->x - target.x, want->y - target.y));
  }
}

TEST(FleetNearest, PolygonFootprintEqualsAScan) {
  std::mt19937 rng(5);
  const Footprint footprint =
      Footprint::Polygon({{-1.6, -0.7}, {1.6, -0.7}, {1.6, 0.7}, {-1.6, 0.7}}).value();
  const FootprintChecker checker = FootprintChecker::Create(footprint).value();
  for (int n = 0; n < std::max(2, Cases() / 3); ++n) {
    const Grid grid = RandomGrid(rng, 12 + rng() % 12, 12 + rng() % 12, 12, false);
    const Cell target{static_cast<int32_t>(rng() % grid.width()),
                      static_cast<int32_t>(rng() % grid.height())};
    const double yaw = (rng() % 8) * 0.785398;
    const auto fits = FootprintFits(grid, checker, yaw, false);
    const std::optional<NearestCell> got = NearestAllowedCell(grid, target, 1000.0, fits);
    const std::optional<Cell> want = ScanNearest(grid, target, 1000.0, fits);
    ASSERT_EQ(got.has_value(), want.has_value());
    if (want) {
      EXPECT_EQ(got->cell, *want);
    }
  }
}

// ---- Isochrone: the polygons hold exactly the cells within the budget ----

using BgPoint = bg::model::d2::point_xy<double>;
using BgPolygon = bg::model::polygon<BgPoint>;

// Forward costs from `start` by a plain Dijkstra of the test's own.
std::vector<double> CostsFrom(const Grid& grid, const CostParams& cost, Cell start) {
  std::vector<double> d(grid.size(), kInf);
  using E = std::pair<double, Cell>;
  auto cmp = [](const E& a, const E& b) { return a.first > b.first; };
  std::priority_queue<E, std::vector<E>, decltype(cmp)> open(cmp);
  d[grid.Index(start)] = 0.0;
  open.push({0.0, start});
  const auto ok = [&](int x, int y) {
    return grid.InBounds(x, y) && Traversable(grid.cost(x, y), cost.unknown_is_free);
  };
  while (!open.empty()) {
    const auto [g, c] = open.top();
    open.pop();
    if (g > d[grid.Index(c)]) continue;
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        if ((dx == 0 && dy == 0) || !ok(c.x + dx, c.y + dy)) continue;
        const bool diag = dx != 0 && dy != 0;
        if (diag && (cost.connectivity == Connectivity::kFour || !ok(c.x + dx, c.y) ||
                     !ok(c.x, c.y + dy))) {
          continue;
        }
        const Cell v{c.x + dx, c.y + dy};
        const double step = (diag ? std::sqrt(2.0) : 1.0) *
                            (1.0 + cost.cost_weight * grid.cost(v) / 252.0);
        if (g + step < d[grid.Index(v)]) {
          d[grid.Index(v)] = g + step;
          open.push({g + step, v});
        }
      }
    }
  }
  return d;
}

BgPolygon ToBg(const CellPolygon& p) {
  BgPolygon out;
  for (const GridCorner& v : p.exterior) out.outer().push_back(BgPoint(v.x, v.y));
  for (const auto& hole : p.holes) {
    out.inners().emplace_back();
    for (const GridCorner& v : hole) out.inners().back().push_back(BgPoint(v.x, v.y));
  }
  bg::correct(out);
  return out;
}

TEST(FleetIsochrone, PolygonsContainExactlyTheCellsWithinTheBudget) {
  std::mt19937 rng(17);
  for (int n = 0; n < Cases(); ++n) {
    const Grid grid = RandomGrid(rng, 5 + rng() % 30, 5 + rng() % 30, 10 + rng() % 30, n % 2);
    const std::vector<Cell> start = FreeCells(grid, rng, 1);
    if (start.empty()) continue;
    CostParams cost;
    cost.connectivity = n % 3 == 0 ? Connectivity::kFour : Connectivity::kEight;
    const double budget = static_cast<double>(rng() % 25);
    const Isochrone iso = ComputeIsochrone(grid, cost, start[0], budget, StopCondition::None());
    ASSERT_EQ(iso.outcome, PlanOutcome::kFound);
    const std::vector<double> d = CostsFrom(grid, cost, start[0]);
    std::vector<BgPolygon> polygons;
    double area = 0.0;
    for (const CellPolygon& p : iso.polygons) {
      polygons.push_back(ToBg(p));
      std::string why;
      EXPECT_TRUE(bg::is_valid(polygons.back(), why)) << "case " << n << ": " << why;
      area += bg::area(polygons.back());
    }
    int64_t within = 0;
    for (int32_t y = 0; y < grid.height(); ++y) {
      for (int32_t x = 0; x < grid.width(); ++x) {
        const bool want = d[grid.Index(Cell{x, y})] <= budget + 1e-9;
        within += want ? 1 : 0;
        const BgPoint centre(x + 0.5, y + 0.5);
        const bool inside = std::any_of(polygons.begin(), polygons.end(), [&](const BgPolygon& p) {
          return bg::within(centre, p);
        });
        ASSERT_EQ(inside, want) << "case " << n << " cell (" << x << ", " << y << ") cost "
                                << d[grid.Index(Cell{x, y})] << " budget " << budget;
      }
    }
    EXPECT_EQ(iso.reachable_cells, within);
    // The polygons are the cells' squares: their area is the cell count.
    EXPECT_NEAR(area, static_cast<double>(within), 1e-9) << "case " << n;
  }
}

TEST(FleetIsochrone, IslandInALakeInARegion) {
  // A ring of free cells around a blocked moat around a free island:
  // two polygons, the outer one with a hole, the island inside the hole.
  std::vector<uint8_t> inside(9 * 9, 0);
  for (int y = 0; y < 9; ++y) {
    for (int x = 0; x < 9; ++x) {
      const int ring = std::min({x, y, 8 - x, 8 - y});
      inside[y * 9 + x] = (ring == 0 || ring >= 3) ? 1 : 0;
    }
  }
  const std::vector<CellPolygon> polygons = RegionPolygons(9, 9, inside);
  ASSERT_EQ(polygons.size(), 2u);
  size_t holes = 0;
  for (const CellPolygon& p : polygons) holes += p.holes.size();
  EXPECT_EQ(holes, 1u);
}

}  // namespace
}  // namespace pathd
