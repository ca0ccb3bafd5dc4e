// hybrid_astar (core/planners/kinematic/hybrid_astar.h): every path it
// returns passes the independent kinematic checker (tests/testing/
// kinematic_checker.h: Boost.Geometry footprint against obstacle squares
// along densely sampled motions, curvature, direction, end poses) on random
// maps with random footprints and on the bundled warehouse map; it finds a
// path whenever a brute-force search over the same motions on a finer
// lattice does, at a cost within kCostFactor of it; stop conditions, bad
// input and the derived store.
#include "core/planners/kinematic/hybrid_astar.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>
#include <optional>
#include <queue>
#include <random>
#include <string>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/time/clock.h"
#include "core/kinematics/curves.h"
#include "core/kinematics/footprint.h"
#include "core/kinematics/motion_check.h"
#include "core/kinematics/pose_path.h"
#include "core/kinematics/vehicle.h"
#include "core/map_io/map_io.h"
#include "core/postprocess/plan_through.h"
#include "core/search/endpoints.h"
#include "core/search/path_measure.h"
#include "core/search/registry.h"
#include "gtest/gtest.h"
#include "tests/testing/advancing_store.h"
#include "tests/testing/kinematic_checker.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

constexpr double kPi = std::numbers::pi;

// AddressSanitizer runs these 3-5 times slower; CI runs the random suites
// with fewer maps there (docs/testing.md).
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif

// Random maps checked by the independent checker: the 2,000, fewer
// under AddressSanitizer.
constexpr int kRandomMaps = kSanitized ? 400 : 2000;
// Random maps on which hybrid_astar is compared with the brute force.
constexpr int kBruteForceMaps = kSanitized ? 50 : 200;
// hybrid_astar's cost (unsmoothed) over the brute force's, at most. The
// brute force is optimal on its lattice of quarter cells; hybrid_astar keeps
// one pose per cell and heading bin (and takes analytic expansions, which
// can be cheaper still). On these 200 maps the ratio measured 0.30-1.53,
// mean 0.89; on 250 maps of 12-20 cells 0.18-2.69, mean 0.91, where the
// dearest is the resolution's: a Dijkstra over the same motions on whole
// cells costs as much as hybrid_astar there (docs/planners.md).
constexpr double kCostFactor = 3.0;

PlanRequest KinematicRequest(const KinematicQuery& q, bool unknown_is_free = false) {
  PlanRequest r = PlanRequest::Between(q.start.cell(), q.goal.cell());
  r.cost.unknown_is_free = unknown_is_free;
  r.kinematic = std::make_shared<KinematicQuery>(q);
  return r;
}

std::shared_ptr<const FootprintChecker> Checker(const Footprint& f) {
  return SharedFootprintChecker(f).value();
}

Footprint Rectangle(double back, double front, double half_width) {
  return Footprint::Polygon({{-back, -half_width},
                             {front, -half_width},
                             {front, half_width},
                             {-back, half_width}})
      .value();
}

// The independent checker's view of the query, with the query's tolerances.
testing::KinematicCheck CheckOf(const KinematicQuery& q, bool unknown_is_free) {
  testing::KinematicCheck c;
  const Footprint& f = q.footprint->footprint();
  if (f.is_circle()) {
    c.circle_radius = f.circle_radius();
  } else {
    c.footprint = f.vertices();
  }
  c.unknown_is_free = unknown_is_free;
  c.min_turning_radius = q.min_turning_radius_cells;
  c.allow_reverse = AllowsReverse(q.motion);
  c.start = q.start;
  c.goal = q.goal;
  c.goal_tolerance = std::max(1e-6, q.goal_tolerance_cells);
  c.goal_yaw_tolerance = std::max(1e-6, std::min(kPi, q.goal_tolerance_yaw));
  return c;
}

// Everything a found path must satisfy: the independent checker, the
// pose-path measure (cells, spacing) agreeing with the reported cost and
// length, no reversing for Dubins. Empty when it passes.
std::string CheckResult(const Grid& grid, const PlanResult& r, const KinematicQuery& q,
                        bool unknown_is_free) {
  std::vector<Pose> poses;
  std::vector<bool> reverse;
  for (const PathPose& p : r.poses) {
    poses.push_back(p.pose);
    reverse.push_back(p.reverse);
    if (p.reverse && q.motion == MotionModel::kDubins) return "a Dubins path reverses";
  }
  const std::string problem =
      testing::CheckKinematicPath(grid, poses, reverse, CheckOf(q, unknown_is_free));
  if (!problem.empty()) return problem;
  CostParams cost;
  cost.unknown_is_free = unknown_is_free;
  const HybridMotions m = HybridMotionsFor(q.min_turning_radius_cells, q.footprint->headings());
  const PathMeasure measure =
      MeasurePosePath(grid, r.poses, r.path, cost, PenaltiesOf(q, m.turn_length));
  if (!measure.valid) {
    return "cells or spacing invalid at " + std::to_string(measure.first_invalid);
  }
  if (std::fabs(measure.cost - r.cost) > 1e-9 * (1 + r.cost)) return "cost is not the poses'";
  if (std::fabs(measure.length - r.length) > 1e-9 * (1 + r.length)) {
    return "length is not the poses'";
  }
  return "";
}

