// core/fleet/mapf.h against checkers written apart from it: every returned
// plan through the independent conflict checker (tests/testing/
// fleet_checker.h); CBS's sum of costs against a brute-force search of the
// joint configuration space (this file's own) on tiny instances; every
// solver's cost against the sum of individual shortest paths (this file's
// own BFS); ECBS within its bound; Moving AI maps with many robots.
// Random instances: PATHD_MAPF_CASES (default 1000, split over the solvers;
// the ASan run takes fewer).
#include "core/fleet/mapf.h"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <queue>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "core/fleet/mapf_internal.h"
#include "core/map/grid.h"
#include "core/map_io/map_io.h"
#include "gtest/gtest.h"
#include "tests/testing/fleet_checker.h"

namespace pathd {
namespace {

int EnvInt(const char* name, int fallback) {
  const char* v = std::getenv(name);
  return v != nullptr ? std::atoi(v) : fallback;
}

bool Free(const Grid& g, int x, int y) {
  return g.InBounds(x, y) && Traversable(g.cost(x, y), false);
}

// Steps between two cells on one grid (this test's own BFS), -1 when none.
int BfsSteps(const Grid& g, Cell a, Cell b, bool eight) {
  std::vector<int> dist(g.size(), -1);
  std::queue<Cell> q;
  dist[g.Index(a)] = 0;
  q.push(a);
  while (!q.empty()) {
    const Cell u = q.front();
    q.pop();
    if (u == b) return dist[g.Index(u)];
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        if (dx == 0 && dy == 0) continue;
        if (dx != 0 && dy != 0 &&
            (!eight || !Free(g, u.x + dx, u.y) || !Free(g, u.x, u.y + dy))) {
          continue;
        }
        const Cell v{u.x + dx, u.y + dy};
        if (!Free(g, v.x, v.y) || dist[g.Index(v)] >= 0) continue;
        dist[g.Index(v)] = dist[g.Index(u)] + 1;
        q.push(v);
      }
    }
  }
  return -1;
}

Grid RandomGrid(std::mt19937& rng, int w, int h, double obstacles) {
  Grid g = Grid::Create(w, h).value();
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (unit(rng) < obstacles) g.set_cost(x, y, kLethalCost);
    }
  }
  return g;
}

// Rooms of `room` cells with walls between them and one or two doors in
// each wall.
Grid RoomGrid(std::mt19937& rng, int w, int h, int room) {
  Grid g = Grid::Create(w, h).value();
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (x % room == room - 1 || y % room == room - 1)
        g.set_cost(x, y, kLethalCost);
    }
  }
  for (int y0 = 0; y0 < h; y0 += room) {
    for (int x0 = 0; x0 < w; x0 += room) {
      const int door_x = x0 + static_cast<int>(rng() % (room - 1));
      const int door_y = y0 + static_cast<int>(rng() % (room - 1));
      if (door_x < w && y0 + room - 1 < h)
        g.set_cost(door_x, y0 + room - 1, kFreeCost);
      if (door_y < h && x0 + room - 1 < w)
        g.set_cost(x0 + room - 1, door_y, kFreeCost);
    }
  }
  return g;
}

