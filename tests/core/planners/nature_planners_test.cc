// The nature-inspired heuristic planners (core/planners/nature): ant_colony
// and reaction_diffusion against an independent cost model and Dijkstra
// written here (no core search code): every returned path is a legal move
// chain whose recomputed cost is the reported one and never below the
// optimum; unreachable goals are NO_PATH; bad parameters are
// INVALID_ARGUMENT naming the parameter. ant_colony: its success rate on
// random maps, equal-cost paths in corridors, one answer per seed, honest
// "no ant arrived" outcomes. reaction_diffusion: arrival time decreasing
// along the path, the reported deviation from the exact cost-to-go
// recomputed here, and the front's accuracy on an open map.
// PATHD_NATURE_CASES=N caps the randomised counts (the ASan run sets it low).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/map_io/map_io.h"
#include "core/planners/nature/ant_colony.h"
#include "core/planners/nature/reaction_diffusion.h"
#include "core/search/planner.h"
#include "core/search/registry.h"
#include "gtest/gtest.h"
#include "tests/testing/reference_model.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

int Cases(int fallback) {
  const char* env = std::getenv("PATHD_NATURE_CASES");
  const int scale = env != nullptr ? std::atoi(env) : 0;
  return scale > 0 ? std::min(fallback, scale) : fallback;
}

using testing::CostTo;
using testing::Model;

struct RandomCase {
  Grid grid;
  CostParams params;
  Cell s;
  Cell g;
};

// A random map with traversable endpoints: 8..24 cells a side, up to 30%
// blocked, weighted cells on two maps in three, 4- and 8-connected.
RandomCase MakeRandomCase(std::mt19937& rng, int trial) {
  const int w = 8 + static_cast<int>(rng() % 17);
  const int h = 8 + static_cast<int>(rng() % 17);
  RandomCase c{Grid::Create(w, h).value(), {}, {}, {}};
  const int blocked_pct = static_cast<int>(rng() % 31);
  for (size_t i = 0; i < c.grid.size(); ++i) {
    const int roll = static_cast<int>(rng() % 100);
    uint8_t v = kFreeCost;
    if (roll < blocked_pct) {
      v = kLethalCost;
    } else if (trial % 3 != 0 && rng() % 3 == 0) {
      v = static_cast<uint8_t>(rng() % 253);
    }
    c.grid.mutable_cells()[i] = v;
  }
  c.params.connectivity = trial % 2 ? Connectivity::kFour : Connectivity::kEight;
  c.params.cost_weight = static_cast<double>(rng() % 300) / 100.0;
  c.s = {static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h)};
  c.g = {static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h)};
  c.grid.set_cost(c.s, kFreeCost);
  c.grid.set_cost(c.g, kFreeCost);
  return c;
}

const Planner& Get(const char* name) {
  const Planner* p = PlannerRegistry::Default().Get(name);
  EXPECT_NE(p, nullptr) << name;
  return *p;
}

absl::StatusOr<PlanResult> Plan(const char* name, const Grid& grid,
                                const PlanRequest& request) {
  SearchScratch scratch;
  return Get(name).Plan(grid, request, StopCondition::None(), scratch);
}

// Checks a result against the model and the optimum; returns whether found.
bool CheckResult(const Model& m, const PlanRequest& request, const PlanResult& r,
                 double optimum, const std::string& where) {
  if (!std::isfinite(optimum)) {
    EXPECT_EQ(r.outcome, PlanOutcome::kNoPath) << where;
    return false;
  }
  if (!r.found()) return false;
  const double cost = m.PathCost(r.path, request.start, request.goal);
  EXPECT_GE(cost, 0.0) << where << ": not a legal move chain from start to goal";
  EXPECT_NEAR(r.cost, cost, 1e-9 * (1 + cost)) << where;
  EXPECT_GE(cost, optimum - 1e-9 * (1 + optimum)) << where << ": below the optimum";
  return true;
}

// Each change to the default parameters is INVALID_ARGUMENT with the
// message part given.
template <typename Params>
void ExpectRefused(
    const char* planner, Params PlanRequest::*member,
    const std::vector<std::pair<std::function<void(Params&)>, std::string>>& bad) {
  const Grid grid = Grid::Create(4, 4).value();
  for (const auto& [change, message] : bad) {
    PlanRequest request = PlanRequest::Between({0, 0}, {3, 3});
    change(request.*member);
    auto r = Plan(planner, grid, request);
    EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument) << message;
    EXPECT_NE(r.status().message().find(message), std::string::npos) << r.status();
  }
}

