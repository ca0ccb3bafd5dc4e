// One suite runs every registered planner through the same cases; optimal
// planners are checked against Dijkstra, and Dijkstra itself against an
// independent Bellman-Ford relaxation on small random grids.
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "absl/time/clock.h"
#include "core/search/registry.h"
#include "core/search/path_measure.h"
#include "core/search/endpoints.h"
#include "core/search/line_of_sight.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/planner.h"
#include "gtest/gtest.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

// Minimum cost from start to every cell by repeated relaxation of every legal
// move until nothing changes: slow, obviously correct, shares no code with the
// planners' search loops (only the cost model's CellFactor).
std::vector<double> BellmanFord(const Grid& grid, Cell start, const CostParams& p) {
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> dist(grid.size(), inf);
  dist[grid.Index(start)] = 0.0;
  auto ok = [&](int x, int y) {
    return grid.InBounds(x, y) && Traversable(grid.cost(x, y), p.unknown_is_free);
  };
  for (bool changed = true; changed;) {
    changed = false;
    for (int y = 0; y < grid.height(); ++y) {
      for (int x = 0; x < grid.width(); ++x) {
        const double d = dist[grid.Index(x, y)];
        if (d == inf) continue;
        for (int m = 0; m < MoveCount(p.connectivity); ++m) {
          const int nx = x + kMoves[m].dx, ny = y + kMoves[m].dy;
          if (!ok(nx, ny)) continue;
          if (kMoves[m].dx != 0 && kMoves[m].dy != 0 &&
              (!ok(x + kMoves[m].dx, y) || !ok(x, y + kMoves[m].dy))) {
            continue;
          }
          const double nd =
              d + kMoves[m].length * CellFactor(grid.cost(nx, ny), p.cost_weight);
          if (nd < dist[grid.Index(nx, ny)] - 1e-12) {
            dist[grid.Index(nx, ny)] = nd;
            changed = true;
          }
        }
      }
    }
  }
  return dist;
}

// True when the planner's traits say it refuses this query with
// FAILED_PRECONDITION (JPS on weighted maps or 4-connectivity).
bool Refuses(const PlannerTraits& traits, const Grid& grid, const CostParams& p) {
  if (traits.needs_eight_connected && p.connectivity != Connectivity::kEight) {
    return true;
  }
  if (!traits.needs_uniform_cost || p.cost_weight == 0.0) return false;
  int first = -1;
  for (uint8_t v : grid.cells()) {
    if (!Traversable(v, p.unknown_is_free)) continue;
    const int c = v == kUnknownCost ? 0 : v;
    if (first >= 0 && c != first) return true;
    first = c;
  }
  return false;
}

// A found path is legal: for grid and geometric planners MeasureResultPath
// accepts it; a kinematic planner's (PlanResult::poses) starts at the start
// cell's centre and ends at the goal cell's (the default query of a grid
// request), its poses at most a cell apart, and `path` is their cells, each
// traversable.
bool ResultIsValid(const Grid& grid, const PlanResult& r, const CostParams& params) {
  if (r.poses.empty()) return MeasureResultPath(grid, r, params).valid;
  const Pose& first = r.poses.front().pose;
  const Pose& last = r.poses.back().pose;
  if (!(r.path.front() == first.cell()) || !(r.path.back() == last.cell())) return false;
  if (std::fabs(first.x - (r.path.front().x + 0.5)) > 1e-9 ||
      std::fabs(first.y - (r.path.front().y + 0.5)) > 1e-9 ||
      std::fabs(last.x - (r.path.back().x + 0.5)) > 1e-9 ||
      std::fabs(last.y - (r.path.back().y + 0.5)) > 1e-9) {
    return false;
  }
  std::vector<Cell> cells;
  for (size_t i = 0; i < r.poses.size(); ++i) {
    const Pose& p = r.poses[i].pose;
    if (i > 0 && std::hypot(p.x - r.poses[i - 1].pose.x, p.y - r.poses[i - 1].pose.y) > 1.0) {
      return false;
    }
    const Cell c = p.cell();
    if (!grid.InBounds(c) || !Traversable(grid.cost(c), params.unknown_is_free)) return false;
    if (cells.empty() || !(cells.back() == c)) cells.push_back(c);
  }
  return cells == r.path;
}