// The cells of the largest connected component (4-connected components are
// the components of both move sets: a diagonal needs its sides open).
std::vector<Cell> LargestComponent(const Grid& g) {
  std::vector<int> label(g.size(), -1);
  std::vector<Cell> best;
  for (int y = 0; y < g.height(); ++y) {
    for (int x = 0; x < g.width(); ++x) {
      if (!Free(g, x, y) || label[g.Index(x, y)] >= 0) continue;
      std::vector<Cell> comp{{x, y}};
      label[g.Index(x, y)] = 1;
      for (size_t k = 0; k < comp.size(); ++k) {
        for (const auto& [dx, dy] :
             {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
          const Cell v{comp[k].x + dx, comp[k].y + dy};
          if (Free(g, v.x, v.y) && label[g.Index(v)] < 0) {
            label[g.Index(v)] = 1;
            comp.push_back(v);
          }
        }
      }
      if (comp.size() > best.size()) best = comp;
    }
  }
  return best;
}

struct Instance {
  Grid grid;
  FleetProblem problem;
  int individual = 0;  // sum of individual shortest paths
};

// `robots` distinct starts and goals in the largest component, at most one
// robot per `spread` of its cells.
void PlaceRobots(std::mt19937& rng, int robots, Instance* inst,
                 int spread = 1) {
  std::vector<Cell> cells = LargestComponent(inst->grid);
  robots = std::min<int>(robots, static_cast<int>(cells.size()) / spread);
  std::shuffle(cells.begin(), cells.end(), rng);
  std::vector<Cell> goals = cells;
  std::shuffle(goals.begin(), goals.end(), rng);
  const int n = std::min<int>(robots, static_cast<int>(cells.size()));
  inst->problem.grids = {&inst->grid};
  inst->problem.robots.clear();
  inst->individual = 0;
  for (int i = 0; i < n; ++i) {
    inst->problem.robots.push_back(FleetRobot{cells[i], goals[i], 0});
    inst->individual +=
        BfsSteps(inst->grid, cells[i], goals[i],
                 inst->problem.connectivity == Connectivity::kEight);
  }
}

testing::FleetCheckResult Check(const Instance& inst, const FleetPlan& plan) {
  std::vector<testing::FleetCheckRobot> robots;
  for (const FleetRobot& r : inst.problem.robots) {
    robots.push_back({r.start, r.goal, inst.problem.grids[r.grid]});
  }
  return testing::CheckFleetPlan(
      robots, inst.problem.connectivity == Connectivity::kEight,
      inst.problem.unknown_is_free, plan.paths);
}

// Checks a found plan and its figures; returns its sum of costs (-1 when
// no plan).
int64_t ExpectValid(const Instance& inst, const FleetPlan& plan,
                    const std::string& what) {
  EXPECT_GE(plan.lower_bound, inst.individual) << what;
  if (plan.outcome != PlanOutcome::kFound) {
    EXPECT_FALSE(plan.complete) << what;
    return -1;
  }
  EXPECT_TRUE(plan.complete) << what;
  const testing::FleetCheckResult r = Check(inst, plan);
  EXPECT_TRUE(r.ok) << what << ": " << r.error;
  if (!r.ok) return -1;
  EXPECT_EQ(plan.sum_of_costs, r.sum_of_costs) << what;
  EXPECT_EQ(plan.makespan, r.makespan) << what;
  EXPECT_GE(plan.sum_of_costs, plan.lower_bound) << what;
  EXPECT_GE(plan.sum_of_costs, inst.individual) << what;
  return plan.sum_of_costs;
}

StopCondition Within(absl::Duration d) {
  return StopCondition(absl::Now() + d, nullptr, 0);
}

FleetPlan Solve(const Instance& inst, FleetSolver solver, double w = 1.0,
                absl::Duration limit = absl::Seconds(10), int restarts = 10) {
  FleetOptions options;
  options.solver = solver;
  options.restarts = restarts;
  options.suboptimality = w;
  absl::StatusOr<FleetPlan> plan =
      PlanFleet(inst.problem, options, Within(limit));
  EXPECT_TRUE(plan.ok()) << plan.status();
  return plan.ok() ? *plan : FleetPlan{};
}

// --- Brute force: Dijkstra over joint configurations ---------------------

// The cells a step a -> b sweeps (this test's own statement of the rule).
std::vector<Cell> Swept(Cell a, Cell b) {
  std::vector<Cell> s{a};
  if (!(a == b)) s.push_back(b);
  if (a.x != b.x && a.y != b.y) {
    s.push_back(Cell{b.x, a.y});
    s.push_back(Cell{a.x, b.y});
  }
  return s;
}

// Optimal sum of costs (-1: unsolvable within `horizon` steps). A state is
// the configuration, the set of robots that have finished (stay at their
// goals for good) and the time (capped at the horizon); a step costs one
// per unfinished robot.
// With `loss`: the least sum of loss instead (LaCAM*'s cost: per step, the
// robots not resting at their goals), over configurations alone.
int64_t BruteForce(const Instance& inst, int horizon, bool loss = false) {
  const Grid& g = inst.grid;
  const bool eight = inst.problem.connectivity == Connectivity::kEight;
  const auto& robots = inst.problem.robots;
  const size_t n = robots.size();
  using State = std::pair<std::vector<int>, int>;  // cells, finished mask
  auto moves = [&](Cell a) {
    std::vector<Cell> out{a};
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        if ((dx == 0 && dy == 0) || !Free(g, a.x + dx, a.y + dy)) continue;
        if (dx != 0 && dy != 0 &&
            (!eight || !Free(g, a.x + dx, a.y) || !Free(g, a.x, a.y + dy))) {
          continue;
        }
        out.push_back(Cell{a.x + dx, a.y + dy});
      }
    }
    return out;
  };
  std::map<State, int64_t> dist;
  using Entry = std::pair<int64_t, State>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> open;
  State s0;
  for (const auto& r : robots)
    s0.first.push_back(static_cast<int>(g.Index(r.start)));
  s0.second = 0;
  dist[s0] = 0;
  open.push({0, s0});
  const int all = (1 << n) - 1;
  while (!open.empty()) {
    auto [d, s] = open.top();
    open.pop();
    if (d > dist[s]) continue;
    if (s.second == all) return d;
    // Finishing a robot at its goal costs nothing.
    for (size_t i = 0; i < n && !loss; ++i) {
      if ((s.second >> i & 1) == 0 &&
          s.first[i] == static_cast<int>(g.Index(robots[i].goal))) {
        State f{s.first, s.second | (1 << i)};
        if (!dist.count(f) || dist[f] > d) {
          dist[f] = d;
          open.push({d, f});
        }
      }
    }
    if (d >= static_cast<int64_t>(horizon) * static_cast<int64_t>(n)) continue;
    // Every joint step of the unfinished robots.
    std::vector<std::vector<Cell>> options(n);
    int unfinished = 0;
    for (size_t i = 0; i < n; ++i) {
      const Cell a = g.CellAt(s.first[i]);
      if (s.second >> i & 1) {
        options[i] = {a};
      } else {
        options[i] = moves(a);
        ++unfinished;
      }
    }
    std::vector<size_t> pick(n, 0);
    while (true) {
      std::vector<Cell> all_swept;
      bool ok = true;
      for (size_t i = 0; i < n && ok; ++i) {
        for (const Cell c : Swept(g.CellAt(s.first[i]), options[i][pick[i]])) {
          if (std::find(all_swept.begin(), all_swept.end(), c) !=
              all_swept.end()) {
            ok = false;
            break;
          }
          all_swept.push_back(c);
        }
      }
      if (ok) {
        State t{std::vector<int>(n), s.second};
        int64_t resting_not = 0;
        for (size_t i = 0; i < n; ++i) {
          t.first[i] = static_cast<int>(g.Index(options[i][pick[i]]));
          const int goal = static_cast<int>(g.Index(robots[i].goal));
          if (s.first[i] != goal || t.first[i] != goal) ++resting_not;
        }
        if (loss) {
          t.second = 0;
          for (size_t i = 0; i < n; ++i) {
            if (t.first[i] == static_cast<int>(g.Index(robots[i].goal)))
              t.second |= 1 << i;
          }
        }
        const int64_t nd = d + (loss ? resting_not : unfinished);
        if (!dist.count(t) || dist[t] > nd) {
          dist[t] = nd;
          open.push({nd, t});
        }
      }
      size_t k = 0;
      while (k < n && ++pick[k] == options[k].size()) pick[k++] = 0;
      if (k == n) break;
    }
  }
  return -1;
}