// ---------------------------------------------------------------- ant_colony

// Over random maps with a path, the default colony (20 ants, up to 100
// iterations, seed 1) finds one on at least 95% of them. A colony whose
// pheromone and desirability did nothing would be a random walk with a tabu
// list: in three iterations, with alpha = beta = 0 (both terms switched
// off) it finds at most 90% of what the guided colony finds in three.
TEST(AntColony, RandomMapsLegalNeverBelowOptimumAndMostlyFound) {
  std::mt19937 rng(20261202);
  const int trials = Cases(300);
  int reachable = 0, found = 0, found_short = 0, found_blind = 0;
  for (int trial = 0; trial < trials; ++trial) {
    const RandomCase c = MakeRandomCase(rng, trial);
    const Model m{c.grid, c.params};
    const double optimum = CostTo(m, c.g)[c.grid.Index(c.s)];
    PlanRequest request = PlanRequest::Between(c.s, c.g, c.params);
    auto r = Plan("ant_colony", c.grid, request);
    ASSERT_TRUE(r.ok()) << r.status();
    const std::string where = absl::StrCat("trial ", trial);
    ASSERT_TRUE(r->ant_colony.has_value());
    if (std::isfinite(optimum)) ++reachable;
    if (CheckResult(m, request, *r, optimum, where)) {
      ++found;
      EXPECT_GE(r->ant_colony->best_iteration, 1) << where;
      EXPECT_LE(r->ant_colony->best_iteration, r->ant_colony->iterations_run) << where;
      EXPECT_NEAR(r->ant_colony->best_cost, r->cost, 1e-6 * (1 + r->cost)) << where;
    } else if (std::isfinite(optimum)) {
      EXPECT_EQ(r->outcome, PlanOutcome::kExpansionLimit) << where;
      EXPECT_NE(r->reason.find("reachable"), std::string::npos) << r->reason;
    }
    // Three iterations, guided and blind (alpha = beta = 0).
    request.ant_colony.iterations = 3;
    auto short_run = Plan("ant_colony", c.grid, request);
    ASSERT_TRUE(short_run.ok());
    if (CheckResult(m, request, *short_run, optimum, where + " short")) ++found_short;
    request.ant_colony.alpha = 0.0;
    request.ant_colony.beta = 0.0;
    auto blind = Plan("ant_colony", c.grid, request);
    ASSERT_TRUE(blind.ok());
    if (CheckResult(m, request, *blind, optimum, where + " blind")) ++found_blind;
  }
  ASSERT_GT(reachable, trials / 3);
  const double rate = static_cast<double>(found) / reachable;
  std::printf("ant_colony found %d of %d reachable goals (%.1f%%); in 3 iterations %d, "
              "blind (alpha = beta = 0) %d\n",
              found, reachable, 100 * rate, found_short, found_blind);
  EXPECT_GE(rate, 0.95);
  EXPECT_LT(found_blind, found_short * 9 / 10);
}

TEST(AntColony, CorridorsGiveTheOptimum) {
  // One way through: every ant that arrives took it.
  const Grid grid = MakeGrid({"......#...",
                              "#####.#.#.",
                              "......#.#.",
                              ".######.#.",
                              "........#."});
  const Model m{grid, {}};
  const PlanRequest request = PlanRequest::Between({0, 0}, {9, 0});
  auto r = Plan("ant_colony", grid, request);
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_TRUE(r->found()) << r->reason;
  EXPECT_NEAR(r->cost, CostTo(m, {9, 0})[0], 1e-9);
  // An open strip 3 cells high: the straight row is optimal and the colony
  // converges to it.
  const Grid strip = MakeGrid({"..............................",
                               "..............................",
                               ".............................."});
  r = Plan("ant_colony", strip, PlanRequest::Between({0, 1}, {29, 1}));
  ASSERT_TRUE(r.ok() && r->found());
  EXPECT_NEAR(r->cost, 29.0, 1e-9);
}

TEST(AntColony, OneSeedOneAnswer) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < Cases(20); ++trial) {
    const RandomCase c = MakeRandomCase(rng, trial);
    PlanRequest request = PlanRequest::Between(c.s, c.g, c.params);
    request.ant_colony.seed = 1234 + trial;
    auto a = Plan("ant_colony", c.grid, request);
    auto b = Plan("ant_colony", c.grid, request);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->outcome, b->outcome);
    EXPECT_EQ(a->path, b->path);
    EXPECT_EQ(a->expansions, b->expansions);
    EXPECT_EQ(a->ant_colony->best_iteration, b->ant_colony->best_iteration);
  }
}

