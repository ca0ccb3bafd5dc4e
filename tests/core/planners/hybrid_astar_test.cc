// hybrid_astar (core/planners/kinematic/hybrid_astar.h).
#include "core/planners/kinematic/hybrid_astar.h"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include "core/kinematics/footprint.h"
#include "core/kinematics/pose_path.h"
#include "core/kinematics/vehicle.h"
#include "core/map_io/map_io.h"
#include "core/search/registry.h"
#include "gtest/gtest.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

constexpr double kPi = std::numbers::pi;

PlanRequest KinematicRequest(const KinematicQuery& q) {
  PlanRequest r = PlanRequest::Between(q.start.cell(), q.goal.cell());
  r.kinematic = std::make_shared<KinematicQuery>(q);
  return r;
}

TEST(HybridAStar, Smoke) {
  Grid grid = Grid::Create(40, 30).value();
  for (int y = 0; y < 20; ++y) grid.set_cost(20, y, kLethalCost);
  KinematicQuery q;
  q.start = Pose{5.5, 5.5, 0.0};
  q.goal = Pose{35.5, 5.5, kPi};
  q.footprint = SharedFootprintChecker(
                    Footprint::Polygon({{-1.0, -0.6}, {1.5, -0.6}, {1.5, 0.6}, {-1.0, 0.6}}).value())
                    .value();
  q.min_turning_radius_cells = 3.0;
  for (MotionModel m : {MotionModel::kReedsShepp, MotionModel::kDubins}) {
    q.motion = m;
    auto r = PlanHybridAStar(grid, KinematicRequest(q), StopCondition::None());
    ASSERT_TRUE(r.ok()) << r.status();
    ASSERT_TRUE(r->found()) << PlanOutcomeName(r->outcome);
    std::printf("%s: %zu poses, length %.2f cost %.2f expansions %lld time %s\n",
                std::string(MotionModelName(m)).c_str(), r->poses.size(), r->length, r->cost,
                static_cast<long long>(r->expansions), absl::FormatDuration(r->planning_time).c_str());
  }
}

}  // namespace
}  // namespace pathd