// LaCAM*'s cost: robot-steps not resting at the goal (this test's own sum).
int64_t SumOfLoss(const FleetProblem& problem, const FleetPlan& plan) {
  int64_t loss = 0;
  for (size_t i = 0; i < plan.paths.size(); ++i) {
    const std::vector<Cell>& p = plan.paths[i];
    for (int64_t t = 0; t < plan.makespan; ++t) {
      const Cell a = p[std::min<size_t>(t, p.size() - 1)];
      const Cell b = p[std::min<size_t>(t + 1, p.size() - 1)];
      if (!(a == problem.robots[i].goal && b == problem.robots[i].goal)) ++loss;
    }
  }
  return loss;
}

TEST(MapfTest, CbsMatchesBruteForceOnTinyInstances) {
  std::mt19937 rng(7);
  const int cases = std::max(4, EnvInt("PATHD_MAPF_CASES", 1000) / 20);
  int solved = 0;
  int refined_better = 0;
  int refined_exhausted = 0;
  int refined_runs = 0;
  for (int k = 0; k < cases; ++k) {
    Instance inst;
    // Three robots on 4x4 and 5x5 only: the joint space grows as cells^3.
    const int robots = k % 3 == 2 ? 3 : 2;
    const int side = 4 + static_cast<int>(rng() % (robots == 3 ? 2 : 3));
    inst.grid = RandomGrid(rng, side, side, 0.2);
    inst.problem.connectivity =
        k % 2 == 0 ? Connectivity::kFour : Connectivity::kEight;
    PlaceRobots(rng, robots, &inst);
    if (inst.problem.robots.size() < 2) continue;
    const std::string what = "tiny case " + std::to_string(k);
    const int64_t best = BruteForce(inst, 3 * side * side);
    const FleetPlan lacam = Solve(inst, FleetSolver::kLacam);
    if (best < 0) {
      EXPECT_NE(lacam.outcome, PlanOutcome::kFound) << what;
      continue;
    }
    ++solved;
    EXPECT_EQ(ExpectValid(inst, lacam, what + " lacam") >= best, true) << what;
    // LaCAM* from the same seed: the same first plan, then never worse in
    // its own cost; with a deadline it returns the best plan in hand.
    {
      FleetOptions options;
      options.solver = FleetSolver::kLacam;
      options.refine = true;
      absl::StatusOr<FleetPlan> refined =
          PlanFleet(inst.problem, options, Within(absl::Milliseconds(50)));
      ASSERT_TRUE(refined.ok()) << refined.status();
      EXPECT_TRUE(refined->outcome == PlanOutcome::kFound ||
                  refined->outcome == PlanOutcome::kTimeout)
          << what;
      ASSERT_TRUE(refined->complete) << what;
      const testing::FleetCheckResult r = Check(inst, *refined);
      EXPECT_TRUE(r.ok) << what << " lacam*: " << r.error;
      EXPECT_GE(refined->sum_of_costs, best) << what;
      EXPECT_LE(SumOfLoss(inst.problem, *refined),
                SumOfLoss(inst.problem, lacam))
          << what;
      if (refined->outcome == PlanOutcome::kFound) {
        // An exhausted LaCAM* search has the least sum of loss.
        EXPECT_EQ(SumOfLoss(inst.problem, *refined),
                  BruteForce(inst, 3 * side * side, true))
            << what;
      }
      refined_better +=
          SumOfLoss(inst.problem, *refined) < SumOfLoss(inst.problem, lacam);
      refined_exhausted += refined->outcome == PlanOutcome::kFound;
      refined_runs += 1;
    }
    const FleetPlan cbs = Solve(inst, FleetSolver::kCbs);
    ASSERT_EQ(cbs.outcome, PlanOutcome::kFound) << what;
    EXPECT_EQ(ExpectValid(inst, cbs, what + " cbs"), best) << what;
    EXPECT_TRUE(cbs.optimal) << what;
    EXPECT_EQ(cbs.lower_bound, best) << what;
    const FleetPlan ecbs = Solve(inst, FleetSolver::kCbs, 1.5);
    ASSERT_EQ(ecbs.outcome, PlanOutcome::kFound) << what;
    const int64_t e = ExpectValid(inst, ecbs, what + " ecbs");
    EXPECT_GE(e, best) << what;
    EXPECT_LE(static_cast<double>(e), 1.5 * static_cast<double>(best)) << what;
    for (const FleetSolver s :
         {FleetSolver::kPrioritized, FleetSolver::kPibt}) {
      const FleetPlan p = Solve(inst, s);
      const int64_t c =
          ExpectValid(inst, p, what + " " + std::string(FleetSolverName(s)));
      if (c >= 0) {
        EXPECT_GE(c, best) << what;
      }
    }
  }
  EXPECT_GT(solved, cases / 2);
  std::printf(
      "lacam*: %d of %d runs exhausted the search, %d improved on lacam\n",
      refined_exhausted, refined_runs, refined_better);
}