TEST(AntColony, StallsAndReportsConvergence) {
  const Grid grid = Grid::Create(20, 20).value();
  PlanRequest request = PlanRequest::Between({0, 0}, {19, 13});
  request.ant_colony.iterations = 500;
  request.ant_colony.stall_iterations = 10;
  auto r = Plan("ant_colony", grid, request);
  ASSERT_TRUE(r.ok() && r->found());
  const AntColonyStats& s = *r->ant_colony;
  EXPECT_EQ(s.stopped_by, "stalled");
  // Stalled exactly stall_iterations after the last improvement.
  EXPECT_EQ(s.iterations_run, s.best_iteration + 10);
  EXPECT_EQ(s.ants_reached_goal + s.ants_died, int64_t{20} * s.iterations_run);
}

TEST(AntColony, UnreachableIsNoPathAndLostAntsAreNot) {
  const Grid walled = MakeGrid({"..#..", "..#..", "..#.."});
  auto r = Plan("ant_colony", walled, PlanRequest::Between({0, 0}, {4, 2}));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kNoPath);
  // Reachable, but no ant may walk far enough.
  const Grid open = Grid::Create(30, 30).value();
  PlanRequest request = PlanRequest::Between({0, 0}, {29, 29});
  request.ant_colony.max_steps = 5;
  request.ant_colony.iterations = 3;
  r = Plan("ant_colony", open, request);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kExpansionLimit);
  EXPECT_NE(r->reason.find("none of the 20 ants of 3 iterations reached the goal"),
            std::string::npos)
      << r->reason;
  EXPECT_NE(r->reason.find("the goal is reachable"), std::string::npos) << r->reason;
  EXPECT_EQ(r->ant_colony->ants_died, 60);
}

TEST(AntColony, BadParametersNameTheParameter) {
  ExpectRefused<AntColonyParams>(
      "ant_colony", &PlanRequest::ant_colony,
      {
          {[](AntColonyParams& p) { p.ants = 0; }, "ant_colony.ants 0"},
          {[](AntColonyParams& p) { p.iterations = -2; }, "ant_colony.iterations -2"},
          {[](AntColonyParams& p) { p.alpha = std::nan(""); }, "ant_colony.alpha nan"},
          {[](AntColonyParams& p) { p.beta = 17; }, "ant_colony.beta 17"},
          {[](AntColonyParams& p) { p.rho = 0; }, "ant_colony.rho 0"},
          {[](AntColonyParams& p) { p.xi = 1.5; }, "ant_colony.xi 1.5"},
          {[](AntColonyParams& p) { p.q0 = -0.1; }, "ant_colony.q0 -0.1"},
          {[](AntColonyParams& p) { p.tau0 = kInf; }, "ant_colony.tau0 inf"},
          {[](AntColonyParams& p) { p.max_steps = -1; }, "ant_colony.max_steps -1"},
          {[](AntColonyParams& p) { p.stall_iterations = -1; },
           "ant_colony.stall_iterations"},
      });
}

TEST(AntColony, RefusesMapsAboveThePheromoneCap) {
  const Grid big = Grid::Create(2048, 1025).value();
  auto r = Plan("ant_colony", big, PlanRequest::Between({0, 0}, {5, 5}));
  EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_NE(r.status().message().find("2099200 cells"), std::string::npos) << r.status();
}

// -------------------------------------------------------- reaction_diffusion

