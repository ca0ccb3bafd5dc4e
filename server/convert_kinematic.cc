// proto <-> core for robots with shape and kinematics: poses, footprints,
// the kinematic part of a plan query, and the path as poses in responses.
// Metres and world frames stop here; core sees cells and grid headings.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "core/search/endpoints.h"
#include "core/search/registry.h"
#include "core/status_macros.h"
#include "server/convert.h"

namespace pathd::server {
namespace {

std::string Num(double v) { return absl::StrFormat("%g", v); }

// Nav2 Smac's angle_quantization_bins.
constexpr int32_t kHeadingBins = 72;
// Nav2 Smac's minimum_turning_radius, metres.
constexpr double kDefaultTurningRadiusM = 0.4;

absl::Status Finite(std::string_view what, std::initializer_list<double> values) {
  for (double v : values) {
    if (!std::isfinite(v)) {
      return absl::InvalidArgumentError(absl::StrFormat("%s is not finite", what));
    }
  }
  return absl::OkStatus();
}

absl::Status OnMap(const Grid& grid, CellPoint p, std::string_view what) {
  if (p.x >= 0 && p.y >= 0 && p.x < grid.width() && p.y < grid.height()) {
    return absl::OkStatus();
  }
  absl::Status outside = absl::InvalidArgumentError(absl::StrFormat(
      "%s (%s, %s) in cell coordinates is outside the %d x %d map", what, Num(p.x),
      Num(p.y), grid.width(), grid.height()));
  if (const auto fault = EndpointFaultFor(what, /*outside=*/true)) {
    return WithEndpointFault(std::move(outside), *fault);
  }
  return outside;
}

// A penalty option: unset keeps `*out`; set, it must be finite and >= min.
absl::Status SetPenalty(bool has, double value, std::string_view name, double min,
                        double* out) {
  if (!has) return absl::OkStatus();
  if (!std::isfinite(value) || value < min) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.penalties.%s %s must be finite and >= %s", name, Num(value), Num(min)));
  }
  *out = value;
  return absl::OkStatus();
}

absl::StatusOr<MotionModel> MotionFromProto(v1::MotionModel model) {
  switch (model) {
    case v1::MOTION_MODEL_UNSPECIFIED:
    case v1::MOTION_MODEL_DUBINS:
      return MotionModel::kDubins;
    case v1::MOTION_MODEL_REEDS_SHEPP:
      return MotionModel::kReedsShepp;
    case v1::MOTION_MODEL_DIFFERENTIAL:
      return MotionModel::kDifferential;
    case v1::MOTION_MODEL_OMNIDIRECTIONAL:
      return MotionModel::kOmnidirectional;
    default:
      break;
  }
  return absl::InvalidArgumentError(
      absl::StrFormat("options.motion_model: unknown motion model %d", static_cast<int>(model)));
}

}  // namespace