// The low level alone: space-time A* (and focal search) under random CBS
// constraints against this test's own breadth-first search over (cell,
// time) layers, many constraints on the goal so the earliest stop matters.
TEST(MapfTest, SpaceTimeSearchMatchesLayeredSearch) {
  using namespace mapf_internal;  // NOLINT: the test of these internals
  std::mt19937 rng(13);
  const int cases = std::max(20, EnvInt("PATHD_MAPF_CASES", 1000) / 2);
  for (int k = 0; k < cases; ++k) {
    const int side = 4 + static_cast<int>(rng() % 5);
    Grid grid = RandomGrid(rng, side, side, 0.2);
    const bool eight = k % 2 == 1;
    std::vector<Cell> comp = LargestComponent(grid);
    if (comp.size() < 2) continue;
    std::shuffle(comp.begin(), comp.end(), rng);
    const Cell start = comp[0];
    const Cell goal = k % 7 == 0 ? comp[0] : comp[1];
    const MoveGraph graph(
        grid, eight ? Connectivity::kEight : Connectivity::kFour, false);
    const size_t cells = grid.size();
    ConstraintSet cons;
    std::set<std::pair<uint32_t, int32_t>> banned;  // (cell, step)
    const int n = static_cast<int>(rng() % 25);
    for (int c = 0; c < n; ++c) {
      const Cell at = c % 3 == 0 ? goal : comp[rng() % comp.size()];
      const auto t = static_cast<int32_t>(rng() % 16);
      cons.Add(static_cast<uint32_t>(grid.Index(at)), t, cells);
      banned.insert({static_cast<uint32_t>(grid.Index(at)), t});
    }
    // Layers of the cells reachable at t without sweeping a banned cell.
    auto swept = [&](Cell a, Cell b) {
      std::vector<uint32_t> out;
      for (const Cell c : Swept(a, b))
        out.push_back(static_cast<uint32_t>(grid.Index(c)));
      return out;
    };
    int32_t last_goal = -1;
    for (const auto& [c, t] : banned) {
      if (c == grid.Index(goal)) last_goal = std::max(last_goal, t);
    }
    int expected = -1;
    std::set<uint32_t> layer{static_cast<uint32_t>(grid.Index(start))};
    const int horizon = 20 + static_cast<int>(cells);
    for (int t = 0; t <= horizon && !layer.empty(); ++t) {
      // At the goal at t and never sweeping a banned cell by staying.
      if (layer.count(static_cast<uint32_t>(grid.Index(goal))) != 0 &&
          t > last_goal) {
        expected = t;
        break;
      }
      std::set<uint32_t> next;
      for (const uint32_t u : layer) {
        const Cell a = grid.CellAt(u);
        for (int dx = -1; dx <= 1; ++dx) {
          for (int dy = -1; dy <= 1; ++dy) {
            const Cell b{a.x + dx, a.y + dy};
            if (!Free(grid, b.x, b.y)) continue;
            if (dx != 0 && dy != 0 &&
                (!eight || !Free(grid, b.x, a.y) || !Free(grid, a.x, b.y))) {
              continue;
            }
            bool ok = true;
            for (const uint32_t c : swept(a, b))
              ok = ok && banned.count({c, t}) == 0;
            if (ok) next.insert(static_cast<uint32_t>(grid.Index(b)));
          }
        }
      }
      layer = std::move(next);
    }
    int32_t exact = kUnreachable;
    BfsScratch scratch;
    const DistanceTable h = graph.DistancesTo(
        static_cast<uint32_t>(grid.Index(goal)),
        static_cast<uint32_t>(grid.Index(start)), &exact, &scratch);
    for (const double w : {1.0, 1.5}) {
      LowLevelQuery q;
      q.graph = &graph;
      q.h = &h;
      q.start = static_cast<uint32_t>(grid.Index(start));
      q.goal = static_cast<uint32_t>(grid.Index(goal));
      q.constraints = &cons;
      q.max_steps = horizon;
      q.w = w;
      int64_t expansions = 0;
      const LowLevelResult r =
          SpaceTimeSearch(q, StopCondition::None(), &expansions);
      const std::string what =
          "case " + std::to_string(k) + " w " + std::to_string(w);
      if (expected < 0) {
        EXPECT_NE(r.outcome, PlanOutcome::kFound) << what;
        continue;
      }
      ASSERT_EQ(r.outcome, PlanOutcome::kFound) << what;
      if (w == 1.0) {
        EXPECT_EQ(r.cost, expected) << what;
      } else {
        EXPECT_GE(r.cost, expected) << what;
        EXPECT_LE(r.cost, w * expected + 1e-9) << what;
      }
      EXPECT_LE(r.lower_bound, expected) << what;
      // The path itself: legal and never sweeping a banned cell, parked
      // after its end.
      ASSERT_FALSE(r.path.empty());
      EXPECT_EQ(r.path.front(), q.start) << what;
      EXPECT_EQ(r.path.back(), q.goal) << what;
      for (int32_t t = 0; t < horizon; ++t) {
        const size_t i = std::min<size_t>(t, r.path.size() - 1);
        const size_t j = std::min<size_t>(t + 1, r.path.size() - 1);
        for (const uint32_t c :
             swept(grid.CellAt(r.path[i]), grid.CellAt(r.path[j]))) {
          EXPECT_EQ(banned.count({c, t}), 0u) << what << " step " << t;
        }
      }
    }
  }
}