class EveryPlanner : public ::testing::TestWithParam<std::string> {
 protected:
  const PlannerTraits& traits() const { return planner().traits(); }
  const Planner& planner() const {
    const Planner* p = PlannerRegistry::Default().Get(GetParam());
    EXPECT_NE(p, nullptr);
    return *p;
  }
  absl::StatusOr<PlanResult> Plan(const Grid& grid, Cell s, Cell g,
                                  CostParams params = {},
                                  StopCondition stop = StopCondition::None()) {
    return planner().Plan(grid, PlanRequest::Between(s, g, params), stop, scratch_);
  }
  SearchScratch scratch_;
};

TEST_P(EveryPlanner, StartEqualsGoal) {
  Grid grid = MakeGrid({"...", "...", "..."});
  auto r = Plan(grid, {1, 1}, {1, 1});
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_TRUE(r->found());
  ASSERT_EQ(r->path.size(), 1u);
  EXPECT_EQ(r->path[0], (Cell{1, 1}));
  EXPECT_EQ(r->cost, 0.0);
  EXPECT_EQ(r->length, 0.0);
}

TEST_P(EveryPlanner, UnreachableGoalIsAnOutcomeNotAnError) {
  Grid grid = MakeGrid({"..#..", "..#..", "..#.."});
  auto r = Plan(grid, {0, 0}, {4, 2});
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_FALSE(r->found());
  if (traits().complete) {
    EXPECT_EQ(r->outcome, PlanOutcome::kNoPath);
  } else {
    // The potential field cannot prove there is no path; it stalls.
    EXPECT_TRUE(r->outcome == PlanOutcome::kNoPath ||
                r->outcome == PlanOutcome::kLocalMinimum)
        << PlanOutcomeName(r->outcome);
  }
  EXPECT_TRUE(r->path.empty());
}

TEST_P(EveryPlanner, DiagonalGapIsNotPassable) {
  // The only way through is a corner between two blocked cells.
  Grid grid = MakeGrid({".#", "#."});
  auto r = Plan(grid, {0, 0}, {1, 1});
  ASSERT_TRUE(r.ok());
  EXPECT_FALSE(r->found());
  EXPECT_TRUE(r->path.empty());
}

TEST_P(EveryPlanner, BlockedOrOffMapEndpointsNameTheEndpoint) {
  Grid grid = MakeGrid({"..#", "...", "..."});
  auto r = Plan(grid, {2, 0}, {0, 0});
  EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("start"), std::string::npos) << r.status();
  r = Plan(grid, {0, 0}, {2, 0});
  EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("goal"), std::string::npos) << r.status();
  r = Plan(grid, {-1, 0}, {0, 0});
  EXPECT_NE(r.status().message().find("start"), std::string::npos) << r.status();
  EXPECT_NE(r.status().message().find("outside"), std::string::npos) << r.status();
  r = Plan(grid, {0, 0}, {0, 3});
  EXPECT_NE(r.status().message().find("goal"), std::string::npos) << r.status();
}