Footprint RandomFootprint(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  switch (rng() % 3) {
    case 0:
      return Footprint::Circle(0.3 + 1.2 * u(rng)).value();
    case 1:
      return Rectangle(0.2 + 1.0 * u(rng), 0.3 + 1.5 * u(rng), 0.3 + 0.7 * u(rng));
    default: {
      // A star-shaped polygon about the origin (3 to 8 vertices).
      const int n = 3 + static_cast<int>(rng() % 6);
      std::vector<CellPoint> v;
      for (int i = 0; i < n; ++i) {
        const double a = 2 * kPi * (i + 0.8 * u(rng)) / n;
        const double r = 0.4 + 1.1 * u(rng);
        v.push_back({r * std::cos(a), r * std::sin(a)});
      }
      return Footprint::Polygon(v).value();
    }
  }
}

// A w x h map with `blocks` random rectangles (up to `size` cells on a
// side) of lethal or unknown cells.
Grid RandomMap(std::mt19937& rng, int w, int h, int blocks, int size, bool unknown) {
  Grid grid = Grid::Create(w, h).value();
  for (int b = 0; b < blocks; ++b) {
    const int bx = static_cast<int>(rng() % w), by = static_cast<int>(rng() % h);
    const int bw = 1 + static_cast<int>(rng() % size), bh = 1 + static_cast<int>(rng() % size);
    const uint8_t v = unknown && rng() % 6 == 0 ? kUnknownCost : kLethalCost;
    for (int y = by; y < std::min(h, by + bh); ++y) {
      for (int x = bx; x < std::min(w, bx + bw); ++x) grid.set_cost(x, y, v);
    }
  }
  return grid;
}

// A uniformly random pose where the footprint is free, or nullopt after
// 200 tries.
std::optional<Pose> RandomFreePose(std::mt19937& rng, const Grid& grid,
                                   const FootprintChecker& checker, bool unknown_is_free) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 200; ++k) {
    const Pose p{grid.width() * u(rng), grid.height() * u(rng), 2 * kPi * u(rng) - kPi};
    if (!checker.Collides(grid, p, unknown_is_free)) return p;
  }
  return std::nullopt;
}

TEST(HybridAStar, RandomMapsPassTheIndependentChecker) {
  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int planned = 0, found = 0;
  Footprint footprint = Footprint::Circle(1.0).value();
  for (int trial = 0; trial < kRandomMaps; ++trial) {
    const int w = 16 + static_cast<int>(rng() % 17), h = 16 + static_cast<int>(rng() % 17);
    Grid grid = RandomMap(rng, w, h, static_cast<int>(rng() % 12), 6, true);
    // Weighted cells, so the cost penalty shapes some of the paths.
    for (size_t i = 0; i < grid.size(); ++i) {
      if (grid.cells()[i] == kFreeCost && rng() % 4 == 0) {
        grid.mutable_cells()[i] = static_cast<uint8_t>(rng() % 200);
      }
    }
    const bool unknown_is_free = trial % 5 == 0;
    // A new footprint every 100 maps: building a checker's masks costs tens
    // of milliseconds, the planning of one map about as much.
    if (trial % 100 == 0) footprint = RandomFootprint(rng);
    KinematicQuery q;
    q.footprint = Checker(footprint);
    q.motion = trial % 3 == 0 ? MotionModel::kDubins : MotionModel::kReedsShepp;
    q.min_turning_radius_cells = 1.0 + 3.0 * u(rng);
    if (trial % 4 == 1) q.goal_tolerance_cells = 1.0;
    if (trial % 4 == 2) q.goal_tolerance_yaw = 0.3;
    if (trial % 8 == 3) q.goal_tolerance_yaw = kPi;
    q.smooth = trial % 2 == 0;
    const std::optional<Pose> s = RandomFreePose(rng, grid, *q.footprint, unknown_is_free);
    const std::optional<Pose> g = RandomFreePose(rng, grid, *q.footprint, unknown_is_free);
    if (!s || !g) continue;
    q.start = *s;
    q.goal = *g;
    // A budget keeps the searches that end without a path (the lattice
    // exhausted at every resolution) from dominating the suite.
    auto r = PlanHybridAStar(grid, KinematicRequest(q, unknown_is_free),
                             StopCondition(absl::InfiniteFuture(), nullptr, 5000));
    ASSERT_TRUE(r.ok()) << "trial " << trial << ": " << r.status();
    ++planned;
    if (!r->found()) continue;
    ++found;
    EXPECT_EQ(CheckResult(grid, *r, q, unknown_is_free), "")
        << "trial " << trial << ", " << q.footprint->footprint().DebugString()
        << ", radius " << q.min_turning_radius_cells << ", smooth " << q.smooth;
  }
  std::printf("%d maps planned, %d paths found and checked\n", planned, found);
  EXPECT_GT(found, planned / 2);
}

