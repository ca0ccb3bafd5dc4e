// state_lattice figures: planning time, expansions and path length
//  (1) on a 1000 x 1000 warehouse-like map at 0.05 m (shelf rows, cross
//      aisles, pallets) for a car-like footprint, per motion model, against
//      grid A*'s length for a point robot on the same map;
//  (2) on Reeds-Shepp-like queries on an empty map: pose to pose, against
//      the exact shortest Reeds-Shepp (Dubins) curve length from OMPL, which
//      is the optimum there.
// Prints markdown tables; docs/performance.md records them with the command.
//
//   lattice_bench [--queries 50] [--seed 7] [--models reeds_shepp,dubins,...]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/str_split.h"
#include "absl/time/clock.h"
#include "core/kinematics/footprint.h"
#include "core/kinematics/vehicle.h"
#include "core/map/grid.h"
#include "core/planners/kinematic/state_lattice.h"
#include "core/search/registry.h"
#include "ompl/base/spaces/DubinsStateSpace.h"
#include "ompl/base/spaces/ReedsSheppStateSpace.h"

ABSL_FLAG(int32_t, queries, 50, "queries per table row");
ABSL_FLAG(uint32_t, seed, 7, "random seed of the map's pallets and the queries");
ABSL_FLAG(std::string, models, "reeds_shepp,dubins,differential,omnidirectional",
          "motion models to measure");
ABSL_FLAG(double, timeout_s, 10.0, "deadline of each query, seconds");
ABSL_FLAG(std::string, heuristic_weights, "1,1.2",
          "heuristic weights (PlanRequest::heuristic_weight) of the warehouse rows");
ABSL_FLAG(bool, verbose, false, "print every warehouse query to stderr");

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kResolution = 0.05;

// 50 m x 50 m: a wall round the edge, six bays of shelf rows (shelves 0.5 m
// deep, 10 m long, aisles 2.5 m wide) separated by 4 m cross aisles, and 300
// pallets (0.8 m x 1.2 m) dropped at random in the aisles.
pathd::Grid WarehouseMap(std::mt19937& rng) {
  pathd::Grid grid = pathd::Grid::Create(1000, 1000).value();
  grid.set_resolution(kResolution);
  const auto block = [&](int32_t x0, int32_t y0, int32_t w, int32_t h) {
    for (int32_t y = std::max(0, y0); y < std::min(1000, y0 + h); ++y) {
      for (int32_t x = std::max(0, x0); x < std::min(1000, x0 + w); ++x) {
        grid.set_cost(x, y, pathd::kLethalCost);
      }
    }
  };
  block(0, 0, 1000, 4);
  block(0, 996, 1000, 4);
  block(0, 0, 4, 1000);
  block(996, 0, 4, 1000);
  for (int32_t bay = 0; bay < 3; ++bay) {
    const int32_t y0 = 80 + bay * 300;
    for (int32_t x = 80; x + 10 < 920; x += 60) block(x, y0, 10, 200);
  }
  std::uniform_int_distribution<int32_t> at(10, 970);
  for (int i = 0; i < 300; ++i) block(at(rng), at(rng), 16, 24);
  return grid;
}

struct Figures {
  int queries = 0;
  int found = 0;
  std::vector<double> millis;
  double expansions = 0;
  double length_m = 0;
  double ratio = 0;
  int ratio_n = 0;
};

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(p * v.size()))];
}

void PrintRow(const std::string& label, const Figures& f) {
  std::printf("| %s | %d/%d | %.1f | %.1f | %.1f | %.0f | %.2f | %.3f |\n", label.c_str(),
              f.found, f.queries, Percentile(f.millis, 0.5), Percentile(f.millis, 0.95),
              f.millis.empty() ? 0.0 : *std::max_element(f.millis.begin(), f.millis.end()),
              f.queries ? f.expansions / f.queries : 0.0, f.found ? f.length_m / f.found : 0.0,
              f.ratio_n ? f.ratio / f.ratio_n : 0.0);
}