TEST_P(EveryPlanner, EndpointErrorsCarryTheirFault) {
  Grid grid = MakeGrid({"..#", "...", "#.."});
  EXPECT_EQ(EndpointFaultOf(Plan(grid, {2, 0}, {0, 0}).status()),
            EndpointFault::kStartBlocked);
  EXPECT_EQ(EndpointFaultOf(Plan(grid, {0, 0}, {0, 2}).status()),
            EndpointFault::kGoalBlocked);
  EXPECT_EQ(EndpointFaultOf(Plan(grid, {-1, 0}, {0, 0}).status()),
            EndpointFault::kStartOutsideMap);
  EXPECT_EQ(EndpointFaultOf(Plan(grid, {0, 0}, {0, 3}).status()),
            EndpointFault::kGoalOutsideMap);
  CostParams bad;
  bad.cost_weight = -1.0;
  const absl::Status other = Plan(grid, {0, 0}, {1, 1}, bad).status();
  EXPECT_EQ(other.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(EndpointFaultOf(other), std::nullopt);
}

// Counts reports; with interval zero every poll after the first reports.
class CountingSink final : public ProgressSink {
 public:
  explicit CountingSink(absl::Duration interval) : ProgressSink(interval) {}
  int reports = 0;
  int64_t last_expansions = 0;

 protected:
  void Report(int64_t expansions, double /*best_f*/, absl::Time /*now*/) override {
    ++reports;
    last_expansions = expansions;
  }
};

TEST_P(EveryPlanner, LongSearchesReportProgressThroughTheStopCondition) {
  // A wall with one gap at the far end: every planner works through
  // thousands of cells (or steps), so the stop condition polls several times.
  std::vector<std::string> rows(96, std::string(96, '.'));
  for (int y = 0; y < 95; ++y) rows[y][48] = '#';
  const Grid grid = MakeGrid(rows);
  CountingSink sink(absl::ZeroDuration());
  const StopCondition stop(absl::InfiniteFuture(), nullptr, 0, &sink);
  auto r = Plan(grid, {0, 0}, {95, 0}, {}, stop);
  ASSERT_TRUE(r.ok()) << r.status();
  if (r->expansions < 4 * StopCondition::kPollInterval) {
    GTEST_SKIP() << "only " << r->expansions << " expansions";
  }
  EXPECT_GE(sink.reports, 2) << r->expansions << " expansions";
  EXPECT_LE(sink.last_expansions, r->expansions);
}

TEST_P(EveryPlanner, UnknownCellsFollowTheOption) {
  Grid grid = MakeGrid({".?.", "#?#", ".?."});
  CostParams params;
  auto r = Plan(grid, {0, 0}, {0, 2}, params);
  ASSERT_TRUE(r.ok());
  EXPECT_FALSE(r->found());
  if (traits().complete) {
    EXPECT_EQ(r->outcome, PlanOutcome::kNoPath);
  }
  params.unknown_is_free = true;
  r = Plan(grid, {0, 0}, {0, 2}, params);
  ASSERT_TRUE(r.ok());
  if (traits().complete) {
    EXPECT_TRUE(r->found());
  }
  if (r->found()) {
    EXPECT_TRUE(ResultIsValid(grid, *r, params));
  }
}

TEST_P(EveryPlanner, WeightedCellsAreHonouredOrRefused) {
  // A band of costly cells: with weight 3 crossing it costs 7 + 4 = 11, going
  // around 4 + 4 * sqrt(2) = 9.66.
  Grid grid = MakeGrid({".........", "....9....", "....9....", "....9....",
                        "........."});
  CostParams heavy;
  heavy.cost_weight = 3.0;
  auto r = Plan(grid, {0, 2}, {8, 2}, heavy);
  if (traits().needs_uniform_cost) {
    ASSERT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition) << r.status();
    EXPECT_NE(std::string(r.status().message()).find(planner().name()),
              std::string::npos);
    EXPECT_NE(r.status().message().find("(4, 1)"), std::string::npos) << r.status();
    // Ignoring cell costs makes the map uniform again.
    heavy.cost_weight = 0.0;
    r = Plan(grid, {0, 2}, {8, 2}, heavy);
    ASSERT_TRUE(r.ok()) << r.status();
    EXPECT_DOUBLE_EQ(r->cost, 8.0);
    return;
  }
  ASSERT_TRUE(r.ok()) << r.status();
  if (!traits().complete && !r->found()) return;
  ASSERT_TRUE(r->found());
  ASSERT_TRUE(ResultIsValid(grid, *r, heavy));
  // Kinematic planners price their motions their own way (Nav2 Smac's
  // penalties, core/kinematics/vehicle.h); their tests check them.
  if (traits().kinematic) return;
  const PathMeasure m = MeasureResultPath(grid, *r, heavy);
  EXPECT_NEAR(r->cost, m.cost, 1e-9);
  if (traits().optimal) {
    EXPECT_NEAR(r->cost, 4 + 4 * kSqrt2, 1e-9);
    for (Cell c : r->path) EXPECT_NE(grid.cost(c), 9 * 28) << CellToString(c);
  }
}

TEST_P(EveryPlanner, BadCostParametersAreInvalidArgument) {
  Grid grid = MakeGrid({"..", ".."});
  CostParams params;
  params.cost_weight = -1.0;
  EXPECT_EQ(Plan(grid, {0, 0}, {1, 1}, params).status().code(),
            absl::StatusCode::kInvalidArgument);
  params.cost_weight = std::nan("");
  EXPECT_EQ(Plan(grid, {0, 0}, {1, 1}, params).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST_P(EveryPlanner, ExpiredDeadlineStopsTheSearch) {
  Grid grid = Grid::Create(300, 300).value();
  StopCondition stop(absl::Now() - absl::Seconds(1), nullptr, 0);
  auto r = Plan(grid, {0, 0}, {299, 299}, {}, stop);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kTimeout);
  EXPECT_TRUE(r->path.empty());
}

TEST_P(EveryPlanner, CancelFlagStopsTheSearch) {
  Grid grid = Grid::Create(300, 300).value();
  std::atomic<bool> cancelled{true};
  auto r = Plan(grid, {0, 0}, {299, 299}, {},
                StopCondition(absl::InfiniteFuture(), &cancelled, 0));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kCancelled);
}