// The bundled warehouse map (60 x 40 cells at 0.1 m; aisles 0.6 m wide,
// the cross aisle 0.3 m) with a 0.3 m x 0.2 m robot and a 0.2 m disc,
// turning on 0.2 m, between random free poses (some of them facing a
// shelf with no room to turn, which Dubins cannot leave).
TEST(HybridAStar, WarehouseMapPassesTheIndependentChecker) {
  auto grid = ReadRosMapFile("maps/warehouse.yaml");
  ASSERT_TRUE(grid.ok()) << grid.status();
  std::mt19937 rng(18);
  for (const MotionModel motion : {MotionModel::kReedsShepp, MotionModel::kDubins}) {
    int found = 0, planned = 0;
    int64_t most = 0;
    for (const Footprint& footprint :
         {Rectangle(1.0, 2.0, 1.0), Footprint::Circle(1.0).value()}) {
      for (int i = 0; i < 25; ++i) {
        KinematicQuery q;
        q.footprint = SharedFootprintChecker(footprint, {.subcells = 4}).value();
        q.motion = motion;
        q.min_turning_radius_cells = 2.0;
        q.smooth = i % 2 == 0;
        const std::optional<Pose> s = RandomFreePose(rng, *grid, *q.footprint, false);
        const std::optional<Pose> g = RandomFreePose(rng, *grid, *q.footprint, false);
        ASSERT_TRUE(s && g);
        q.start = *s;
        q.goal = *g;
        // The budget ends the searches for goals the robot cannot reach
        // (facing a shelf, or turning where it does not fit) early; the
        // paths found took at most 16,314 expansions.
        auto r = PlanHybridAStar(*grid, KinematicRequest(q),
                                 StopCondition(absl::InfiniteFuture(), nullptr, 20000));
        ASSERT_TRUE(r.ok()) << r.status();
        ++planned;
        if (!r->found()) continue;
        ++found;
        most = std::max(most, r->expansions);
        EXPECT_EQ(CheckResult(*grid, *r, q, false), "")
            << MotionModelName(motion) << " " << footprint.DebugString() << " query " << i;
      }
    }
    std::printf("warehouse, %s: %d of %d found, in at most %lld expansions\n",
                std::string(MotionModelName(motion)).c_str(), found, planned,
                static_cast<long long>(most));
    EXPECT_GT(found, planned * (motion == MotionModel::kReedsShepp ? 3 : 1) / 4);
  }
}

// Brute force over the same motions: Dijkstra from the start pose driving
// hybrid_astar's motions (HybridMotionsFor: arcs at the turning radius and
// straight, both ways for Reeds-Shepp), each checked with the same
// MotionChecker and priced piece by piece like the planner's, keeping the
// cheapest pose per square of 1/subdivisions cell and heading bin. The
// motions only ever reach the start heading plus whole turns, each in a bin
// of its own, so a finer heading grid would add nothing; the finer squares
// are what keep poses apart that the planner's lattice merges.
struct BruteResult {
  bool found = false;
  // The whole lattice was searched without reaching the goal.
  bool exhausted = false;
  double cost = 0.0;
};

