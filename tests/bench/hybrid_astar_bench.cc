// hybrid_astar_bench: Hybrid A* on a warehouse a Nav2 user would recognise,
// in figures.
//  - The map: 1000 x 1000 cells at 0.05 m (50 m x 50 m), generated: racks
//    1 m deep and 15 m long in rows with 2.5 m aisles, 4 m cross aisles, a
//    staging area with pallets. The robot: a 0.6 m x 0.4 m rectangle about
//    its centre, turning on 0.4 m (Nav2 Smac's default
//    minimum_turning_radius), Reeds-Shepp or Dubins.
//  - (a) Planning time between random poses, per goal twice: the first
//    query builds the obstacle heuristic (no derived store, as a robot
//    linking core would), the second plans from another start towards the
//    same goal with the field from the store (as the server's per-version
//    cache keeps it), and a third without the store for the same pair.
//  - (b) The same Reeds-Shepp queries given to OMPL's sampling planners
//    (RRTConnect, RRT*, InformedRRT*, BIT*) through SimpleSetup on a
//    ReedsSheppStateSpace whose state validity checker is the same
//    FootprintChecker: time to the first solution and its length, against
//    hybrid_astar's (unsmoothed, the field from the store), and state_lattice's
//    on the same queries (at --lattice_weight, the server's default).
// Figures, not assertions.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <ompl/base/ScopedState.h>
#include <ompl/base/spaces/ReedsSheppStateSpace.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/informedtrees/BITstar.h>
#include <ompl/geometric/planners/rrt/InformedRRTstar.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/geometric/planners/rrt/RRTstar.h>
#include <ompl/util/Console.h>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "absl/time/clock.h"
#include "core/kinematics/footprint.h"
#include "core/kinematics/obstacle_heuristic.h"
#include "core/kinematics/vehicle.h"
#include "core/planners/kinematic/hybrid_astar.h"
#include "core/planners/kinematic/state_lattice.h"
#include "core/search/derived.h"
#include "core/search/stop_condition.h"

ABSL_FLAG(int, goals, 20, "goals for (a); each planned from two starts");
ABSL_FLAG(int, ompl_queries, 10, "Reeds-Shepp queries for (b)");
ABSL_FLAG(double, ompl_timeout, 20.0, "seconds an OMPL planner gets per query");
ABSL_FLAG(std::string, ompl_planners, "RRTConnect,RRTstar,InformedRRTstar,BITstar",
          "OMPL planners for (b)");
ABSL_FLAG(int, seed, 1, "random seed for the poses");
ABSL_FLAG(bool, verbose, false, "print every query of (a)");
ABSL_FLAG(double, analytic_slack, 1.2, "HybridAStarOptions::analytic_slack");
ABSL_FLAG(double, curve_radii, 2.0, "HybridAStarOptions::curve_heuristic_radii");
ABSL_FLAG(bool, curve_table, true, "HybridAStarOptions::curve_table");
ABSL_FLAG(double, lattice_weight, 1.5,
          "state_lattice's heuristic_weight in (b) (the server's default, 1.5)");