TEST_P(EveryPlanner, ExpansionBudgetRunsOut) {
  // Walls with alternating gaps (a serpentine), so that no planner, JPS with
  // its long jumps included, gets through in 10 expansions.
  Grid grid = Grid::Create(100, 100).value();
  for (int32_t y = 4; y < 100; y += 4) {
    for (int32_t x = 0; x < 100; ++x) grid.set_cost(x, y, kLethalCost);
    grid.set_cost((y / 4) % 2 == 0 ? 99 : 0, y, kFreeCost);
  }
  auto r = Plan(grid, {0, 0}, {99, 99}, {},
                StopCondition(absl::InfiniteFuture(), nullptr, 10));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kExpansionLimit);
  EXPECT_LE(r->expansions, 10);
}

TEST_P(EveryPlanner, FourAndEightConnectivity) {
  // An obstacle off the diagonal, so any-angle and heuristic planners have
  // something to go around without changing the optima.
  Grid grid = MakeGrid({".....####.", ".....####.", ".......##.", "..........",
                        "..........", "#.........", "##........", "###.......",
                        "###.......", ".........."});
  CostParams four;
  four.connectivity = Connectivity::kFour;
  auto r4 = Plan(grid, {0, 0}, {9, 9}, four);
  if (traits().needs_eight_connected) {
    EXPECT_EQ(r4.status().code(), absl::StatusCode::kFailedPrecondition) << r4.status();
  } else {
    ASSERT_TRUE(r4.ok()) << r4.status();
    ASSERT_TRUE(r4->found() || !traits().complete);
    // A kinematic robot's moves are its own, whatever the connectivity.
    if (r4->found() && !traits().kinematic) {
      const PathMeasure m = MeasureResultPath(grid, *r4, four);
      ASSERT_TRUE(m.valid);
      if (!r4->any_angle) {
        // Only straight moves.
        for (size_t i = 1; i < r4->path.size(); ++i) {
          EXPECT_EQ(std::abs(r4->path[i].x - r4->path[i - 1].x) +
                        std::abs(r4->path[i].y - r4->path[i - 1].y),
                    1);
        }
      }
      if (traits().optimal || traits().fewest_moves) {
        EXPECT_EQ(r4->path.size(), 19u);  // 18 straight moves
      }
      EXPECT_LE(r4->length, 18.0 + 1e-9) << "no longer than the Manhattan optimum";
    }
  }
  auto r8 = Plan(grid, {0, 0}, {9, 9});
  ASSERT_TRUE(r8.ok()) << r8.status();
  ASSERT_TRUE(r8->found() || !traits().complete);
  if (!r8->found()) return;
  ASSERT_TRUE(ResultIsValid(grid, *r8, {}));
  if ((traits().optimal || traits().fewest_moves) && !traits().geometric) {
    EXPECT_EQ(r8->path.size(), 10u);  // 9 diagonal moves
  }
  if (traits().optimal) {
    EXPECT_NEAR(r8->length, 9 * kSqrt2, 1e-9);
  }
  if (traits().any_angle || (traits().geometric && traits().optimal)) {
    EXPECT_LE(r8->length, 9 * kSqrt2 + 1e-9);
  }
}

TEST_P(EveryPlanner, SearchScratchIsReusedAcrossMapSizes) {
  Grid big = Grid::Create(50, 50).value();
  Grid small = MakeGrid({"...", ".#.", "..."});
  for (int i = 0; i < 3; ++i) {
    auto a = Plan(big, {0, 0}, {49, 0});
    ASSERT_TRUE(a.ok() && a->found()) << (a.ok() ? "" : a.status().ToString());
    // Around the centre obstacle: the potential field stalls on its axis of
    // symmetry, so it gets a goal it can see.
    const Cell goal = traits().complete ? Cell{2, 2} : Cell{2, 0};
    auto b = Plan(small, {0, 0}, goal);
    ASSERT_TRUE(b.ok() && b->found());
    EXPECT_EQ(b->path.front(), (Cell{0, 0}));
    EXPECT_EQ(b->path.back(), goal);
  }
}

