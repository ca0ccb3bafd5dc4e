// Local planner benchmark (core/local): the time of one control cycle of DWA
// for several sample counts and horizons, of ORCA against 10 to 1000
// neighbours within range, of a whole-fleet ORCA step for N robots, and of
// FIRAS, on a generated map at 5 cm cells (markdown tables). Times are the
// thread's CPU time, mean over --cycles cycles at random free poses.
//
// Then N robots swapping across a circle with each planner: arrivals, path
// length and separation side by side.
//
//   build/tests/bench/local_bench --cycles=200
#include <cmath>
#include <cstdio>
#include <ctime>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "core/geometry/free_space.h"
#include "core/geometry/obstacle_polygons.h"
#include "core/kinematics/footprint.h"
#include "core/local/dwa.h"
#include "core/local/firas.h"
#include "core/local/orca.h"

ABSL_FLAG(int, cycles, 200, "control cycles timed per row");
ABSL_FLAG(int, seed, 20, "random seed");

namespace pathd {
namespace {

double CpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + ts.tv_nsec * 1e-9;
}

// 400 x 400 cells (20 m at 5 cm): random 10 x 10 blocks (50 cm boxes) over
// 8% of the area.
Grid MakeMap(std::mt19937& rng) {
  Grid g = *Grid::Create(400, 400);
  g.set_resolution(0.05);
  const int blocks = 400 * 400 * 8 / 100 / 100;
  for (int b = 0; b < blocks; ++b) {
    const int32_t x0 = static_cast<int32_t>(rng() % 390),
                  y0 = static_cast<int32_t>(rng() % 390);
    for (int32_t y = y0; y < y0 + 10; ++y) {
      for (int32_t x = x0; x < x0 + 10; ++x) g.set_cost(x, y, kLethalCost);
    }
  }
  return g;
}

void BenchDwa(const Grid& grid, std::mt19937& rng, int cycles) {
  // A 60 x 40 cm robot; 1 m/s = 20 cells/s.
  const Footprint footprint =
      *Footprint::Polygon({{6, 4}, {-6, 4}, {-6, -4}, {6, -4}});
  FootprintCheckerOptions copt;
  copt.margin_cells = 1.0;  // 5 cm: sub-steps of up to 10 cm of motion
  const FootprintChecker checker = *FootprintChecker::Create(footprint, copt);
  const std::vector<float> distance = ObstacleDistanceField(grid, false);
  VelocityLimits limits;
  limits.max_v = 20.0;
  limits.max_w = 2.0;
  limits.acc_v = 50.0;
  limits.acc_w = 6.0;
  std::printf(
      "\n### DWA: one control cycle (400 x 400 map, 60 x 40 cm footprint, 5 cm "
      "margin)\n\n");
  std::printf(
      "| v x w samples | horizon (s) | max sub-step (s) | rollouts | us per "
      "cycle | us per rollout |\n");
  std::printf("|---|---|---|---|---|---|\n");
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Pose> starts;
  while (static_cast<int>(starts.size()) < cycles) {
    const Pose p{20 + 360 * u(rng), 20 + 360 * u(rng), 6.283 * u(rng)};
    if (!checker.Collides(grid, p, false, distance.data())) starts.push_back(p);
  }
  for (auto [nv, nw] :
       {std::pair{5, 11}, std::pair{11, 21}, std::pair{21, 41}}) {
    for (double horizon : {1.0, 2.0, 3.0}) {
      DwaOptions options;
      options.v_samples = nv;
      options.w_samples = nw;
      options.horizon = horizon;
      options.lookahead = 40.0;
      options.clearance_limit = 20.0;
      options.max_sub_steps = 200;
      int64_t rollouts = 0;
      const double t0 = CpuSeconds();
      for (const Pose& p : starts) {
        const std::vector<CellPoint> path = {
            p.point(), CellPoint{p.x + 100 * std::cos(p.yaw),
                                 p.y + 100 * std::sin(p.yaw)}};
        const RobotState state{p, 10.0, 0.0, 0.0};
        rollouts += DwaStep(DwaMap{&grid, &checker, distance.data()}, state,
                            limits, {}, path, 0.1, options)
                        ->samples;
      }
      const double dt = CpuSeconds() - t0;
      std::printf("| %d x %d | %.1f | %.2f | %lld | %.1f | %.2f |\n", nv, nw,
                  horizon, options.sub_step,
                  static_cast<long long>(rollouts / cycles), 1e6 * dt / cycles,
                  1e6 * dt / static_cast<double>(rollouts));
    }
  }
}

void BenchOrcaNeighbours(std::mt19937& rng, int cycles) {
  std::printf(
      "\n### ORCA: one control cycle against n neighbours within range (no "
      "map)\n\n");
  std::printf(
      "| neighbours | half-planes | infeasible cycles | us per cycle "
      "|\n|---|---|---|---|\n");
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  VelocityLimits limits;
  limits.holonomic = true;
  limits.min_v = -1.0;
  limits.max_v = 1.0;
  limits.max_vy = 1.0;
  for (int n : {10, 50, 200, 1000}) {
    OrcaOptions options;
    options.max_neighbours = static_cast<size_t>(n);
    options.neighbour_range = 1e9;
    // Neighbours spread so that the density stays that of a busy floor: a
    // disc whose area gives each about 4 cells^2... of radius 0.3 cells.
    const double spread = std::sqrt(n * 4.0 / 3.14159);
    int64_t lines = 0;
    int infeasible = 0;
    double total = 0;
    for (int c = 0; c < cycles; ++c) {
      std::vector<MovingObstacle> others;
      while (static_cast<int>(others.size()) < n) {
        const CellPoint p{spread * u(rng), spread * u(rng)};
        if (std::hypot(p.x, p.y) < 1.0) continue;
        others.push_back(MovingObstacle{
            p, CellPoint{0.5 * u(rng), 0.5 * u(rng)}, 0.3, true});
      }
      const RobotState state{Pose{0, 0, 0}, 0.5, 0.0, 0.0};
      const std::vector<CellPoint> path = {CellPoint{0, 0},
                                           CellPoint{spread * 2, 0}};
      const double t0 = CpuSeconds();
      absl::StatusOr<LocalPlan> plan =
          OrcaStep(state, 0.3, limits, others, {}, path, 0.1, options);
      total += CpuSeconds() - t0;
      lines += plan->constraints;
      infeasible += plan->status == LocalStatus::kBlocked;
    }
    std::printf("| %d | %lld | %d of %d | %.1f |\n", n,
                static_cast<long long>(lines / cycles), infeasible, cycles,
                1e6 * total / cycles);
  }
}

void BenchOrcaFleet(const Grid& grid, std::mt19937& rng, int cycles) {
  std::printf(
      "\n### ORCA: one whole-fleet step (every robot one cycle; 16 nearest "
      "neighbours within 2 m, "
      "static obstacle lines within 50 cm of the 400 x 400 map)\n\n");
  std::printf(
      "| robots | us per fleet step | us per robot | of which obstacle "
      "segments |\n|---|---|---|---|\n");
  const std::shared_ptr<const ObstaclePolygons> polygons =
      ObstaclePolygons::Build(FreeSpace(grid, false));
  std::uniform_real_distribution<double> u(0.0, 1.0);
  VelocityLimits limits;
  limits.holonomic = true;
  limits.min_v = -20.0;
  limits.max_v = 20.0;
  limits.max_vy = 20.0;
  OrcaOptions options;
  options.neighbour_range = 40.0;
  options.obstacle_range = 10.0;
  options.lookahead = 40.0;
  for (int n : {10, 50, 200, 1000}) {
    std::vector<MovingObstacle> robots;
    while (static_cast<int>(robots.size()) < n) {
      const Cell c{static_cast<int32_t>(rng() % 400),
                   static_cast<int32_t>(rng() % 400)};
      if (grid.cost(c) != kFreeCost) continue;
      robots.push_back(MovingObstacle{CellPoint{c.x + 0.5, c.y + 0.5},
                                      CellPoint{0, 0}, 6.0, true});
    }
    const int steps = std::max(1, cycles / 20);
    double total = 0, segments_time = 0;
    for (int s = 0; s < steps; ++s) {
      const double t0 = CpuSeconds();
      for (int i = 0; i < n; ++i) {
        const double t1 = CpuSeconds();
        const std::vector<ObstacleSegment> segments = ObstacleSegmentsNear(
            *polygons, robots[i].position, options.obstacle_range + 6.0,
            options.max_obstacle_lines);
        segments_time += CpuSeconds() - t1;
        std::vector<MovingObstacle> others = robots;
        others.erase(others.begin() + i);
        const RobotState state{
            Pose{robots[i].position.x, robots[i].position.y, 0}, 0, 0, 0};
        const std::vector<CellPoint> path = {robots[i].position,
                                             CellPoint{200, 200}};
        (void)OrcaStep(state, 6.0, limits, others, segments, path, 0.1,
                       options);
      }
      total += CpuSeconds() - t0;
    }
    std::printf("| %d | %.0f | %.1f | %.1f |\n", n, 1e6 * total / steps,
                1e6 * total / steps / n, 1e6 * segments_time / steps / n);
  }
}

void BenchFiras(const Grid& grid, std::mt19937& rng, int cycles) {
  std::printf(
      "\n### FIRAS: one control cycle (400 x 400 map, 30 cm radius)\n\n");
  std::printf("| influence (cells) | us per cycle |\n|---|---|\n");
  std::uniform_real_distribution<double> u(0.0, 1.0);
  VelocityLimits limits;
  limits.max_v = 20.0;
  limits.max_w = 2.0;
  for (double influence : {10.0, 20.0, 40.0}) {
    FirasOptions options;
    options.influence = influence;
    options.lookahead = 40.0;
    double total = 0;
    for (int c = 0; c < cycles; ++c) {
      const Pose p{20 + 360 * u(rng), 20 + 360 * u(rng), 0};
      const std::vector<CellPoint> path = {p.point(),
                                           CellPoint{p.x + 100, p.y}};
      const double t0 = CpuSeconds();
      (void)FirasStep(grid, RobotState{p, 0, 0, 0}, 6.0, limits, {}, path, 0.1,
                      options, nullptr);
      total += CpuSeconds() - t0;
    }
    std::printf("| %.0f | %.1f |\n", influence, 1e6 * total / cycles);
  }
}

// Robots swapping places across a circle on an open 60 x 60 map, stepped
// from one snapshot per period (0.1 s), each robot a 0.5-cell disc at up to
// 1 cell/s with finite accelerations; the others are its moving obstacles
// (reciprocal for ORCA). Figures, not pass/fail: arrivals, the time of the
// last arrival, path length over the straight distance, the smallest
// separation seen (contact below 1.0) and the periods with a contact.
enum class Planner { kOrcaHolonomic, kOrcaDiffDrive, kDwa, kFiras };

void BenchSwap(Planner planner, int n) {
  const double period = 0.1, radius = 0.5;
  const Grid grid = *Grid::Create(60, 60);
  const Footprint disc = *Footprint::Circle(radius);
  FootprintCheckerOptions copt;
  copt.margin_cells = 0.05;
  const FootprintChecker checker = *FootprintChecker::Create(disc, copt);
  const std::vector<float> distance = ObstacleDistanceField(grid, false);
  VelocityLimits limits;
  limits.holonomic = planner == Planner::kOrcaHolonomic;
  limits.min_v = limits.holonomic ? -1.0 : 0.0;
  limits.max_v = 1.0;
  limits.max_vy = limits.holonomic ? 1.0 : 0.0;
  limits.max_w = 2.0;
  limits.acc_v = limits.acc_vy = 2.0;
  limits.acc_w = 4.0;
  OrcaOptions orca;
  orca.keep_right = planner == Planner::kOrcaDiffDrive ? 0.5 : 0.15;
  DwaOptions dwa;
  FirasOptions firas;
  const double ring = 4.0 + 0.4 * n;
  struct Robot {
    RobotState state;
    std::vector<CellPoint> path;
    double travelled = 0;
    bool arrived = false;
    LocalStatus last = LocalStatus::kOk;
    ProgressWindow progress;
  };
  std::vector<Robot> robots(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double a = 2 * 3.141592653589793 * i / n;
    const CellPoint p{30 + ring * std::cos(a), 30 + ring * std::sin(a)};
    robots[i].state.pose =
        Pose{p.x, p.y, NormalizeAngle(a + 3.141592653589793)};
    robots[i].path = {p, CellPoint{60 - p.x, 60 - p.y}};
  }
  const auto grid_velocity = [](const RobotState& s) {
    const double c = std::cos(s.pose.yaw), sn = std::sin(s.pose.yaw);
    return CellPoint{s.v * c - s.vy * sn, s.v * sn + s.vy * c};
  };
  double min_sep = 1e9, last_arrival = 0;
  int contacts = 0;
  const double limit = 3 * 2 * ring + 20;
  for (double t = 0; t < limit; t += period) {
    std::vector<LocalPlan> plans(robots.size());
    for (size_t i = 0; i < robots.size(); ++i) {
      std::vector<MovingObstacle> others;
      for (size_t j = 0; j < robots.size(); ++j) {
        if (j == i) continue;
        others.push_back(
            MovingObstacle{robots[j].state.pose.point(),
                           grid_velocity(robots[j].state), radius,
                           planner == Planner::kOrcaHolonomic ||
                               planner == Planner::kOrcaDiffDrive});
      }
      absl::StatusOr<LocalPlan> plan;
      switch (planner) {
        case Planner::kOrcaHolonomic:
        case Planner::kOrcaDiffDrive:
          plan = OrcaStep(robots[i].state, radius, limits, others, {},
                          robots[i].path, period, orca, &robots[i].progress);
          break;
        case Planner::kDwa:
          plan = DwaStep(DwaMap{&grid, &checker, distance.data()},
                         robots[i].state, limits, others, robots[i].path,
                         period, dwa, nullptr, &robots[i].progress);
          break;
        case Planner::kFiras:
          plan = FirasStep(grid, robots[i].state, radius, limits, others,
                           robots[i].path, period, firas, &robots[i].progress);
          break;
      }
      plans[i] = *plan;
      robots[i].last = plan->status;
      if (plan->status == LocalStatus::kGoalReached && !robots[i].arrived) {
        robots[i].arrived = true;
        last_arrival = t;
      }
    }
    bool all = true;
    for (size_t i = 0; i < robots.size(); ++i) {
      all = all && robots[i].arrived;
      const Pose before = robots[i].state.pose;
      const Pose after = IntegrateVelocity(before, plans[i].v, plans[i].vy,
                                           plans[i].w, period, 10);
      robots[i].travelled += std::hypot(after.x - before.x, after.y - before.y);
      robots[i].state = RobotState{after, plans[i].v, plans[i].vy, plans[i].w};
    }
    if (all) break;
    bool contact = false;
    for (size_t i = 0; i < robots.size(); ++i) {
      for (size_t j = i + 1; j < robots.size(); ++j) {
        const double d =
            std::hypot(robots[i].state.pose.x - robots[j].state.pose.x,
                       robots[i].state.pose.y - robots[j].state.pose.y);
        min_sep = std::min(min_sep, d);
        contact = contact || d < 2 * radius;
      }
    }
    contacts += contact;
  }
  int arrived = 0;
  double ratio = 0;
  for (const Robot& r : robots) {
    arrived += r.arrived;
    ratio += r.travelled / (2 * ring);
  }
  static const char* kNames[] = {
      "orca (holonomic)", "orca (diff drive, keep_right 0.5)", "dwa", "firas"};
  // How the robots that did not arrive ended: the last status of each.
  std::map<std::string, int> endings;
  for (const Robot& r : robots) {
    if (!r.arrived) ++endings[LocalStatusName(r.last)];
  }
  std::string ended;
  for (const auto& [name, count] : endings) {
    ended += (ended.empty() ? "" : ", ") + std::to_string(count) + " " + name;
  }
  if (ended.empty()) ended = "-";
  char last[32] = "-";
  if (arrived == n) std::snprintf(last, sizeof(last), "%.1f", last_arrival);
  std::printf("| %s | %d | %d | %s | %.2f | %.3f | %d | %s |\n",
              kNames[static_cast<int>(planner)], n, arrived, last, ratio / n,
              min_sep, contacts, ended.c_str());
}

}  // namespace
}  // namespace pathd

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "Times one control cycle of the local planners (core/local).");
  absl::ParseCommandLine(argc, argv);
  std::mt19937 rng(static_cast<uint32_t>(absl::GetFlag(FLAGS_seed)));
  const int cycles = absl::GetFlag(FLAGS_cycles);
  const pathd::Grid grid = pathd::MakeMap(rng);
  pathd::BenchDwa(grid, rng, cycles);
  pathd::BenchOrcaNeighbours(rng, cycles);
  pathd::BenchOrcaFleet(grid, rng, cycles);
  pathd::BenchFiras(grid, rng, cycles);
  std::printf(
      "\n### Circle swap: N robots (0.5-cell discs, 1 cell/s) to the opposite "
      "side, 0.1 s periods\n\n");
  std::printf(
      "| planner | robots | arrived | last arrival (s) | travelled / straight "
      "| "
      "min separation (contact < 1) | periods with contact | non-arrivals' "
      "last status |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (pathd::Planner p :
       {pathd::Planner::kOrcaHolonomic, pathd::Planner::kOrcaDiffDrive,
        pathd::Planner::kDwa, pathd::Planner::kFiras}) {
    for (int n : {2, 8, 16}) pathd::BenchSwap(p, n);
  }
  return 0;
}