namespace pathd {
namespace {

namespace ob = ompl::base;
namespace og = ompl::geometric;

constexpr double kPi = std::numbers::pi;
constexpr double kResolution = 0.05;

// The warehouse, 1000 x 1000 cells.
Grid Warehouse(std::mt19937& rng) {
  Grid grid = Grid::Create(1000, 1000).value();
  grid.set_resolution(kResolution);
  const auto fill = [&grid](int x0, int y0, int x1, int y1) {
    for (int y = std::max(0, y0); y < std::min(1000, y1); ++y) {
      for (int x = std::max(0, x0); x < std::min(1000, x1); ++x) grid.set_cost(x, y, kLethalCost);
    }
  };
  // Walls.
  fill(0, 0, 1000, 4);
  fill(0, 996, 1000, 1000);
  fill(0, 0, 4, 1000);
  fill(996, 0, 1000, 1000);
  // Racks: 20 cells deep, 300 long; rows every 70 cells (a 50-cell aisle);
  // three columns of racks with 80-cell cross aisles between them.
  for (int y = 120; y + 20 <= 960; y += 70) {
    for (const auto& [x, length] : {std::pair{60, 300}, {440, 300}, {820, 140}}) {
      fill(x, y, x + length, y + 20);
    }
  }
  // Staging area along the bottom: pallets 1.2 m x 1 m, scattered.
  std::uniform_int_distribution<int> px(20, 960), py(10, 90);
  for (int i = 0; i < 40; ++i) {
    const int x = px(rng), y = py(rng);
    fill(x, y, x + 24, y + 20);
  }
  // Columns of the building every 10 m.
  for (int y = 200; y < 1000; y += 200) {
    for (int x = 0; x < 1000; x += 200) {
      if (grid.cost(x, y) == kFreeCost) fill(x - 4, y - 4, x + 4, y + 4);
    }
  }
  return grid;
}

// A random pose where the robot fits with 0.2 m to spare (where a robot
// would be sent, not squeezed against a wall), heading along the aisles or
// anywhere.
Pose FreePose(std::mt19937& rng, const Grid& grid, const FootprintChecker& checker,
              const std::vector<float>& distance) {
  static const auto* const spare = new std::shared_ptr<const FootprintChecker>(
      SharedFootprintChecker(checker.footprint(), {.margin_cells = 0.2 / kResolution}).value());
  std::uniform_real_distribution<double> u(0.0, 1.0);
  while (true) {
    const double yaw = rng() % 2 == 0 ? (rng() % 2 == 0 ? 0.0 : kPi) : 2 * kPi * u(rng) - kPi;
    const Pose p{10 + 980 * u(rng), 10 + 980 * u(rng), yaw};
    if (!(*spare)->Collides(grid, p, false, distance.data())) return p;
  }
}

// The server's derived cache reduced to one map version.
class OneVersionStore final : public DerivedStore {
 public:
  explicit OneVersionStore(const Grid& grid) : grid_(grid) {}
  std::shared_ptr<const void> Get(const std::string& key, const DerivedRecipe& recipe,
                                  DerivedStop& stop) override {
    auto& slot = values_[key];
    if (slot == nullptr) slot = recipe.build(grid_, stop);
    return slot;
  }