// Random weighted grids, 4- and 8-connected, thousands per planner: every
// found path is legal (a move chain, or line-of-sight segments for any-angle
// results) and its reported cost and length match a re-measurement; what else
// is checked follows the traits: optimal planners match an independent
// Bellman-Ford, fewest-move planners a reference BFS in moves, bounded ones
// stay within heuristic_weight times the optimum, any-angle and exact
// geometric ones are never longer than the optimum on uniform-cost grids
// (geometric ones never shorter than the straight line; their exactness is
// checked in geometric_planners_test; a channel-refined trapezoidal path can
// be slightly longer than the grid optimum), complete ones find a path
// exactly when one exists, and cost-to-go fields match Bellman-Ford from the
// goal's side.
TEST_P(EveryPlanner, RandomWeightedGridsAgreeWithReferences) {
  std::mt19937 rng(20261123);
  const PlannerTraits& t = traits();
  int found = 0;
  int refused = 0;
  constexpr int kTrials = 2000;
  for (int trial = 0; trial < kTrials; ++trial) {
    const int w = 2 + static_cast<int>(rng() % 14);
    const int h = 2 + static_cast<int>(rng() % 14);
    Grid grid = Grid::Create(w, h).value();
    const int obstacle_pct = static_cast<int>(rng() % 40);
    const bool weighted = trial % 3 != 0;
    for (size_t i = 0; i < grid.size(); ++i) {
      const int roll = static_cast<int>(rng() % 100);
      uint8_t v = kFreeCost;
      if (roll < obstacle_pct) {
        v = (rng() % 5 == 0) ? kUnknownCost : kLethalCost;
      } else if (weighted && rng() % 3 == 0) {
        v = static_cast<uint8_t>(rng() % 253);
      }
      grid.mutable_cells()[i] = v;
    }
    CostParams params;
    params.connectivity = (trial % 2) ? Connectivity::kFour : Connectivity::kEight;
    params.cost_weight = (trial % 5 == 0) ? 0.0 : static_cast<double>(rng() % 400) / 100.0;
    params.unknown_is_free = trial % 7 == 0;
    const Cell s{static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h)};
    const Cell g{static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h)};
    PlanRequest request = PlanRequest::Between(s, g, params);
    request.heuristic_weight = 1.0 + static_cast<double>(rng() % 300) / 100.0;
    request.lookahead = 1 + static_cast<int32_t>(rng() % 32);
    request.want_cost_to_go = t.cost_to_go && trial % 4 == 0;
    auto r = planner().Plan(grid, request, StopCondition::None(), scratch_);
    const bool endpoints_ok = Traversable(grid.cost(s), params.unknown_is_free) &&
                              Traversable(grid.cost(g), params.unknown_is_free);
    if (!endpoints_ok) {
      EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
      continue;
    }
    if (Refuses(t, grid, params)) {
      EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition)
          << "trial " << trial << ": " << r.status();
      ++refused;
      continue;
    }
    ASSERT_TRUE(r.ok()) << "trial " << trial << ": " << r.status();
    const std::vector<double> dist = BellmanFord(grid, s, params);
    const double optimum = dist[grid.Index(g)];
    const bool reachable = std::isfinite(optimum);
    if (t.complete) {
      ASSERT_EQ(r->found(), reachable) << "trial " << trial;
    } else {
      ASSERT_TRUE(reachable || !r->found()) << "trial " << trial;
    }
    if (request.want_cost_to_go) {
      ASSERT_EQ(r->cost_to_go.size(), grid.size()) << "trial " << trial;
      // Cost-to-go of s is the cost from s to the goal.
      if (reachable) {
        EXPECT_NEAR(r->cost_to_go[grid.Index(s)], optimum, 1e-9 * (1 + optimum))
            << "trial " << trial;
      } else {
        EXPECT_TRUE(std::isinf(r->cost_to_go[grid.Index(s)])) << "trial " << trial;
      }
    }
    if (!r->found()) continue;
    ++found;
    ASSERT_EQ(r->path.front(), s);
    ASSERT_EQ(r->path.back(), g);
    if (t.kinematic) {
      // Poses from the start cell's centre to the goal cell's (the default
      // query of a grid request), through traversable cells; the kinematic
      // checks are the planners' own tests'.
      ASSERT_TRUE(ResultIsValid(grid, *r, params)) << "trial " << trial;
      EXPECT_GE(r->length, SegmentLength(s, g) - 1e-9) << "trial " << trial;
      continue;
    }
    const PathMeasure m = MeasureResultPath(grid, *r, params);
    ASSERT_TRUE(m.valid) << "trial " << trial << " step " << m.first_invalid;
    EXPECT_NEAR(r->cost, m.cost, 1e-9 * (1 + m.cost)) << "trial " << trial;
    EXPECT_NEAR(r->length, m.length, 1e-9 * (1 + m.length)) << "trial " << trial;
    if (t.optimal && !t.geometric) {
      EXPECT_NEAR(r->cost, optimum, 1e-9 * (1 + r->cost)) << "trial " << trial;
    }
    if (t.geometric) {
      // Never below the straight line between the cell centres.
      EXPECT_GE(r->length, SegmentLength(s, g) - 1e-9) << "trial " << trial;
    }
    if (t.fewest_moves) {
      const std::vector<int> moves = MoveCounts(grid, s, params);
      EXPECT_EQ(static_cast<int>(r->path.size()) - 1, moves[grid.Index(g)])
          << "trial " << trial;
    }
    if (t.bounded) {
      EXPECT_LE(r->cost, request.heuristic_weight * optimum + 1e-9 * (1 + optimum))
          << "trial " << trial;
    }
    if ((t.any_angle || (t.geometric && t.optimal)) && params.cost_weight == 0.0) {
      EXPECT_LE(r->length, optimum + 1e-9 * (1 + optimum)) << "trial " << trial;
    }
  }
  EXPECT_GT(found + refused, kTrials / 3);
}