absl::StatusOr<PositionPose> PoseFromPosition(const v1::Position& position, const Grid& grid,
                                              std::string_view what) {
  PositionPose out;
  switch (position.kind_case()) {
    case v1::Position::kCell: {
      const Cell c = FromProto(position.cell());
      out.pose = Pose::AtCellCenter(c);
      if (!grid.InBounds(c)) {
        PATHD_RETURN_IF_ERROR(OnMap(grid, out.pose.point(), what));
      }
      return out;
    }
    case v1::Position::kWorld: {
      const v1::WorldPoint& w = position.world();
      PATHD_RETURN_IF_ERROR(
          Finite(absl::StrFormat("%s world point (%s, %s)", what, Num(w.x()), Num(w.y())),
                 {w.x(), w.y()}));
      const CellPoint p = grid.WorldToCellPoint(WorldPoint{w.x(), w.y()});
      out.pose = Pose{p.x, p.y, 0.0};
      break;
    }
    case v1::Position::kWorldPose: {
      const v1::WorldPose& w = position.world_pose();
      PATHD_RETURN_IF_ERROR(Finite(absl::StrFormat("%s world pose (%s, %s, %s)", what,
                                                   Num(w.x()), Num(w.y()), Num(w.yaw())),
                                   {w.x(), w.y(), w.yaw()}));
      const CellPoint p = grid.WorldToCellPoint(WorldPoint{w.x(), w.y()});
      out.pose = Pose{p.x, p.y, NormalizeAngle(w.yaw() - grid.frame_yaw())};
      out.has_yaw = true;
      break;
    }
    case v1::Position::kCellPose: {
      const v1::CellPose& c = position.cell_pose();
      PATHD_RETURN_IF_ERROR(Finite(absl::StrFormat("%s cell pose (%s, %s, %s)", what,
                                                   Num(c.x()), Num(c.y()), Num(c.yaw())),
                                   {c.x(), c.y(), c.yaw()}));
      out.pose = Pose{c.x(), c.y(), NormalizeAngle(c.yaw())};
      out.has_yaw = true;
      break;
    }
    case v1::Position::KIND_NOT_SET:
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s is not set (give a cell, a world point or a pose)", what));
  }
  PATHD_RETURN_IF_ERROR(OnMap(grid, out.pose.point(), what));
  return out;
}

absl::StatusOr<std::optional<Footprint>> FootprintFromOptions(const v1::PlanOptions& options,
                                                              const Grid& grid) {
  if (!options.has_footprint()) return std::nullopt;
  const v1::Footprint& f = options.footprint();
  const int set = (f.radius_m() != 0.0) + (f.polygon_m_size() > 0) + (f.radius_cells() != 0.0) +
                  (f.polygon_cells_size() > 0);
  if (set != 1) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.footprint must set exactly one of radius_m, polygon_m, radius_cells, "
        "polygon_cells (%d set)",
        set));
  }
  const double to_cells = 1.0 / grid.resolution();
  absl::StatusOr<Footprint> footprint = absl::InternalError("unreachable");
  if (f.radius_m() != 0.0 || f.radius_cells() != 0.0) {
    footprint = f.radius_m() != 0.0 ? Footprint::Circle(f.radius_m() * to_cells)
                                    : Footprint::Circle(f.radius_cells());
  } else {
    std::vector<CellPoint> vertices;
    if (f.polygon_m_size() > 0) {
      for (const v1::WorldPoint& p : f.polygon_m()) {
        vertices.push_back(CellPoint{p.x() * to_cells, p.y() * to_cells});
      }
    } else {
      for (const v1::CellPoint& p : f.polygon_cells()) vertices.push_back(CellPoint{p.x(), p.y()});
    }
    footprint = Footprint::Polygon(std::move(vertices));
  }
  if (!footprint.ok()) {
    return absl::InvalidArgumentError(
        absl::StrCat("options.footprint: ", footprint.status().message()));
  }
  const double reach = std::hypot(grid.width(), grid.height());
  if (footprint->circumscribed_radius() > reach) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.footprint reaches %s cells from the robot's centre, more than the map's "
        "diagonal (%s cells)",
        Num(footprint->circumscribed_radius()), Num(reach)));
  }
  return *std::move(footprint);
}