BruteResult BruteForce(const Grid& grid, const KinematicQuery& q, int subdivisions,
                       int64_t max_expansions) {
  const std::vector<float> distance = ObstacleDistanceField(grid, false);
  const MotionChecker checker =
      MotionChecker::Create(q.footprint, grid, false, distance.data()).value();
  const int bins = q.footprint->headings();
  const HybridMotions m = HybridMotionsFor(q.min_turning_radius_cells, bins);
  const double r = q.min_turning_radius_cells;
  struct Motion {
    Steer steer;
    double length;
  };
  std::vector<Motion> motions;
  for (const double d : {1.0, -1.0}) {
    if (d < 0 && !AllowsReverse(q.motion)) break;
    motions.push_back({Steer::kStraight, d * m.straight_length});
    motions.push_back({Steer::kLeft, d * m.turn_length});
    motions.push_back({Steer::kRight, d * m.turn_length});
  }
  const MotionPenalties penalties = PenaltiesOf(q, m.turn_length);
  struct State {
    Pose pose;
    double g = 0.0;
    std::optional<PieceKind> kind;
    bool closed = false;
  };
  std::vector<State> states;
  absl::flat_hash_map<int64_t, int> index;
  const auto key = [&](const Pose& p) {
    const int64_t fx = static_cast<int64_t>(std::floor(p.x * subdivisions));
    const int64_t fy = static_cast<int64_t>(std::floor(p.y * subdivisions));
    return (fy * grid.width() * subdivisions + fx) * bins + q.footprint->HeadingIndex(p.yaw);
  };
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
  states.push_back({q.start, 0.0, std::nullopt, false});
  index[key(q.start)] = 0;
  open.push({0.0, 0});
  BruteResult result;
  int64_t expansions = 0;
  while (!open.empty()) {
    const auto [g, id] = open.top();
    open.pop();
    if (states[id].closed || g != states[id].g) continue;
    if (expansions++ >= max_expansions) return result;
    states[id].closed = true;
    const State from = states[id];
    if (std::hypot(from.pose.x - q.goal.x, from.pose.y - q.goal.y) <= q.goal_tolerance_cells &&
        AngleBetween(from.pose.yaw, q.goal.yaw) <= q.goal_tolerance_yaw) {
      result.found = true;
      result.cost = g;
      return result;
    }
    for (const Motion& mo : motions) {
      const bool turns = mo.steer != Steer::kStraight;
      const double turn = turns ? std::fabs(mo.length) / r : 0.0;
      const int pieces = static_cast<int>(
          std::ceil(std::fabs(mo.length) / MaxPieceLength(turns ? r : 1e300) - 1e-9));
      const auto at = [&](double t) { return Drive(from.pose, mo.steer, r, mo.length * t); };
      const Pose end = at(1.0);
      if (!grid.InBounds(end.cell())) continue;
      const int64_t k = key(end);
      const auto it = index.find(k);
      if (it != index.end() && states[it->second].closed) continue;
      double cost = 0.0;
      Pose previous = from.pose;
      std::optional<PieceKind> kind = from.kind;
      for (int j = 1; j <= pieces; ++j) {
        const Pose next = at(static_cast<double>(j) / pieces);
        const PieceKind piece = KindOf(previous, next, mo.length < 0);
        cost += PieceCost(PieceLength(previous, next), grid.cost(next.cell()), piece,
                          kind ? &*kind : nullptr, penalties);
        kind = piece;
        previous = next;
      }
      const double next_g = g + cost;
      if (it != index.end() && next_g >= states[it->second].g) continue;
      const double deviation = turns ? r * (1 - std::cos(turn / pieces / 2)) : 0.0;
      if (!checker.MotionFree(at, std::fabs(mo.length) + checker.reach() * turn, deviation,
                              id == 0 ? MotionEnd::kExact : MotionEnd::kProven,
                              MotionEnd::kSample)) {
        continue;
      }
      int next_id = static_cast<int>(states.size());
      if (it == index.end()) {
        states.push_back({});
        index[k] = next_id;
      } else {
        next_id = it->second;
      }
      states[next_id] = State{end, next_g, kind, false};
      open.push({next_g, next_id});
    }
  }
  result.exhausted = true;
  return result;
}

// Completeness at its resolution: on random small maps, whenever the brute
// force (squares of a quarter cell) reaches the goal, hybrid_astar does too
// (with its finer-lattice retries, HybridAStarOptions::max_subdivisions),
// at a cost within kCostFactor of the brute force's.
TEST(HybridAStar, FindsAPathWheneverABruteForceSearchDoes) {
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int both = 0, hybrid_only = 0, neither = 0, inconclusive = 0;
  double worst = 0.0, best = 1e9, sum = 0.0;
  Footprint footprint = Footprint::Circle(1.0).value();
  for (int trial = 0; trial < kBruteForceMaps; ++trial) {
    const int w = 10 + static_cast<int>(rng() % 8), h = 10 + static_cast<int>(rng() % 8);
    const Grid grid = RandomMap(rng, w, h, 2 + static_cast<int>(rng() % 8), 4, false);
    if (trial % 20 == 0) footprint = RandomFootprint(rng);
    KinematicQuery q;
    q.footprint = Checker(footprint);
    q.motion = trial % 3 == 0 ? MotionModel::kDubins : MotionModel::kReedsShepp;
    q.min_turning_radius_cells = 1.0 + 2.0 * u(rng);
    // The brute force's motions reach poses, not the exact goal: a
    // tolerance makes the goal reachable to both.
    q.goal_tolerance_cells = 1.0;
    q.goal_tolerance_yaw = 0.35;
    q.smooth = false;
    const std::optional<Pose> s = RandomFreePose(rng, grid, *q.footprint, false);
    const std::optional<Pose> g = RandomFreePose(rng, grid, *q.footprint, false);
    if (!s || !g) continue;
    q.start = *s;
    q.goal = *g;
    const BruteResult brute = BruteForce(grid, q, 4, 400000);
    auto r = PlanHybridAStar(grid, KinematicRequest(q), StopCondition::None());
    ASSERT_TRUE(r.ok()) << r.status();
    if (!brute.found && !brute.exhausted) {
      ++inconclusive;
      continue;
    }
    if (brute.found) {
      ASSERT_TRUE(r->found()) << "trial " << trial << ": the brute force reached the goal, "
                              << "hybrid_astar ended with " << PlanOutcomeName(r->outcome);
      ++both;
      const double ratio = brute.cost > 0 ? r->cost / brute.cost : (r->cost == 0 ? 1.0 : 1e9);
      EXPECT_LE(ratio, kCostFactor) << "trial " << trial;
      worst = std::max(worst, ratio);
      best = std::min(best, ratio);
      sum += ratio;
    } else if (r->found()) {
      // Analytic expansions reach goals the motions alone cannot.
      ++hybrid_only;
    } else {
      ++neither;
    }
  }
  std::printf(
      "both found %d, only hybrid_astar %d, neither %d, brute force inconclusive %d; "
      "cost / brute force: %.3f .. %.3f, mean %.3f\n",
      both, hybrid_only, neither, inconclusive, best, worst, sum / std::max(1, both));
  EXPECT_GT(both, kBruteForceMaps / 3);
}