INSTANTIATE_TEST_SUITE_P(Registry, EveryPlanner,
                         ::testing::ValuesIn(PlannerRegistry::Default().Names()),
                         [](const auto& info) { return info.param; });

TEST(ProgressSink, ReportsOncePerIntervalAfterTheFirstPoll) {
  CountingSink every_poll(absl::ZeroDuration());
  CountingSink hourly(absl::Hours(1));
  for (int i = 0; i < 5; ++i) {
    every_poll.Poll(i * 1024, 1.0);
    hourly.Poll(i * 1024, 1.0);
  }
  // The first poll arms the interval; each later one passed a zero interval.
  EXPECT_EQ(every_poll.reports, 4);
  EXPECT_EQ(every_poll.last_expansions, 4 * 1024);
  EXPECT_EQ(hourly.reports, 0);
}

TEST(PlannerRegistry, CreatesByNameAndListsNames) {
  const PlannerRegistry& registry = PlannerRegistry::Default();
  auto names = registry.Names();
  EXPECT_NE(std::find(names.begin(), names.end(), "astar"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "dijkstra"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "bfs"), names.end());
  auto p = registry.Create("astar");
  ASSERT_TRUE(p.ok());
  EXPECT_EQ((*p)->name(), "astar");
  auto unknown = registry.Create("nope");
  EXPECT_EQ(unknown.status().code(), absl::StatusCode::kNotFound);
  EXPECT_NE(unknown.status().message().find("dijkstra"), std::string::npos);
}

TEST(AStar, ExpandsNoMoreThanDijkstra) {
  Grid grid = Grid::Create(64, 64).value();
  SearchScratch scratch;
  const PlanRequest req = PlanRequest::Between({3, 5}, {60, 50});
  auto a = PlannerRegistry::Default().Get("astar")->Plan(grid, req,
                                                          StopCondition::None(), scratch);
  auto d = PlannerRegistry::Default().Get("dijkstra")->Plan(
      grid, req, StopCondition::None(), scratch);
  ASSERT_TRUE(a.ok() && d.ok());
  EXPECT_DOUBLE_EQ(a->cost, d->cost);
  EXPECT_LT(a->expansions, d->expansions / 4);
}

TEST(Grid, WorldCellRoundTripWithRotation) {
  Grid grid = Grid::Create(20, 10).value();
  grid.set_resolution(0.05);
  grid.set_origin({-1.0, 2.0, 0.3});
  for (Cell c : {Cell{0, 0}, Cell{19, 9}, Cell{7, 3}}) {
    auto back = grid.WorldToCell(grid.CellCenter(c));
    ASSERT_TRUE(back.ok());
    EXPECT_EQ(*back, c);
  }
  EXPECT_EQ(grid.WorldToCell({100, 100}).status().code(), absl::StatusCode::kOutOfRange);
  EXPECT_EQ(grid.WorldToCell({std::nan(""), 0}).status().code(),
            absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace pathd