 private:
  const Grid& grid_;
  std::map<std::string, std::shared_ptr<const void>> values_;
};

double Ms(absl::Duration d) { return absl::ToDoubleMilliseconds(d); }

HybridAStarOptions Options() {
  HybridAStarOptions o;
  o.analytic_slack = absl::GetFlag(FLAGS_analytic_slack);
  o.curve_heuristic_radii = absl::GetFlag(FLAGS_curve_radii);
  o.curve_table = absl::GetFlag(FLAGS_curve_table);
  return o;
}

struct Stats {
  std::vector<double> values;
  void Add(double v) { values.push_back(v); }
  double Percentile(double p) {
    if (values.empty()) return 0.0;
    std::sort(values.begin(), values.end());
    return values[std::min(values.size() - 1, static_cast<size_t>(p * values.size()))];
  }
  double Mean() const {
    double s = 0.0;
    for (double v : values) s += v;
    return values.empty() ? 0.0 : s / values.size();
  }
};

PlanRequest RequestFor(const KinematicQuery& q, DerivedStore* store) {
  PlanRequest r = PlanRequest::Between(q.start.cell(), q.goal.cell());
  r.kinematic = std::make_shared<KinematicQuery>(q);
  r.derived = store;
  return r;
}

KinematicQuery Robot(MotionModel motion, std::shared_ptr<const FootprintChecker> checker) {
  KinematicQuery q;
  q.footprint = std::move(checker);
  q.motion = motion;
  q.min_turning_radius_cells = 0.4 / kResolution;
  return q;
}

// What a query without the store builds first: the obstacle distance field
// (per map version) and the goal's obstacle heuristic (per goal).
void Builds(const Grid& grid, const FootprintChecker& checker) {
  Stats field, heuristic;
  std::mt19937 rng(absl::GetFlag(FLAGS_seed));
  std::vector<float> distance;
  for (int i = 0; i < 5; ++i) {
    absl::Time t = absl::Now();
    distance = ObstacleDistanceField(grid, false);
    field.Add(Ms(absl::Now() - t));
    ObstacleHeuristicParams params;
    params.goal = FreePose(rng, grid, checker, distance).cell();
    params.cost_penalty = 2.0;
    params.blocked_within =
        std::max(0.0, checker.footprint().inscribed_radius() - std::numbers::sqrt2 / 2.0);
    DerivedStop never;
    t = absl::Now();
    (void)BuildObstacleHeuristic(grid, params, distance.data(), never);
    heuristic.Add(Ms(absl::Now() - t));
  }
  std::printf("\nBuilt per query without a store (median of 5, ms): obstacle distance field "
              "%.1f, obstacle heuristic of one goal %.1f\n",
              field.Percentile(0.5), heuristic.Percentile(0.5));
}

void PartA(const Grid& grid, std::shared_ptr<const FootprintChecker> checker,
           const std::vector<float>& distance) {
  Builds(grid, *checker);
  std::printf("\n(a) hybrid_astar, %d goals, two starts each (ms; expansions)\n\n",
              absl::GetFlag(FLAGS_goals));
  std::printf("| motion | smooth | field built (1st query) | field from store (2nd) | "
              "same pair, field built | expansions (median) | found |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (const MotionModel motion : {MotionModel::kReedsShepp, MotionModel::kDubins}) {
    for (const bool smooth : {false, true}) {
      std::mt19937 rng(absl::GetFlag(FLAGS_seed));
      Stats cold, warm, rebuilt, expansions;
      int found = 0, planned = 0;
      for (int g = 0; g < absl::GetFlag(FLAGS_goals); ++g) {
        KinematicQuery q = Robot(motion, checker);
        q.smooth = smooth;
        q.goal = FreePose(rng, grid, *checker, distance);
        const Pose first = FreePose(rng, grid, *checker, distance);
        const Pose second = FreePose(rng, grid, *checker, distance);
        OneVersionStore store(grid);
        // The obstacle distance field is per map version, not per goal:
        // the store has it before the first query of a goal, as the server's
        // cache would after any query on the map.
        (void)GetObstacleDistance(&store, grid, false);
        q.start = first;
        absl::Time t = absl::Now();
        auto a = PlanHybridAStar(grid, RequestFor(q, &store), StopCondition::None(), Options());
        cold.Add(Ms(absl::Now() - t));
        q.start = second;
        t = absl::Now();
        auto b = PlanHybridAStar(grid, RequestFor(q, &store), StopCondition::None(), Options());
        warm.Add(Ms(absl::Now() - t));
        t = absl::Now();
        auto c = PlanHybridAStar(grid, RequestFor(q, nullptr), StopCondition::None(), Options());
        rebuilt.Add(Ms(absl::Now() - t));
        if (absl::GetFlag(FLAGS_verbose)) {
          for (const auto* r : {&a, &b}) {
            std::printf("  goal %d (%.1f %.1f %.2f): %s, %lld expansions, length %.0f, %.1f ms\n", g, q.goal.x, q.goal.y, q.goal.yaw,
                        std::string(PlanOutcomeName((*r)->outcome)).c_str(),
                        static_cast<long long>((*r)->expansions), (*r)->length,
                        Ms((*r)->planning_time));
          }
        }
        for (const auto* r : {&a, &b}) {
          ++planned;
          if (r->ok() && (*r)->found()) {
            ++found;
            expansions.Add(static_cast<double>((*r)->expansions));
          }
        }
      }
      std::printf("| %s | %s | %.1f median, %.1f p90 | %.1f median, %.1f p90 | %.1f median | "
                  "%.0f | %d / %d |\n",
                  std::string(MotionModelName(motion)).c_str(), smooth ? "yes" : "no",
                  cold.Percentile(0.5), cold.Percentile(0.9), warm.Percentile(0.5),
                  warm.Percentile(0.9), rebuilt.Percentile(0.5), expansions.Percentile(0.5),
                  found, planned);
    }
  }
}

// One OMPL planner on one query: time to its first solution and that
// solution's length (cells), and time until its solution was no longer
// than `target` (hybrid_astar's); -1 for what did not happen within the
// timeout.
struct OmplRun {
  double first_ms = -1.0;
  double first_length = -1.0;
  double target_ms = -1.0;
};

OmplRun RunOmpl(const std::string& name, const Grid& grid, const FootprintChecker& checker,
                const std::vector<float>& distance, const Pose& start, const Pose& goal,
                double radius, double target) {
  auto space = std::make_shared<ob::ReedsSheppStateSpace>(radius);
  ob::RealVectorBounds bounds(2);
  bounds.setLow(0, 0.0);
  bounds.setHigh(0, grid.width());
  bounds.setLow(1, 0.0);
  bounds.setHigh(1, grid.height());
  space->setBounds(bounds);
  og::SimpleSetup setup(space);
  setup.setStateValidityChecker([&](const ob::State* s) {
    const auto* se2 = s->as<ob::SE2StateSpace::StateType>();
    return !checker.Collides(grid, Pose{se2->getX(), se2->getY(), se2->getYaw()}, false,
                             distance.data());
  });
  // Motions checked every 0.25 cells along the Reeds-Shepp curve (as a
  // fraction of the space's extent).
  setup.getSpaceInformation()->setStateValidityCheckingResolution(
      0.25 / space->getMaximumExtent());
  ob::ScopedState<> s(space), g(space);
  s->as<ob::SE2StateSpace::StateType>()->setXY(start.x, start.y);
  s->as<ob::SE2StateSpace::StateType>()->setYaw(start.yaw);
  g->as<ob::SE2StateSpace::StateType>()->setXY(goal.x, goal.y);
  g->as<ob::SE2StateSpace::StateType>()->setYaw(goal.yaw);
  // OMPL's headings are in [-pi, pi): a heading of pi becomes -pi.
  space->enforceBounds(s.get());
  space->enforceBounds(g.get());
  // Reached within half a cell in the Reeds-Shepp metric.
  setup.setStartAndGoalStates(s, g, 0.5);
  const auto si = setup.getSpaceInformation();
  if (name == "RRTConnect") {
    setup.setPlanner(std::make_shared<og::RRTConnect>(si));
  } else if (name == "RRTstar") {
    setup.setPlanner(std::make_shared<og::RRTstar>(si));
  } else if (name == "InformedRRTstar") {
    setup.setPlanner(std::make_shared<og::InformedRRTstar>(si));
  } else if (name == "BITstar") {
    setup.setPlanner(std::make_shared<og::BITstar>(si));
  } else {
    std::fprintf(stderr, "unknown OMPL planner %s\n", name.c_str());
    return {};
  }
  setup.setup();
  // RRTConnect returns one solution, as exact; the asymptotically optimal
  // planners report each better solution (its cost is its length, the
  // default objective) through the intermediate-solution callback and go
  // on until the target length or the timeout.
  const absl::Time started = absl::Now();
  OmplRun run;
  std::atomic<bool> done{false};
  setup.getProblemDefinition()->setIntermediateSolutionCallback(
      [&](const ob::Planner*, const std::vector<const ob::State*>&, const ob::Cost cost) {
        const double ms = Ms(absl::Now() - started);
        if (run.first_ms < 0) {
          run.first_ms = ms;
          run.first_length = cost.value();
        }
        if (cost.value() <= target && run.target_ms < 0) {
          run.target_ms = ms;
          done.store(true);
        }
      });
  const ob::PlannerTerminationCondition stop = ob::plannerOrTerminationCondition(
      ob::timedPlannerTerminationCondition(absl::GetFlag(FLAGS_ompl_timeout)),
      ob::PlannerTerminationCondition([&done] { return done.load(); }));
  const ob::PlannerStatus status =
      name == "RRTConnect"
          ? setup.solve(ob::plannerOrTerminationCondition(
                stop, ob::exactSolnPlannerTerminationCondition(setup.getProblemDefinition())))
          : setup.solve(stop);
  if (run.first_ms < 0 && status == ob::PlannerStatus::EXACT_SOLUTION) {
    run.first_ms = Ms(absl::Now() - started);
    run.first_length = setup.getSolutionPath().length();
    if (run.first_length <= target) run.target_ms = run.first_ms;
  }
  return run;
}

void PartB(const Grid& grid, std::shared_ptr<const FootprintChecker> checker,
           const std::vector<float>& distance) {
  const std::vector<std::string> planners =
      absl::StrSplit(absl::GetFlag(FLAGS_ompl_planners), ',', absl::SkipEmpty());
  std::printf("\n(b) Reeds-Shepp, %d queries: hybrid_astar's time and length; for each OMPL "
              "planner the time to its first solution / that solution's length, and the "
              "time until its solution was no longer than hybrid_astar's (%.0f s each)\n\n",
              absl::GetFlag(FLAGS_ompl_queries), absl::GetFlag(FLAGS_ompl_timeout));
  std::printf("| query | straight line | hybrid_astar ms / length | state_lattice ms / length |");
  for (const std::string& p : planners) std::printf(" %s first ms / length; as short, ms |", p.c_str());
  std::printf("\n|---|---|---|---|");
  for (size_t i = 0; i < planners.size(); ++i) std::printf("---|");
  std::printf("\n");
  std::mt19937 rng(absl::GetFlag(FLAGS_seed) + 1000);
  std::map<std::string, Stats> first_ratio, length_ratio, target_ratio;
  std::map<std::string, Stats> lattice_first_ratio, lattice_length_ratio;
  std::map<std::string, int> solved, reached;
  int hybrid_found = 0;
  int lattice_found = 0;
  OneVersionStore store(grid);
  for (int i = 0; i < absl::GetFlag(FLAGS_ompl_queries); ++i) {
    KinematicQuery q = Robot(MotionModel::kReedsShepp, checker);
    q.smooth = false;
    q.start = FreePose(rng, grid, *checker, distance);
    q.goal = FreePose(rng, grid, *checker, distance);
    // The field of this goal is built once, outside the timing, as the
    // server's store holds it after the goal's first query; (a) has the
    // cost of building it.
    (void)PlanHybridAStar(grid, RequestFor(q, &store), StopCondition::None(), Options());
    const absl::Time t = absl::Now();
    auto r = PlanHybridAStar(grid, RequestFor(q, &store), StopCondition::None(), Options());
    const double hybrid_ms = Ms(absl::Now() - t);
    const bool found = r.ok() && r->found();
    hybrid_found += found;
    // state_lattice on the same query, its control set (generated for this
    // radius) and field made by a first run outside the timing.
    PlanRequest lattice_request = RequestFor(q, &store);
    lattice_request.heuristic_weight = absl::GetFlag(FLAGS_lattice_weight);
    (void)PlanStateLattice(grid, lattice_request, StopCondition::None());
    const absl::Time tl = absl::Now();
    auto l = PlanStateLattice(grid, lattice_request, StopCondition::None());
    const double lattice_ms = Ms(absl::Now() - tl);
    const bool lattice_ok = l.ok() && l->found();
    lattice_found += lattice_ok;
    std::printf("| %d | %.0f | %s | %s |", i,
                std::hypot(q.goal.x - q.start.x, q.goal.y - q.start.y),
                found ? absl::StrFormat("%.1f / %.0f", hybrid_ms, r->length).c_str() : "none",
                lattice_ok ? absl::StrFormat("%.1f / %.0f", lattice_ms, l->length).c_str()
                           : "none");
    for (const std::string& p : planners) {
      const OmplRun run = RunOmpl(p, grid, *checker, distance, q.start, q.goal,
                                  q.min_turning_radius_cells, found ? r->length : 0.0);
      if (run.first_ms < 0) {
        std::printf(" none |");
        continue;
      }
      ++solved[p];
      std::printf(" %.1f / %.0f; %s |", run.first_ms, run.first_length,
                  run.target_ms < 0 ? "not within the timeout"
                                    : absl::StrFormat("%.1f", run.target_ms).c_str());
      if (lattice_ok) {
        lattice_first_ratio[p].Add(run.first_ms / lattice_ms);
        lattice_length_ratio[p].Add(run.first_length / l->length);
      }
      if (!found) continue;
      first_ratio[p].Add(run.first_ms / hybrid_ms);
      length_ratio[p].Add(run.first_length / r->length);
      if (run.target_ms >= 0) {
        ++reached[p];
        target_ratio[p].Add(run.target_ms / hybrid_ms);
      }
    }
    std::printf("\n");
  }
  std::printf("\nhybrid_astar found %d of %d, state_lattice (heuristic_weight %g) %d.\n\n",
              hybrid_found, absl::GetFlag(FLAGS_ompl_queries),
              absl::GetFlag(FLAGS_lattice_weight), lattice_found);
  std::printf("| OMPL planner | solved | first solution: time / hybrid_astar's (median) | "
              "its length / hybrid_astar's (median) | as short as hybrid_astar's within %.0f s | "
              "then, time / hybrid_astar's (median) |\n|---|---|---|---|---|---|\n",
              absl::GetFlag(FLAGS_ompl_timeout));
  for (const std::string& p : planners) {
    std::printf("| %s | %d / %d | %.2fx | %.2f | %d | %s |\n", p.c_str(), solved[p],
                absl::GetFlag(FLAGS_ompl_queries), first_ratio[p].Percentile(0.5),
                length_ratio[p].Percentile(0.5), reached[p],
                reached[p] > 0 ? absl::StrFormat("%.0fx", target_ratio[p].Percentile(0.5)).c_str()
                               : "-");
  }
  std::printf("\n| OMPL planner | first solution: time / state_lattice's (median) | its length / "
              "state_lattice's (median) |\n|---|---|---|\n");
  for (const std::string& p : planners) {
    std::printf("| %s | %.2fx | %.2f |\n", p.c_str(), lattice_first_ratio[p].Percentile(0.5),
                lattice_length_ratio[p].Percentile(0.5));
  }
}

}  // namespace
}  // namespace pathd

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "hybrid_astar_bench [--goals N] [--ompl_queries N] [--ompl_timeout S] "
      "[--ompl_planners a,b] [--seed N]\nPrints markdown tables: hybrid_astar "
      "planning times on a generated 50 m warehouse, and against OMPL's planners.");
  absl::ParseCommandLine(argc, argv);
  // OMPL warns on stdout that BIT* renames itself kBITstar (its k-nearest
  // default); only errors are printed.
  ompl::msg::setLogLevel(ompl::msg::LOG_ERROR);
  std::mt19937 rng(7);
  const pathd::Grid grid = pathd::Warehouse(rng);
  const auto footprint =
      pathd::Footprint::Polygon({{-6, -4}, {6, -4}, {6, 4}, {-6, 4}}).value();
  const auto checker = pathd::SharedFootprintChecker(footprint).value();
  const std::vector<float> distance = pathd::ObstacleDistanceField(grid, false);
  std::printf("hybrid_astar_bench: 1000 x 1000 cells at 0.05 m, robot 0.6 m x 0.4 m "
              "(12 x 8 cells), turning radius 0.4 m (8 cells), %d heading bins\n",
              checker->headings());
  pathd::PartA(grid, checker, distance);
  if (absl::GetFlag(FLAGS_ompl_queries) > 0) pathd::PartB(grid, checker, distance);
  return 0;
}