TEST(MapfTest, RandomInstancesCheckedForEverySolver) {
  std::mt19937 rng(21);
  const int cases = EnvInt("PATHD_MAPF_CASES", 1000);
  std::map<std::string, std::pair<int, int>> found;  // solver -> (found, run)
  std::map<std::string, double> seconds;             // printed, not asserted
  for (int k = 0; k < cases; ++k) {
    Instance inst;
    const int side = 16 + static_cast<int>(rng() % 49);  // 16..64
    const bool rooms = rng() % 2 == 0;
    inst.grid =
        rooms ? RoomGrid(rng, side, side, 6 + static_cast<int>(rng() % 6))
              : RandomGrid(rng, side, side, 0.1 + 0.2 * (rng() % 100) / 100.0);
    inst.problem.connectivity =
        rng() % 3 == 0 ? Connectivity::kFour : Connectivity::kEight;
    const auto solver = static_cast<FleetSolver>(k % 4);
    // CBS (and ECBS) only on few robots and small maps: it is exponential.
    int robots = 4 + static_cast<int>(rng() % 61);
    double w = 1.0;
    if (solver == FleetSolver::kCbs) {
      inst.grid = RandomGrid(rng, 16, 16, 0.1 + 0.1 * (rng() % 2));
      robots = 4 + static_cast<int>(rng() % 5);
      w = k % 8 == 1 ? 1.0 : 1.3;
    }
    // At most one robot per 4 free cells: denser random sets under the
    // no-following rule are often unsolvable, and proving that takes long.
    PlaceRobots(rng, robots, &inst, 4);
    const std::string what = "case " + std::to_string(k) + " " +
                             std::string(FleetSolverName(solver)) + " robots " +
                             std::to_string(inst.problem.robots.size());
    const absl::Time t0 = absl::Now();
    // A short deadline and few restarts: the instances that need more are
    // few, and this test checks plans rather than success rates.
    const FleetPlan plan = Solve(inst, solver, w, absl::Milliseconds(100), 3);
    const std::string key =
        std::string(FleetSolverName(solver)) + (w > 1 ? " w=1.3" : "");
    seconds[key] += absl::ToDoubleSeconds(absl::Now() - t0);
    auto& f = found[key];
    ++f.second;
    if (ExpectValid(inst, plan, what) >= 0) {
      ++f.first;
    } else if (std::getenv("PATHD_MAPF_VERBOSE") != nullptr) {
      std::printf("%s: %s side %d rooms %d iterations %lld expansions %lld\n",
                  what.c_str(),
                  std::string(PlanOutcomeName(plan.outcome)).c_str(), side,
                  rooms ? 1 : 0, static_cast<long long>(plan.iterations),
                  static_cast<long long>(plan.expansions));
    }
    if (solver == FleetSolver::kCbs && plan.outcome == PlanOutcome::kFound &&
        w > 1) {
      EXPECT_LE(static_cast<double>(plan.sum_of_costs),
                w * static_cast<double>(plan.lower_bound) + 1e-9)
          << what;
    }
    if (HasFailure()) return;
  }
  for (const auto& [name, f] : found) {
    std::printf("%s: %d of %d solved, %.2f s\n", name.c_str(), f.first,
                f.second, seconds[name]);
    EXPECT_GT(f.first, 0) << name;
  }
}