namespace {

// The robot's checker: the footprint, else a disc of the robot radius, else
// a point-like disc checked with 4 subcells (so one-cell corridors stay
// open).
absl::StatusOr<std::shared_ptr<const FootprintChecker>> RobotChecker(
    const std::optional<Footprint>& footprint, double robot_radius_cells) {
  FootprintCheckerOptions checker{.headings = kHeadingBins};
  Footprint shape = footprint.has_value() ? *footprint : *Footprint::Circle(0.05);
  if (!footprint.has_value()) {
    if (robot_radius_cells > 0.0) {
      shape = *Footprint::Circle(robot_radius_cells);
    } else {
      checker.subcells = 4;
    }
  }
  return SharedFootprintChecker(shape, checker);
}

// options.min_turning_radius_m/_cells (set) in cells, validated.
absl::StatusOr<double> TurningRadiusCells(const v1::PlanOptions& options, const Grid& grid) {
  const bool metres = options.min_turning_radius_case() ==
                      v1::PlanOptions::MinTurningRadiusCase::kMinTurningRadiusM;
  double radius = metres ? options.min_turning_radius_m() : options.min_turning_radius_cells();
  if (!std::isfinite(radius) || radius <= 0.0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("options.min_turning_radius_%s %s must be finite and > 0",
                        metres ? "m" : "cells", Num(radius)));
  }
  if (metres) radius /= grid.resolution();
  const double reach = std::hypot(grid.width(), grid.height());
  if (radius > reach) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "options.min_turning_radius is %s cells, more than the map's diagonal (%s cells)",
        Num(radius), Num(reach)));
  }
  return radius;
}

}  // namespace

absl::Status DecodeKinematics(const WireQuery& wire, const Grid& grid, PlanQuery* query) {
  const v1::PlanOptions& options = *wire.options;
  PATHD_ASSIGN_OR_RETURN(const std::optional<Footprint> footprint,
                         FootprintFromOptions(options, grid));
  const Planner* planner = PlannerRegistry::Default().Get(query->planner);
  if (planner == nullptr || !planner->traits().kinematic) {
    // Grid and geometric planners plan for the footprint's inscribed radius,
    // as Nav2's costmap inflates by it.
    if (footprint.has_value() && query->robot_radius_cells == 0.0) {
      query->robot_radius_cells = footprint->inscribed_radius();
    }
    if (!options.smooth()) return absl::OkStatus();
    // options.smooth = true: the path also as smoothed poses for the robot
    // (the footprint, else the radius's disc, else a point), checked on the
    // map as stored.
    PATHD_ASSIGN_OR_RETURN(query->smooth_for, RobotChecker(footprint, query->robot_radius_cells));
    if (options.min_turning_radius_case() !=
        v1::PlanOptions::MinTurningRadiusCase::MIN_TURNING_RADIUS_NOT_SET) {
      PATHD_ASSIGN_OR_RETURN(query->smooth_min_turning_radius_cells,
                             TurningRadiusCells(options, grid));
    }
    return absl::OkStatus();
  }
  auto kinematic = std::make_shared<KinematicQuery>();
  if (wire.start == nullptr || wire.goal == nullptr) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "planner %s needs a start and a goal", std::string(query->planner)));
  }
  PATHD_ASSIGN_OR_RETURN(const PositionPose start, PoseFromPosition(*wire.start, grid, "start"));
  PATHD_ASSIGN_OR_RETURN(const PositionPose goal, PoseFromPosition(*wire.goal, grid, "goal"));
  kinematic->start = start.pose;
  kinematic->goal = goal.pose;
  const double dx = goal.pose.x - start.pose.x;
  const double dy = goal.pose.y - start.pose.y;
  const double facing = dx == 0.0 && dy == 0.0 ? 0.0 : std::atan2(dy, dx);
  if (!start.has_yaw) kinematic->start.yaw = facing;
  if (!goal.has_yaw) kinematic->goal.yaw = facing;
  kinematic->goal_tolerance_yaw = goal.has_yaw ? 0.0 : std::numbers::pi;
  if (options.has_goal_yaw_tolerance()) {
    const double t = options.goal_yaw_tolerance();
    if (!std::isfinite(t) || t < 0.0) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "options.goal_yaw_tolerance %s must be finite and >= 0 (radians)", Num(t)));
    }
    kinematic->goal_tolerance_yaw = std::min(t, std::numbers::pi);
  }
  kinematic->goal_tolerance_cells = query->goal_tolerance_cells;
  // The tolerance is the kinematic planner's (how close the path ends), not
  // the grid planners' blocked-goal substitute.
  query->goal_tolerance_cells = 0.0;

  PATHD_ASSIGN_OR_RETURN(kinematic->footprint, RobotChecker(footprint, query->robot_radius_cells));
  // The footprint does what the radius's inflation does for grid planners;
  // the inflation costs still decay from its inscribed radius, as Nav2's.
  query->robot_radius_cells = 0.0;
  query->inflation_inscribed_cells = kinematic->footprint->footprint().inscribed_radius();

  PATHD_ASSIGN_OR_RETURN(kinematic->motion, MotionFromProto(options.motion_model()));
  double radius = std::max(kDefaultTurningRadiusM / grid.resolution(), 1.0);
  if (options.min_turning_radius_case() !=
      v1::PlanOptions::MinTurningRadiusCase::MIN_TURNING_RADIUS_NOT_SET) {
    PATHD_ASSIGN_OR_RETURN(radius, TurningRadiusCells(options, grid));
  }
  kinematic->min_turning_radius_cells = radius;
  const v1::KinematicPenalties& p = options.penalties();
  PATHD_RETURN_IF_ERROR(
      SetPenalty(p.has_reverse(), p.reverse(), "reverse", 1.0, &kinematic->reverse_penalty));
  PATHD_RETURN_IF_ERROR(
      SetPenalty(p.has_change(), p.change(), "change", 0.0, &kinematic->change_penalty));
  PATHD_RETURN_IF_ERROR(SetPenalty(p.has_non_straight(), p.non_straight(), "non_straight", 1.0,
                                   &kinematic->non_straight_penalty));
  PATHD_RETURN_IF_ERROR(
      SetPenalty(p.has_cost(), p.cost(), "cost", 0.0, &kinematic->cost_penalty));
  kinematic->lattice = options.lattice();
  kinematic->smooth = !options.has_smooth() || options.smooth();
  query->request.start = kinematic->start.cell();
  query->request.goal = kinematic->goal.cell();
  query->requested_goal = query->request.goal;
  query->request.kinematic = std::move(kinematic);
  return absl::OkStatus();
}