TEST(ReactionDiffusion, RandomMapsLegalNeverBelowOptimumAndHonestStatistics) {
  std::mt19937 rng(20261203);
  const int trials = Cases(200);
  int reachable = 0, found = 0;
  int64_t total_escapes = 0;
  for (int trial = 0; trial < trials; ++trial) {
    const RandomCase c = MakeRandomCase(rng, trial);
    const Model m{c.grid, c.params};
    const std::vector<double> exact = CostTo(m, c.g);
    const double optimum = exact[c.grid.Index(c.s)];
    const PlanRequest request = PlanRequest::Between(c.s, c.g, c.params);
    auto r = Plan("reaction_diffusion", c.grid, request);
    ASSERT_TRUE(r.ok()) << r.status();
    const std::string where = absl::StrCat("trial ", trial);
    if (std::isfinite(optimum)) ++reachable;
    const bool ok = CheckResult(m, request, *r, optimum, where);
    found += ok;
    ASSERT_TRUE(r->reaction_diffusion.has_value());
    const ReactionDiffusionStats& s = *r->reaction_diffusion;
    // The statistics recomputed from the front's arrival times and the
    // reference cost-to-go.
    const Autowave wave = PropagateAutowave(c.grid, request, StopCondition::None());
    double max_e = 0, sum_e = 0;
    int64_t count = 0, reached = 0;
    for (size_t i = 0; i < c.grid.size(); ++i) {
      if (!std::isfinite(wave.arrival[i])) continue;
      ++reached;
      if (i == c.grid.Index(c.g)) continue;
      const double e = std::abs(s.front_speed * wave.arrival[i] - exact[i]) / exact[i];
      max_e = std::max(max_e, e);
      sum_e += e;
      ++count;
    }
    EXPECT_EQ(s.reached_cells, reached) << where;
    EXPECT_NEAR(s.max_relative_error, max_e, 1e-9) << where;
    EXPECT_NEAR(s.mean_relative_error, count ? sum_e / count : 0.0, 1e-9) << where;
    EXPECT_EQ(s.optimal_cost, optimum) << where;
    if (!ok) continue;
    EXPECT_NEAR(s.cost_ratio, optimum > 0 ? r->cost / optimum : 1.0, 1e-9) << where;
    // Arrival time strictly decreasing along the path to 0 at the goal,
    // but for the escapes the planner reports; no cell twice.
    int64_t climbs = 0;
    std::vector<bool> seen(c.grid.size(), false);
    for (size_t k = 0; k < r->path.size(); ++k) {
      EXPECT_FALSE(seen[c.grid.Index(r->path[k])]) << where << " step " << k;
      seen[c.grid.Index(r->path[k])] = true;
      if (k > 0 && !(wave.arrival[c.grid.Index(r->path[k])] <
                     wave.arrival[c.grid.Index(r->path[k - 1])])) {
        ++climbs;
      }
    }
    EXPECT_EQ(climbs, s.escapes) << where;
    total_escapes += s.escapes;
  }
  ASSERT_GT(reachable, trials / 3);
  std::printf("reaction_diffusion found %d of %d reachable goals, %d escapes\n", found,
              reachable, static_cast<int>(total_escapes));
  EXPECT_GE(found, reachable * 95 / 100);
}

// On an open map the front is a circle growing from the goal. Two effects
// keep speed * T from the Euclidean distance d, and are what the test
// bounds: the ignition delay (one excited cell is smaller than the
// critical nucleus, so the front needs time to form: about 26 time units,
// ten cells' worth, at the defaults) and curvature, which slows a front of
// radius r to about speed - D / r. Between 10 and 30 cells from the goal the
// front moves at 85% to 100% of the plane-wave speed, along the axis and the
// diagonal alike (the 9-point Laplacian is isotropic: arrival times at the
// same distance in the two directions agree within 3%).
TEST(ReactionDiffusion, OpenMapFrontMovesAtThePlaneWaveSpeedLessCurvature) {
  const Grid grid = Grid::Create(81, 81).value();
  const PlanRequest request = PlanRequest::Between({0, 0}, {40, 40});
  const Autowave wave = PropagateAutowave(grid, request, StopCondition::None());
  const double speed = NagumoFrontSpeed(request.reaction_diffusion);
  auto at = [&](int x, int y) { return wave.arrival[grid.Index(x, y)]; };
  // Along the axis: cells 10 and 30 to the right of the goal.
  const double axis = (30 - 10) / (at(70, 40) - at(50, 40));
  // Along the diagonal: cells 7 and 21 diagonal steps away (9.9 and 29.7).
  const double diagonal = (21 - 7) * std::sqrt(2.0) / (at(61, 61) - at(47, 47));
  std::printf("open map: front speed %.4f along the axis, %.4f along the diagonal, "
              "plane wave %.4f; ignition delay %.2f\n",
              axis, diagonal, speed, at(50, 40) - 10 / axis);
  for (const double measured : {axis, diagonal}) {
    EXPECT_GE(measured, 0.85 * speed);
    EXPECT_LE(measured, 1.0 * speed);
  }
  // The same Euclidean distance, 28.28 cells, both ways: (60, 60) is 20
  // diagonal steps away; along the axis interpolate between 28 and 29.
  const double along_axis = at(68, 40) + 0.28 * (at(69, 40) - at(68, 40));
  EXPECT_NEAR(at(60, 60) / along_axis, 1.0, 0.03);
  for (int x = 41; x < 81; ++x) EXPECT_GT(at(x, 40), at(x - 1, 40)) << x;
}