double CurveLength(const pathd::Pose& a, const pathd::Pose& b, double radius, bool reverse) {
  std::unique_ptr<ompl::base::SE2StateSpace> space;
  if (reverse) {
    space = std::make_unique<ompl::base::ReedsSheppStateSpace>(radius);
  } else {
    space = std::make_unique<ompl::base::DubinsStateSpace>(radius);
  }
  ompl::base::State* s = space->allocState();
  ompl::base::State* t = space->allocState();
  s->as<ompl::base::SE2StateSpace::StateType>()->setXY(a.x, a.y);
  s->as<ompl::base::SE2StateSpace::StateType>()->setYaw(a.yaw);
  t->as<ompl::base::SE2StateSpace::StateType>()->setXY(b.x, b.y);
  t->as<ompl::base::SE2StateSpace::StateType>()->setYaw(b.yaw);
  const double d = space->distance(s, t);
  space->freeState(s);
  space->freeState(t);
  return d;
}

}  // namespace

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "lattice_bench [--queries N] [--seed S] [--models reeds_shepp,dubins,differential,"
      "omnidirectional]\nstate_lattice on a 1000 x 1000 warehouse-like map at 0.05 m and on "
      "Reeds-Shepp-like queries against OMPL's curve lengths.");
  absl::ParseCommandLine(argc, argv);
  const int32_t queries = absl::GetFlag(FLAGS_queries);
  std::mt19937 rng(absl::GetFlag(FLAGS_seed));
  std::vector<pathd::MotionModel> models;
  for (const absl::string_view name :
       absl::StrSplit(absl::GetFlag(FLAGS_models), ',', absl::SkipEmpty())) {
    absl::StatusOr<pathd::MotionModel> m = pathd::ParseMotionModel(std::string(name));
    if (!m.ok()) {
      std::fprintf(stderr, "%s\n", std::string(m.status().message()).c_str());
      return 2;
    }
    models.push_back(*m);
  }
  // A car 0.6 m x 0.4 m, its reference point (rear axle) 0.1 m from the
  // rear; turning radius 0.5 m = 10 cells (the shipped sets at 5 cm).
  const pathd::Footprint car =
      *pathd::Footprint::Polygon({{-2, -4}, {10, -4}, {10, 4}, {-2, 4}});
  auto checker = *pathd::SharedFootprintChecker(car);
  const pathd::Grid warehouse = WarehouseMap(rng);
  const absl::Duration timeout = absl::Seconds(absl::GetFlag(FLAGS_timeout_s));

  // Random free poses, far enough apart to be a trip (>= 10 m).
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto free_pose = [&](const pathd::Grid& grid) {
    for (;;) {
      const pathd::Pose p{u(rng) * grid.width(), u(rng) * grid.height(), (2 * u(rng) - 1) * kPi};
      if (!checker->Collides(grid, p, false)) return p;
    }
  };
  std::vector<std::pair<pathd::Pose, pathd::Pose>> trips;
  while (static_cast<int32_t>(trips.size()) < queries) {
    const pathd::Pose a = free_pose(warehouse);
    const pathd::Pose b = free_pose(warehouse);
    if (std::hypot(a.x - b.x, a.y - b.y) * kResolution >= 10.0) trips.push_back({a, b});
  }
  const pathd::Planner* astar = pathd::PlannerRegistry::Default().Get("astar");
  pathd::SearchScratch scratch;

  std::printf("## state_lattice on a 1000 x 1000 warehouse-like map (0.05 m cells)\n\n");
  std::printf("car 0.6 x 0.4 m, turning radius 0.5 m (10 cells); %d random pose-to-pose "
              "trips of at least 10 m; deadline %.0f s per query. len/A* is the path length "
              "over grid A*'s for a point between the same cells.\n\n",
              queries, absl::ToDoubleSeconds(timeout));
  std::vector<double> weights;
  for (const absl::string_view w :
       absl::StrSplit(absl::GetFlag(FLAGS_heuristic_weights), ',', absl::SkipEmpty())) {
    weights.push_back(std::stod(std::string(w)));
  }
  std::printf("| motion model | found | p50 ms | p95 ms | max ms | expansions | length m | "
              "len/A* |\n|---|---|---|---|---|---|---|---|\n");
  for (const double weight : weights) {
  for (const pathd::MotionModel model : models) {
    Figures f;
    for (const auto& [a, b] : trips) {
      auto q = std::make_shared<pathd::KinematicQuery>();
      q->start = a;
      q->goal = b;
      q->footprint = checker;
      q->motion = model;
      q->min_turning_radius_cells = 10.0;
      pathd::PlanRequest request = pathd::PlanRequest::Between(a.cell(), b.cell());
      request.kinematic = q;
      request.heuristic_weight = weight;
      const absl::Time t0 = absl::Now();
      auto r = pathd::PlanStateLattice(warehouse, request,
                                       pathd::StopCondition(absl::Now() + timeout, nullptr, 0));
      const double ms = absl::ToDoubleMilliseconds(absl::Now() - t0);
      if (!r.ok()) {
        std::fprintf(stderr, "%s\n", std::string(r.status().message()).c_str());
        return 1;
      }
      ++f.queries;
      f.millis.push_back(ms);
      f.expansions += static_cast<double>(r->expansions);
      if (absl::GetFlag(FLAGS_verbose)) {
        std::fprintf(stderr, "%s w=%g (%.1f, %.1f, %.2f) -> (%.1f, %.1f, %.2f): %s, %ld expansions, "
                     "length %.1f cells, %.0f ms\n",
                     std::string(pathd::MotionModelName(model)).c_str(), weight, a.x, a.y, a.yaw,
                     b.x, b.y, b.yaw, std::string(pathd::PlanOutcomeName(r->outcome)).c_str(),
                     static_cast<long>(r->expansions), r->length, ms);
      }
      if (!r->found()) continue;
      ++f.found;
      f.length_m += r->length * kResolution;
      auto grid_path = astar->Plan(warehouse, pathd::PlanRequest::Between(a.cell(), b.cell()),
                                   pathd::StopCondition::None(), scratch);
      if (grid_path.ok() && grid_path->found() && grid_path->length > 0) {
        f.ratio += r->length / grid_path->length;
        ++f.ratio_n;
      }
    }
    PrintRow(std::string(pathd::MotionModelName(model)) +
                 (weight == 1.0 ? "" : ", heuristic weight " + std::to_string(weight).substr(0, 4)),
             f);
    std::fflush(stdout);
  }
  }

  // Reeds-Shepp-like queries: an empty 400 x 400 map (20 m), poses within
  // 2 to 8 m of each other; the obstacle-free optimum is OMPL's curve.
  const pathd::Grid open_map = pathd::Grid::Create(400, 400).value();
  std::printf("\n## state_lattice against OMPL's Reeds-Shepp and Dubins curves (empty map)\n\n");
  std::printf("same car and radius; %d random pose pairs 2-8 m apart on an empty 20 m map; "
              "len/curve is the path length over the exact shortest curve's (OMPL).\n\n",
              queries);
  std::printf("| motion model | found | p50 ms | p95 ms | max ms | expansions | length m | "
              "len/curve |\n|---|---|---|---|---|---|---|---|\n");
  for (const pathd::MotionModel model : {pathd::MotionModel::kReedsShepp,
                                         pathd::MotionModel::kDubins}) {
    for (const bool analytic : {true, false}) {
      Figures f;
      std::mt19937 pairs(absl::GetFlag(FLAGS_seed) + 1);
      std::uniform_real_distribution<double> w(0.0, 1.0);
      for (int32_t i = 0; i < queries; ++i) {
        pathd::Pose a, b;
        do {
          a = pathd::Pose{100 + 200 * w(pairs), 100 + 200 * w(pairs), (2 * w(pairs) - 1) * kPi};
          b = pathd::Pose{100 + 200 * w(pairs), 100 + 200 * w(pairs), (2 * w(pairs) - 1) * kPi};
        } while (std::hypot(a.x - b.x, a.y - b.y) < 40 || std::hypot(a.x - b.x, a.y - b.y) > 160);
        auto q = std::make_shared<pathd::KinematicQuery>();
        q->start = a;
        q->goal = b;
        q->footprint = checker;
        q->motion = model;
        q->min_turning_radius_cells = 10.0;
        // Without analytic expansions the lattice must reach the goal
        // itself: within half a cell and 0.2 rad.
        if (!analytic) {
          q->goal_tolerance_cells = 0.75;
          q->goal_tolerance_yaw = 0.2;
        }
        pathd::PlanRequest request = pathd::PlanRequest::Between(a.cell(), b.cell());
        request.kinematic = q;
        pathd::StateLatticeOptions options;
        options.analytic_expansion = analytic;
        const absl::Time t0 = absl::Now();
        auto r = pathd::PlanStateLattice(
            open_map, request, pathd::StopCondition(absl::Now() + timeout, nullptr, 0), options);
        const double ms = absl::ToDoubleMilliseconds(absl::Now() - t0);
        if (!r.ok()) {
          std::fprintf(stderr, "%s\n", std::string(r.status().message()).c_str());
          return 1;
        }
        ++f.queries;
        f.millis.push_back(ms);
        f.expansions += static_cast<double>(r->expansions);
        if (!r->found()) continue;
        ++f.found;
        f.length_m += r->length * kResolution;
        f.ratio += r->length /
                   CurveLength(a, b, 10.0, model == pathd::MotionModel::kReedsShepp);
        ++f.ratio_n;
      }
      PrintRow(std::string(pathd::MotionModelName(model)) +
                   (analytic ? "" : ", lattice only (goal within 0.75 cells, 0.2 rad)"),
               f);
      std::fflush(stdout);
    }
  }
  return 0;
}