// A regression from the brute-force comparison: a 2.7 x 0.7 robot (turning
// radius 3) must thread between two blocks; one pose per cell and heading
// misses the way, squares of a quarter cell find it.
TEST(HybridAStar, TightPassageNeedsTheFinerLattice) {
  // Row 0 first.
  const Grid grid = MakeGrid({
      "..................",
      "...##....##.......",
      ".........##.......",
      ".........##.......",
      ".........##.......",
      "..................",
      "..................",
      "..................",
      "####....##........",
      "####....##........",
      "########..........",
      "########...####...",
  });
  KinematicQuery q;
  q.footprint = Checker(Rectangle(0.921388, 1.75107, 0.342686));
  q.motion = MotionModel::kReedsShepp;
  q.min_turning_radius_cells = 2.757;
  q.start = Pose{5.457, 4.227, -1.995};
  q.goal = Pose{7.798, 7.408, -0.056};
  q.goal_tolerance_cells = 1.0;
  q.goal_tolerance_yaw = 0.35;
  q.smooth = false;
  HybridAStarOptions one_lattice;
  one_lattice.max_subdivisions = 1;
  const BruteResult brute = BruteForce(grid, q, 4, 400000);
  ASSERT_TRUE(brute.found);
  auto coarse = PlanHybridAStar(grid, KinematicRequest(q), StopCondition::None(), one_lattice);
  ASSERT_TRUE(coarse.ok()) << coarse.status();
  auto r = PlanHybridAStar(grid, KinematicRequest(q), StopCondition::None());
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_TRUE(r->found()) << PlanOutcomeName(r->outcome);
  EXPECT_EQ(CheckResult(grid, *r, q, false), "");
  // The retry is what found it (if the single lattice ever finds this one,
  // the test no longer shows the retry and needs another map).
  EXPECT_EQ(coarse->outcome, PlanOutcome::kNoPath);
  EXPECT_GT(r->expansions, coarse->expansions);
}

KinematicQuery OpenQuery(MotionModel motion) {
  KinematicQuery q;
  q.footprint = Checker(Rectangle(1.0, 2.0, 0.8));
  q.motion = motion;
  q.min_turning_radius_cells = 4.0;
  q.start = Pose{6.3, 7.1, 0.4};
  q.goal = Pose{31.7, 22.2, -2.0};
  return q;
}

TEST(HybridAStar, EndsExactlyOnTheGoalPoseAndStartsOnTheStart) {
  const Grid grid = Grid::Create(40, 30).value();
  for (const MotionModel motion : {MotionModel::kDubins, MotionModel::kReedsShepp}) {
    for (const bool smooth : {false, true}) {
      KinematicQuery q = OpenQuery(motion);
      q.smooth = smooth;
      auto r = PlanHybridAStar(grid, KinematicRequest(q), StopCondition::None());
      ASSERT_TRUE(r.ok()) << r.status();
      ASSERT_TRUE(r->found());
      EXPECT_EQ(r->poses.front().pose.x, q.start.x);
      EXPECT_EQ(r->poses.front().pose.y, q.start.y);
      EXPECT_EQ(r->poses.front().pose.yaw, q.start.yaw);
      EXPECT_EQ(r->poses.back().pose.x, q.goal.x);
      EXPECT_EQ(r->poses.back().pose.y, q.goal.y);
      EXPECT_EQ(r->poses.back().pose.yaw, q.goal.yaw);
      EXPECT_EQ(r->path.front(), q.start.cell());
      EXPECT_EQ(r->path.back(), q.goal.cell());
      EXPECT_EQ(CheckResult(grid, *r, q, false), "");
      // Longer than the straight line, shorter than a detour.
      EXPECT_GT(r->length, std::hypot(q.goal.x - q.start.x, q.goal.y - q.start.y));
      EXPECT_LT(r->length, 60.0);
    }
  }
}