TEST(MapfTest, CbsNoWorseThanPrioritizedAndSeedsRepeat) {
  std::mt19937 rng(5);
  const int cases = std::max(4, EnvInt("PATHD_MAPF_CASES", 1000) / 50);
  for (int k = 0; k < cases; ++k) {
    Instance inst;
    inst.grid = RandomGrid(rng, 10, 10, 0.15);
    PlaceRobots(rng, 5, &inst);
    const std::string what = "case " + std::to_string(k);
    const FleetPlan pri = Solve(inst, FleetSolver::kPrioritized);
    const FleetPlan cbs = Solve(inst, FleetSolver::kCbs);
    const int64_t p = ExpectValid(inst, pri, what + " prioritized");
    const int64_t c = ExpectValid(inst, cbs, what + " cbs");
    if (p >= 0 && c >= 0) {
      EXPECT_LE(c, p) << what;
    }
    for (const FleetSolver s :
         {FleetSolver::kLacam, FleetSolver::kPrioritized}) {
      const FleetPlan a = Solve(inst, s);
      const FleetPlan b = Solve(inst, s);
      EXPECT_EQ(a.paths, b.paths) << what << " " << FleetSolverName(s);
    }
  }
}

// Robots of two sizes: the larger ones' grid has a wall with one door the
// smaller ones may also pass beside. Every solver's plan is checked against
// each robot's own grid.
TEST(MapfTest, RobotsOnDifferentGrids) {
  Grid small = Grid::Create(12, 12).value();
  for (int y = 0; y < 12; ++y) {
    if (y != 5 && y != 6) small.set_cost(6, y, kLethalCost);
  }
  Grid large = small;
  large.set_cost(6, 6, kLethalCost);
  std::mt19937 rng(9);
  for (int k = 0; k < 10; ++k) {
    Instance inst;
    inst.grid = small;
    // Six robots: CBS needs up to ~900 nodes for eight through the door.
    PlaceRobots(rng, 6, &inst);
    inst.problem.grids = {&small, &large};
    inst.individual = 0;
    for (size_t i = 0; i < inst.problem.robots.size(); ++i) {
      FleetRobot& r = inst.problem.robots[i];
      // A larger robot only where its grid is open at both ends.
      if (i % 2 == 1 && Free(large, r.start.x, r.start.y) &&
          Free(large, r.goal.x, r.goal.y)) {
        r.grid = 1;
      }
      inst.individual +=
          BfsSteps(*inst.problem.grids[r.grid], r.start, r.goal, true);
    }
    for (int s = 0; s < 4; ++s) {
      const FleetPlan plan = Solve(inst, static_cast<FleetSolver>(s));
      EXPECT_EQ(plan.outcome, PlanOutcome::kFound)
          << "case " << k << " "
          << FleetSolverName(static_cast<FleetSolver>(s));
      ExpectValid(
          inst, plan,
          "case " + std::to_string(k) + " " +
              std::string(FleetSolverName(static_cast<FleetSolver>(s))));
    }
  }
}