void FillPoses(const PlanResult& result, const Grid& grid, v1::PlanResponse* response) {
  std::vector<PathPose> poses = result.poses;
  if (poses.empty()) {
    // Headings along the path: each point faces the next, the last as the
    // one before it.
    std::vector<CellPoint> points;
    if (!result.polyline.empty()) {
      points = result.polyline;
    } else {
      points.reserve(result.path.size());
      for (const Cell& c : result.path) points.push_back(CellPoint{c.x + 0.5, c.y + 0.5});
    }
    for (size_t i = 0; i < points.size(); ++i) {
      double yaw = 0.0;
      if (points.size() > 1) {
        const size_t a = i + 1 < points.size() ? i : i - 1;
        yaw = std::atan2(points[a + 1].y - points[a].y, points[a + 1].x - points[a].x);
      }
      poses.push_back(PathPose{Pose{points[i].x, points[i].y, yaw}, false});
    }
  }
  response->mutable_poses()->Reserve(static_cast<int>(poses.size()));
  response->mutable_world_poses()->Reserve(static_cast<int>(poses.size()));
  bool any_reverse = false;
  for (const PathPose& p : poses) any_reverse = any_reverse || p.reverse;
  for (const PathPose& p : poses) {
    v1::CellPose* cell = response->add_poses();
    cell->set_x(p.pose.x);
    cell->set_y(p.pose.y);
    cell->set_yaw(p.pose.yaw);
    const WorldPoint w = grid.CellPointToWorld(p.pose.point());
    v1::WorldPose* world = response->add_world_poses();
    world->set_x(w.x);
    world->set_y(w.y);
    world->set_yaw(NormalizeAngle(p.pose.yaw + grid.frame_yaw()));
    if (any_reverse) response->add_reverse(p.reverse);
  }
}

}  // namespace pathd::server