// Facing a wall at the end of a dead-end corridor: Reeds-Shepp backs out,
// Dubins cannot turn in 3 cells and finds nothing.
TEST(HybridAStar, DubinsNeverReversesReedsSheppMay) {
  std::vector<std::string> rows(20, std::string(30, '.'));
  for (int x = 10; x < 30; ++x) rows[8][x] = rows[12][x] = '#';
  rows[9][29] = rows[10][29] = rows[11][29] = '#';
  const Grid grid = MakeGrid(rows);
  KinematicQuery q;
  q.footprint = Checker(Footprint::Circle(0.6).value());
  q.min_turning_radius_cells = 3.0;
  q.start = Pose{25.5, 10.5, 0.0};
  q.goal = Pose{4.5, 4.5, -kPi / 2};
  q.motion = MotionModel::kReedsShepp;
  auto rs = PlanHybridAStar(grid, KinematicRequest(q), StopCondition::None());
  ASSERT_TRUE(rs.ok()) << rs.status();
  ASSERT_TRUE(rs->found());
  EXPECT_TRUE(std::any_of(rs->poses.begin(), rs->poses.end(),
                          [](const PathPose& p) { return p.reverse; }));
  EXPECT_EQ(CheckResult(grid, *rs, q, false), "");
  q.motion = MotionModel::kDubins;
  auto dubins = PlanHybridAStar(grid, KinematicRequest(q), StopCondition::None());
  ASSERT_TRUE(dubins.ok()) << dubins.status();
  EXPECT_EQ(dubins->outcome, PlanOutcome::kNoPath);
  // Facing out of the corridor, Dubins drives out forwards.
  q.start.yaw = kPi;
  dubins = PlanHybridAStar(grid, KinematicRequest(q), StopCondition::None());
  ASSERT_TRUE(dubins.ok()) << dubins.status();
  ASSERT_TRUE(dubins->found());
  EXPECT_EQ(CheckResult(grid, *dubins, q, false), "");
}

TEST(HybridAStar, GoalToleranceWithoutAnalyticExpansion) {
  const Grid grid = Grid::Create(40, 30).value();
  KinematicQuery q = OpenQuery(MotionModel::kReedsShepp);
  q.goal_tolerance_cells = 0.8;
  q.goal_tolerance_yaw = 0.2;
  HybridAStarOptions lattice_only;
  lattice_only.analytic_expansion = false;
  auto r = PlanHybridAStar(grid, KinematicRequest(q), StopCondition::None(), lattice_only);
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_TRUE(r->found());
  const Pose& end = r->poses.back().pose;
  EXPECT_LE(std::hypot(end.x - q.goal.x, end.y - q.goal.y), 0.8);
  EXPECT_LE(AngleBetween(end.yaw, q.goal.yaw), 0.2);
  EXPECT_EQ(CheckResult(grid, *r, q, false), "");
}

// A goal heading free within the tolerance (pi: any) is chosen when the
// goal's own heading does not fit: a long robot facing into a narrow slot.
TEST(HybridAStar, AnyGoalHeadingWithinTheTolerance) {
  std::vector<std::string> rows(24, std::string(30, '.'));
  for (int y = 0; y < 24; ++y) {
    if (y < 10 || y > 12) rows[y][20] = rows[y][21] = '#';
  }
  const Grid grid = MakeGrid(rows);
  KinematicQuery q;
  q.footprint = Checker(Rectangle(0.5, 2.5, 0.6));
  q.motion = MotionModel::kReedsShepp;
  q.min_turning_radius_cells = 3.0;
  q.start = Pose{5.5, 5.5, 0.0};
  // Across the slot the robot does not fit; along it, it does.
  q.goal = Pose{20.5, 11.5, kPi / 2};
  auto blocked = PlanHybridAStar(grid, KinematicRequest(q), StopCondition::None());
  EXPECT_EQ(blocked.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(blocked.status().message().find("goal pose"), std::string::npos) << blocked.status();
  q.goal_tolerance_yaw = kPi;
  auto r = PlanHybridAStar(grid, KinematicRequest(q), StopCondition::None());
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_TRUE(r->found());
  EXPECT_EQ(CheckResult(grid, *r, q, false), "");
}

TEST(HybridAStar, DeadlineCancelAndBudgetStopTheSearch) {
  // A serpentine: the search works through many states.
  Grid grid = Grid::Create(300, 300).value();
  for (int y = 20; y < 300; y += 20) {
    for (int x = 0; x < 300; ++x) grid.set_cost(x, y, kLethalCost);
    for (int x = 0; x < 10; ++x) grid.set_cost((y / 20) % 2 == 0 ? 289 + x : x, y, kFreeCost);
  }
  KinematicQuery q;
  q.footprint = Checker(Footprint::Circle(1.0).value());
  q.motion = MotionModel::kReedsShepp;
  q.min_turning_radius_cells = 3.0;
  q.start = Pose{5.5, 5.5, 0.0};
  q.goal = Pose{290.5, 290.5, 0.0};
  const PlanRequest request = KinematicRequest(q);
  const Planner* planner = PlannerRegistry::Default().Get("hybrid_astar");
  ASSERT_NE(planner, nullptr);
  SearchScratch scratch;
  auto r = planner->Plan(grid, request, StopCondition(absl::Now() - absl::Seconds(1), nullptr, 0),
                         scratch);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->outcome, PlanOutcome::kTimeout);
  EXPECT_TRUE(r->poses.empty());
  std::atomic<bool> cancelled{true};
  r = planner->Plan(grid, request, StopCondition(absl::InfiniteFuture(), &cancelled, 0), scratch);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->outcome, PlanOutcome::kCancelled);
  r = planner->Plan(grid, request, StopCondition(absl::InfiniteFuture(), nullptr, 500), scratch);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->outcome, PlanOutcome::kExpansionLimit);
  EXPECT_LE(r->expansions, 500);
}