// Regression: a robot whose diagonal to its goal was blocked only by
// robots resting on its side cells never asked them to move (PIBT's
// inheritance looked at the target cell alone), so all three stayed until
// max_steps.
TEST(MapfTest, PibtAsksSideCellOccupantsToMove) {
  Instance inst;
  inst.grid = Grid::Create(3, 3).value();
  inst.problem.grids = {&inst.grid};
  inst.problem.robots = {
      {{0, 0}, {1, 1}, 0}, {{1, 0}, {1, 0}, 0}, {{0, 1}, {0, 1}, 0}};
  inst.individual = 1;
  for (const FleetSolver s : {FleetSolver::kPibt, FleetSolver::kLacam}) {
    const FleetPlan plan = Solve(inst, s);
    EXPECT_EQ(plan.outcome, PlanOutcome::kFound) << FleetSolverName(s);
    ExpectValid(inst, plan, std::string(FleetSolverName(s)));
  }
}

std::filesystem::path MovingAiDir() {
  if (const char* env = std::getenv("PATHD_MOVINGAI_DIR")) return env;
  for (const char* p :
       {"../shared/benchmarks/movingai", "/work/shared/benchmarks/movingai"}) {
    if (std::filesystem::is_directory(p)) return p;
  }
  return {};
}

TEST(MapfTest, MovingAiMapsWithManyRobots) {
  const std::filesystem::path dir = MovingAiDir();
  if (dir.empty()) {
    GTEST_SKIP() << "no Moving AI maps (expected ../shared/benchmarks/movingai "
                    "beside the project or PATHD_MOVINGAI_DIR)";
  }
  const bool small = EnvInt("PATHD_MAPF_CASES", 1000) < 1000;
  std::mt19937 rng(3);
  // Each run builds one distance table per robot (a BFS over 512 x 512), so
  // two solvers a map keep this test short.
  const std::pair<const char*, std::vector<FleetSolver>> runs[] = {
      {"random/random512-10-0.map",
       {FleetSolver::kLacam, FleetSolver::kPrioritized}},
      {"room/32room_000.map", {FleetSolver::kLacam, FleetSolver::kPibt}}};
  for (const auto& [name, solvers] : runs) {
    absl::StatusOr<Grid> grid = ReadMovingAiMapFile((dir / name).string());
    ASSERT_TRUE(grid.ok()) << grid.status();
    Instance inst;
    inst.grid = *std::move(grid);
    PlaceRobots(rng, small ? 20 : 50, &inst);
    for (const FleetSolver s : solvers) {
      const std::string what =
          std::string(name) + " " + std::string(FleetSolverName(s));
      const FleetPlan plan = Solve(inst, s, 1.0, absl::Seconds(20));
      EXPECT_GE(ExpectValid(inst, plan, what), 0)
          << what << ": " << PlanOutcomeName(plan.outcome);
    }
  }
}