TEST(ReactionDiffusion, CorridorGivesTheOptimumAndWallsStopTheFront) {
  const Grid grid = MakeGrid({"......#...",
                              "#####.#.#.",
                              "......#.#.",
                              ".######.#.",
                              "........#."});
  const Model m{grid, {}};
  auto r = Plan("reaction_diffusion", grid, PlanRequest::Between({0, 0}, {9, 0}));
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_TRUE(r->found()) << r->reason;
  EXPECT_NEAR(r->cost, CostTo(m, {9, 0})[0], 1e-9);
  const Grid walled = MakeGrid({"..#..", "..#..", "..#.."});
  r = Plan("reaction_diffusion", walled, PlanRequest::Between({0, 0}, {4, 2}));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->outcome, PlanOutcome::kNoPath);
  EXPECT_EQ(r->reaction_diffusion->reached_cells, 6);
}

// On room/32room_000 (rooms joined by one-cell doors) the scenario below
// descends into a shallow pit of T: the corner cell (191, 481) beside a
// door fires 0.13 time units before the cell the front passed through
// (fewer neighbours to share activator with). The descent climbs out and
// reaches the goal; each climb is an escape. Skipped without the Moving AI
// maps, and under a low PATHD_NATURE_CASES (the ASan run): one query
// updates ~10^8 cells.
TEST(ReactionDiffusion, DescentClimbsOutOfALatticePit) {
  if (Cases(100) < 100) GTEST_SKIP() << "PATHD_NATURE_CASES is low";
  const std::string path = "../shared/benchmarks/movingai/room/32room_000.map";
  auto grid = ReadMovingAiMapFile(path);
  if (!grid.ok()) GTEST_SKIP() << path << " absent";
  CostParams cost;
  cost.cost_weight = 0.0;
  const PlanRequest request = PlanRequest::Between({173, 448}, {226, 465}, cost);
  auto r = Plan("reaction_diffusion", *grid, request);
  ASSERT_TRUE(r.ok() && r->found()) << r->reason;
  const Model m{*grid, cost};
  EXPECT_GE(m.PathCost(r->path, request.start, request.goal),
            CostTo(m, request.goal)[grid->Index(request.start)] - 1e-9);
  const Autowave wave = PropagateAutowave(*grid, request, StopCondition::None());
  int64_t climbs = 0;
  for (size_t k = 1; k < r->path.size(); ++k) {
    climbs += !(wave.arrival[grid->Index(r->path[k])] <
                wave.arrival[grid->Index(r->path[k - 1])]);
  }
  EXPECT_GE(climbs, 1);
  EXPECT_EQ(climbs, r->reaction_diffusion->escapes);
}

TEST(ReactionDiffusion, BadParametersNameTheParameter) {
  ExpectRefused<ReactionDiffusionParams>(
      "reaction_diffusion", &PlanRequest::reaction_diffusion,
      {
          {[](ReactionDiffusionParams& p) { p.diffusion = 0; },
           "reaction_diffusion.diffusion 0"},
          {[](ReactionDiffusionParams& p) { p.reaction_rate = kInf; },
           "reaction_diffusion.reaction_rate inf"},
          {[](ReactionDiffusionParams& p) { p.threshold = 0.5; },
           "reaction_diffusion.threshold 0.5"},
          {[](ReactionDiffusionParams& p) { p.time_step = 0.5; },
           "reaction_diffusion.time_step 0.5 must be <= 1 / (4 diffusion + reaction_rate)"},
          {[](ReactionDiffusionParams& p) { p.max_steps = -3; },
           "reaction_diffusion.max_steps -3"},
      });
}

TEST(ReactionDiffusion, AFrontThatDiesIsNotCalledUnreachable) {
  // A threshold close to 1/2 with weak diffusion: the front stalls in the
  // one-cell corridor (propagation failure of discrete bistable media).
  const Grid grid = MakeGrid({"..........", "#########.", ".........."});
  PlanRequest request = PlanRequest::Between({0, 2}, {0, 0});
  request.reaction_diffusion.threshold = 0.45;
  request.reaction_diffusion.diffusion = 0.05;
  auto r = Plan("reaction_diffusion", grid, request);
  ASSERT_TRUE(r.ok()) << r.status();
  if (r->found()) GTEST_SKIP() << "the front got through";
  EXPECT_EQ(r->outcome, PlanOutcome::kExpansionLimit);
  EXPECT_NE(r->reason.find("which is reachable"), std::string::npos) << r->reason;
}

}  // namespace
}  // namespace pathd