TEST(HybridAStar, BadInputIsNamed) {
  const Grid grid = MakeGrid({
      "..........",
      "..........",
      "....#.....",
      "..........",
      "..........",
  });
  KinematicQuery q;
  q.footprint = Checker(Footprint::Circle(0.8).value());
  q.motion = MotionModel::kReedsShepp;
  q.min_turning_radius_cells = 1.0;
  q.start = Pose{1.0, 1.0, 0.0};
  q.goal = Pose{8.5, 2.5, 0.0};
  const auto plan = [&grid](const KinematicQuery& query) {
    return PlanHybridAStar(grid, KinematicRequest(query), StopCondition::None());
  };
  const auto expect = [](const absl::StatusOr<PlanResult>& r, const std::string& words,
                         std::optional<EndpointFault> fault) {
    EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument) << r.status();
    EXPECT_NE(r.status().message().find(words), std::string::npos) << r.status();
    EXPECT_EQ(EndpointFaultOf(r.status()), fault) << r.status();
  };
  ASSERT_TRUE(plan(q).ok()) << plan(q).status();
  KinematicQuery bad = q;
  // The footprint overlaps the obstacle though the centre's cell is free.
  bad.start = Pose{3.5, 2.5, 0.0};
  expect(plan(bad), "start pose (3.5, 2.5", EndpointFault::kStartBlocked);
  bad = q;
  bad.goal = Pose{5.5, 2.2, 0.0};
  expect(plan(bad), "goal pose (5.5, 2.2", EndpointFault::kGoalBlocked);
  bad = q;
  bad.goal = Pose{12.5, 2.5, 0.0};
  expect(plan(bad), "goal (12, 2) is outside", EndpointFault::kGoalOutsideMap);
  bad = q;
  bad.start = Pose{-0.5, 2.5, 0.0};
  expect(plan(bad), "start (-1, 2) is outside", EndpointFault::kStartOutsideMap);
  bad = q;
  bad.goal = Pose{0.4, 0.4, 0.0};
  // Free cell, but the disc leaves the map.
  expect(plan(bad), "goal pose", EndpointFault::kGoalBlocked);
  bad = q;
  bad.motion = MotionModel::kDifferential;
  expect(plan(bad), "dubins or reeds_shepp motion, not differential", std::nullopt);
  bad = q;
  bad.min_turning_radius_cells = 0.0;
  expect(plan(bad), "min_turning_radius", std::nullopt);
  bad = q;
  bad.reverse_penalty = 0.5;
  expect(plan(bad), "reverse_penalty 0.5 must be finite and >= 1", std::nullopt);
  bad = q;
  bad.goal_tolerance_yaw = std::nan("");
  expect(plan(bad), "goal_tolerance_yaw", std::nullopt);
  // The request's cells must be the poses'.
  PlanRequest mismatched = KinematicRequest(q);
  mismatched.start = Cell{2, 2};
  auto r = PlanHybridAStar(grid, mismatched, StopCondition::None());
  EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("not the cell of the kinematic start pose"),
            std::string::npos)
      << r.status();
}