TEST(MapfTest, BadInputs) {
  Instance inst;
  inst.grid = Grid::Create(8, 8).value();
  inst.problem.grids = {&inst.grid};
  FleetOptions options;
  inst.problem.robots = {{{0, 0}, {5, 5}, 0}, {{0, 0}, {6, 6}, 0}};
  absl::StatusOr<FleetPlan> plan =
      PlanFleet(inst.problem, options, StopCondition::None());
  EXPECT_EQ(plan.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(plan.status().message().find("robots[1].start"), std::string::npos)
      << plan.status();
  inst.problem.robots = {{{0, 0}, {5, 5}, 0}, {{1, 0}, {5, 5}, 0}};
  plan = PlanFleet(inst.problem, options, StopCondition::None());
  EXPECT_EQ(plan.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(plan.status().message().find("robots[1].goal"), std::string::npos);
  inst.problem.robots = {{{0, 0}, {5, 5}, 2}};
  EXPECT_EQ(
      PlanFleet(inst.problem, options, StopCondition::None()).status().code(),
      absl::StatusCode::kInvalidArgument);
  inst.problem.robots = {{{0, 0}, {9, 5}, 0}};
  EXPECT_EQ(
      PlanFleet(inst.problem, options, StopCondition::None()).status().code(),
      absl::StatusCode::kInvalidArgument);
  // A wall cuts off robot 1's goal: kNoPath from every solver.
  for (int y = 0; y < 8; ++y) inst.grid.set_cost(4, y, kLethalCost);
  inst.problem.robots = {{{0, 0}, {1, 1}, 0}, {{0, 7}, {6, 6}, 0}};
  for (int s = 0; s < 4; ++s) {
    options.solver = static_cast<FleetSolver>(s);
    plan = PlanFleet(inst.problem, options, StopCondition::None());
    ASSERT_TRUE(plan.ok()) << plan.status();
    EXPECT_EQ(plan->outcome, PlanOutcome::kNoPath)
        << FleetSolverName(options.solver);
  }
}

TEST(MapfTest, PastDeadlineStopsPromptly) {
  std::mt19937 rng(11);
  Instance inst;
  inst.grid = RandomGrid(rng, 64, 64, 0.2);
  PlaceRobots(rng, 60, &inst);
  const StopCondition past(absl::Now() - absl::Seconds(1), nullptr, 0);
  for (int s = 0; s < 4; ++s) {
    FleetOptions options;
    options.solver = static_cast<FleetSolver>(s);
    const absl::Time t0 = absl::Now();
    absl::StatusOr<FleetPlan> plan = PlanFleet(inst.problem, options, past);
    ASSERT_TRUE(plan.ok()) << plan.status();
    EXPECT_EQ(plan->outcome, PlanOutcome::kTimeout)
        << FleetSolverName(options.solver);
    EXPECT_FALSE(plan->complete);
    EXPECT_TRUE(plan->paths.empty());
    // Stopped before the distance tables were built, no bound is known.
    EXPECT_EQ(plan->lower_bound, 0);
    // Not a timing assertion: the figure is printed for the reader.
    std::printf("%s stopped after %.1f ms\n",
                std::string(FleetSolverName(options.solver)).c_str(),
                absl::ToDoubleMilliseconds(absl::Now() - t0));
  }
  // An expansion budget stops every solver inside its search, after the
  // distance tables: the bound is then known.
  for (int s = 0; s < 4; ++s) {
    FleetOptions options;
    options.solver = static_cast<FleetSolver>(s);
    absl::StatusOr<FleetPlan> plan =
        PlanFleet(inst.problem, options,
                  StopCondition(absl::InfiniteFuture(), nullptr, 64));
    ASSERT_TRUE(plan.ok()) << plan.status();
    EXPECT_EQ(plan->outcome, PlanOutcome::kExpansionLimit)
        << FleetSolverName(options.solver);
    EXPECT_FALSE(plan->complete);
    EXPECT_GE(plan->lower_bound, inst.individual)
        << FleetSolverName(options.solver);
  }
  // A cancelled CBS search stops too.
  std::atomic<bool> cancelled{true};
  FleetOptions options;
  options.solver = FleetSolver::kCbs;
  absl::StatusOr<FleetPlan> plan =
      PlanFleet(inst.problem, options,
                StopCondition(absl::InfiniteFuture(), &cancelled, 0));
  ASSERT_TRUE(plan.ok());
  EXPECT_EQ(plan->outcome, PlanOutcome::kCancelled);
}

}  // namespace
}  // namespace pathd