// Replans towards the same goal on the same map version read the obstacle
// heuristic from the store; a new goal builds its own.
TEST(HybridAStar, ObstacleHeuristicComesFromTheDerivedStore) {
  std::vector<std::string> rows(16, std::string(32, '.'));
  for (int x = 10; x < 16; ++x) rows[6][x] = '#';
  for (int y = 6; y < 11; ++y) rows[y][15] = '#';
  const Grid grid = MakeGrid(rows);
  testing::AdvancingStore store;
  store.SetGrid(grid);
  KinematicQuery q;
  q.footprint = Checker(Footprint::Circle(0.4).value());
  q.motion = MotionModel::kReedsShepp;
  q.min_turning_radius_cells = 1.5;
  q.goal = Pose{26.5, 8.5, 0.0};
  const auto plan = [&](Pose start, Pose goal, DerivedStore* derived) {
    q.start = start;
    q.goal = goal;
    PlanRequest request = KinematicRequest(q);
    request.derived = derived;
    auto r = PlanHybridAStar(grid, request, StopCondition::None());
    EXPECT_TRUE(r.ok() && r->found()) << (r.ok() ? "" : r.status().ToString());
    return r.ok() ? *r : PlanResult{};
  };
  const PlanResult first = plan(Pose{3.5, 8.5, 0.0}, q.goal, &store);
  const PlanResult fresh = plan(Pose{3.5, 8.5, 0.0}, q.goal, nullptr);
  EXPECT_EQ(first.cost, fresh.cost);
  EXPECT_EQ(first.expansions, fresh.expansions);
  const int64_t builds = store.stats().builds;
  EXPECT_EQ(builds, 2);  // the obstacle distance and the goal's heuristic
  plan(Pose{4.5, 3.5, 0.5}, q.goal, &store);
  EXPECT_EQ(store.stats().builds, builds);
  EXPECT_GE(store.stats().hits, 2);
  plan(Pose{3.5, 8.5, 0.0}, Pose{26.5, 12.5, 0.0}, &store);
  EXPECT_EQ(store.stats().builds, builds + 1);
}

TEST(HybridAStar, RecordsItsExpansions) {
  const Grid grid = Grid::Create(40, 30).value();
  KinematicQuery q = OpenQuery(MotionModel::kReedsShepp);
  PlanRequest request = KinematicRequest(q);
  ExpansionRecorder recorder(1 << 20);
  request.expansion_recorder = &recorder;
  auto r = PlanHybridAStar(grid, request, StopCondition::None());
  ASSERT_TRUE(r.ok() && r->found());
  EXPECT_EQ(static_cast<int64_t>(recorder.cells().size()), r->expansions);
  EXPECT_EQ(recorder.cells().front(), q.start.cell());
}

// Without a kinematic query (a grid request naming hybrid_astar), the
// planner plans DefaultKinematicQuery: a point-like Reeds-Shepp robot from
// the start cell's centre to the goal cell's centre, any heading; the cost
// penalty is the request's cost weight.
TEST(HybridAStar, GridRequestsPlanTheDefaultQuery) {
  const Grid grid = MakeGrid({
      "..........",
      ".######...",
      "......#...",
      "..9...#...",
      "..........",
  });
  const Planner* planner = PlannerRegistry::Default().Get("hybrid_astar");
  ASSERT_NE(planner, nullptr);
  EXPECT_TRUE(planner->traits().kinematic);
  EXPECT_FALSE(planner->traits().optimal);
  SearchScratch scratch;
  CostParams cost;
  cost.cost_weight = 3.0;
  auto r = planner->Plan(grid, PlanRequest::Between({0, 4}, {8, 2}, cost), StopCondition::None(),
                         scratch);
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_TRUE(r->found());
  KinematicQuery q = DefaultKinematicQuery({0, 4}, {8, 2});
  q.cost_penalty = cost.cost_weight;
  EXPECT_EQ(CheckResult(grid, *r, q, false), "");
  const PathMeasure m = MeasureResultPath(grid, *r, cost);
  ASSERT_TRUE(m.valid);
  EXPECT_NEAR(m.cost, r->cost, 1e-9 * r->cost);
}

// Through via points (a grid request, so every leg plans its default
// query): the answer carries every leg's poses, measured like one path.
TEST(HybridAStar, ViaPointsJoinTheLegsPoses) {
  const Grid grid = Grid::Create(30, 20).value();
  const Planner* planner = PlannerRegistry::Default().Get("hybrid_astar");
  ASSERT_NE(planner, nullptr);
  SearchScratch scratch;
  auto through = PlanThrough(*planner, grid, PlanRequest::Between({2, 2}, {27, 17}),
                             {Cell{20, 4}, Cell{8, 15}}, StopCondition::None(), scratch, {});
  ASSERT_TRUE(through.ok()) << through.status();
  const PlanResult& plan = through->plan;
  ASSERT_TRUE(plan.found());
  ASSERT_FALSE(plan.poses.empty());
  EXPECT_EQ(plan.poses.front().pose.cell(), (Cell{2, 2}));
  EXPECT_EQ(plan.poses.back().pose.cell(), (Cell{27, 17}));
  const PathMeasure m = MeasureResultPath(grid, plan, {});
  ASSERT_TRUE(m.valid) << m.first_invalid;
  EXPECT_NEAR(m.length, plan.length, 1e-9 * plan.length);
  EXPECT_NEAR(m.cost, plan.cost, 1e-9 * plan.cost);
}

}  // namespace
}  // namespace pathd
