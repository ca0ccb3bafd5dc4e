// pathctl render: a map (and optionally a plan over it, with its expanded
// cells) drawn as a PNG or as text (render.h does the drawing).
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/pathctl/command.h"
#include "client/pathctl/fleet_plan.h"
#include "client/pathctl/maps_stats_cmd.h"
#include "client/pathctl/png_io.h"
#include "client/pathctl/render.h"
#include "core/geometry/structure.h"
#include "core/kinematics/footprint.h"
#include "core/map/inflation.h"
#include "core/map/inflation_cost.h"
#include "core/status_macros.h"

namespace pathd::pathctl {
namespace {

// The Plan request of `render NAME SX SY GX GY`: the plan command's options
// that change the path (planner, cost options, limits, via points), and
// always the expanded cells when --expansions asks to draw them.
absl::StatusOr<v1::PlanRequest> RenderPlanRequest(const PlanFlags& options,
                                                  const CostOptions& cost,
                                                  const RobotOptions& robot,
                                                  const std::string& map,
                                                  Args coordinates) {
  v1::PlanRequest request;
  request.set_map(map);
  static constexpr const char* kStart[] = {"SX", "SY"};
  static constexpr const char* kGoal[] = {"GX", "GY"};
  PATHD_ASSIGN_OR_RETURN(
      *request.mutable_start(),
      PositionFromPair(coordinates.subspan(0, 2), options.world, kStart));
  PATHD_ASSIGN_OR_RETURN(
      *request.mutable_goal(),
      PositionFromPair(coordinates.subspan(2, 2), options.world, kGoal));
  if (!options.planner.empty()) {
    PATHD_ASSIGN_OR_RETURN(const v1::Planner planner,
                           PlannerFromName(options.planner));
    request.set_planner(planner);
  }
  v1::PlanOptions* plan_options = request.mutable_options();
  PATHD_RETURN_IF_ERROR(SetCostOptions(cost, plan_options));
  plan_options->set_max_expansions(options.max_expansions);
  if (options.heuristic_weight.has_value()) {
    plan_options->set_heuristic_weight(*options.heuristic_weight);
  }
  plan_options->set_simplify(options.simplify);
  plan_options->set_lookahead(options.lookahead);
  plan_options->set_return_expansions(options.expansions);
  PATHD_RETURN_IF_ERROR(AddViaPoints(options.via, options.world, &request));
  request.set_allow_partial(options.allow_partial);
  PATHD_RETURN_IF_ERROR(SetRobotOptions(robot, &request));
  return request;
}

// The robot's outline in its body frame, cells: --footprint (metres) or
// --footprint_cells, else a circle of the radius the plan applied; empty
// when the robot is a point.
std::vector<CellPoint> BodyOutline(const v1::PlanRequest& request, const Grid& grid,
                                   double applied_radius_cells) {
  std::vector<CellPoint> outline;
  const v1::Footprint& f = request.options().footprint();
  for (const v1::WorldPoint& p : f.polygon_m()) {
    outline.push_back(CellPoint{p.x() / grid.resolution(), p.y() / grid.resolution()});
  }
  for (const v1::CellPoint& p : f.polygon_cells()) outline.push_back(CellPoint{p.x(), p.y()});
  if (!outline.empty()) return outline;
  double radius = applied_radius_cells;
  if (radius <= 0.0 && request.options().has_robot_radius_m()) {
    radius = request.options().robot_radius_m() / grid.resolution();
  }
  if (radius <= 0.0 && request.options().has_robot_radius_cells()) {
    radius = request.options().robot_radius_cells();
  }
  if (radius <= 0.0) return outline;
  for (int i = 0; i < 24; ++i) {
    const double a = 2 * std::numbers::pi * i / 24;
    outline.push_back(CellPoint{radius * std::cos(a), radius * std::sin(a)});
  }
  return outline;
}

// The outline at poses along the path, about one robot length apart, and
// at the last pose.
std::vector<std::vector<CellPoint>> OutlinesAlong(const v1::PlanResponse& response,
                                                  const std::vector<CellPoint>& body) {
  std::vector<std::vector<CellPoint>> outlines;
  if (body.empty() || response.poses_size() == 0) return outlines;
  double reach = 0.0;
  for (const CellPoint& p : body) reach = std::max(reach, std::hypot(p.x, p.y));
  const double spacing = std::max(1.0, 1.5 * reach);
  double travelled = spacing;
  const auto place = [&](const v1::CellPose& pose) {
    std::vector<CellPoint> placed;
    const double c = std::cos(pose.yaw()), s = std::sin(pose.yaw());
    for (const CellPoint& p : body) {
      placed.push_back(CellPoint{pose.x() + c * p.x - s * p.y, pose.y() + s * p.x + c * p.y});
    }
    outlines.push_back(std::move(placed));
  };
  for (int i = 0; i < response.poses_size(); ++i) {
    if (i > 0) {
      travelled += std::hypot(response.poses(i).x() - response.poses(i - 1).x(),
                              response.poses(i).y() - response.poses(i - 1).y());
    }
    if (travelled >= spacing || i + 1 == response.poses_size()) {
      place(response.poses(i));
      travelled = 0.0;
    }
  }
  return outlines;
}

Cell CoreCell(const v1::Cell& cell) { return Cell{cell.x(), cell.y()}; }

// The robot radius a grid planner applies without a plan to say so: the
// options' robot radius, else the footprint's inscribed radius (as the
// server's decoding does, server/convert_kinematic.cc), else 0.
absl::StatusOr<double> GridRobotRadius(const Grid& stored, const v1::PlanOptions& options) {
  using O = v1::PlanOptions;
  if (options.robot_radius_case() != O::ROBOT_RADIUS_NOT_SET) {
    return options.robot_radius_case() == O::kRobotRadiusM
               ? options.robot_radius_m() / stored.resolution()
               : options.robot_radius_cells();
  }
  const v1::Footprint& f = options.footprint();
  if (f.radius_m() > 0.0) return f.radius_m() / stored.resolution();
  if (f.radius_cells() > 0.0) return f.radius_cells();
  std::vector<CellPoint> polygon;
  for (const v1::WorldPoint& p : f.polygon_m()) {
    polygon.push_back(CellPoint{p.x() / stored.resolution(), p.y() / stored.resolution()});
  }
  for (const v1::CellPoint& p : f.polygon_cells()) polygon.push_back(CellPoint{p.x(), p.y()});
  if (polygon.empty()) return 0.0;
  PATHD_ASSIGN_OR_RETURN(const Footprint footprint, Footprint::Polygon(std::move(polygon)));
  return footprint.inscribed_radius();
}

// The grid the planners see for these options: `stored` shaped (robot
// radius, Nav2 inflation costs, clearance costs) by the server's own core
// function, with the options converted as the server decodes them
// (server/convert.cc: metres / resolution, capped at the map's diagonal;
// the cost scaling factor per metre times the resolution, unset 10).
// `robot_radius_cells` is the radius the plan applied (PlanResponse), or
// GridRobotRadius without a plan; `cost_inscribed_cells` the radius the
// inflation costs decay from when larger (a kinematic plan's footprint,
// GridShape::cost_inscribed_cells). Drawn here rather than fetched: the API
// has no call that returns a shaped grid, and the same function on the same
// cells gives the same bytes.
absl::StatusOr<Grid> PlanningGridOf(const Grid& stored, const v1::PlanOptions& options,
                                    double robot_radius_cells, double cost_inscribed_cells) {
  const double diagonal = std::hypot(stored.width(), stored.height());
  auto cells = [&](bool metres, double value) {
    return std::min(metres ? value / stored.resolution() : value, diagonal);
  };
  using O = v1::PlanOptions;
  const double robot = std::min(robot_radius_cells, diagonal);
  const double inflation = cells(options.inflation_radius_case() == O::kInflationRadiusM,
                                 options.inflation_radius_case() == O::kInflationRadiusM
                                     ? options.inflation_radius_m()
                                     : options.inflation_radius_cells());
  const double clearance = cells(options.min_clearance_case() == O::kMinClearanceM,
                                 options.min_clearance_case() == O::kMinClearanceM
                                     ? options.min_clearance_m()
                                     : options.min_clearance_cells());
  const double factor = options.has_cost_scaling_factor() ? options.cost_scaling_factor()
                                                          : kDefaultCostScalingFactor;
  const GridShape shape = GridShape::Of(robot, inflation, factor * stored.resolution(),
                                        clearance, options.unknown_is_free(),
                                        std::min(cost_inscribed_cells, diagonal));
  if (!shape.shaped()) return stored;
  return ShapeGrid(stored, shape);
}

// `render NAME [--plan SX SY GX GY] (-o FILE.png | --ascii)`: GetMap, an
// optional Plan, then the picture.
int Render(CommandEnv& env, Args args) {
  const RenderFlags& options = env.options().render;
  const PlanFlags& plan_flags = env.options().plan;
  if (env.global().output != OutputFormat::kTable) {
    return env.Unsupported(
        "render", "it draws a picture; 'plan --output json' prints the path");
  }
  if (args.size() != 1 && args.size() != 5) {
    return env.Usage("render takes NAME, or NAME --plan SX SY GX GY, or NAME --robots FILE");
  }
  const bool plan = args.size() == 5;
  const bool fleet = !env.options().fleet.robots.empty();
  if (fleet && plan) return env.Usage("render draws --plan or --robots (a fleet plan), not both");
  if (options.plan && !plan)
    return env.Usage("--plan needs SX SY GX GY after NAME");
  if (plan_flags.expansions && !plan) {
    return env.Usage(
        "--expansions draws a plan's expanded cells; add --plan SX SY GX GY");
  }
  if (options.out.empty() && !options.ascii) {
    return env.Usage("render needs -o FILE.png (a picture) or --ascii (text)");
  }
  if (!options.out.empty() &&
      !absl::EndsWith(absl::AsciiStrToLower(options.out), ".png")) {
    return env.Usage(absl::StrCat("-o ", options.out,
                                  ": render writes PNG; name a .png file"));
  }
  if (options.scale < 0 || options.scale > kMaxScale) {
    return env.Usage(
        absl::StrFormat("--scale must be 1..%d pixels per cell, not %d",
                        kMaxScale, options.scale));
  }
  std::optional<v1::PlanRequest> request;
  if (plan) {
    absl::StatusOr<v1::PlanRequest> built =
        RenderPlanRequest(plan_flags, env.options().cost, env.options().robot, args[0],
                          args.subspan(1));
    if (!built.ok()) return env.Usage(built.status().message());
    request = *std::move(built);
  }
  std::optional<v1::PlanFleetRequest> fleet_request;
  if (fleet) {
    absl::StatusOr<v1::PlanFleetRequest> built = FleetPlanRequest(env.options(), args[0]);
    if (!built.ok()) {
      return built.status().code() == absl::StatusCode::kInvalidArgument
                 ? env.Usage(built.status().message())
                 : env.Fail(built.status());
    }
    fleet_request = *std::move(built);
  }

  // The cost options (and a footprint's inscribed radius) shape the drawn
  // grid with or without a plan.
  v1::PlanOptions cost_options;
  if (absl::Status s = SetCostOptions(env.options().cost, &cost_options); !s.ok()) {
    return env.Usage(s.message());
  }
  if (absl::Status s = SetFootprint(env.options().robot, &cost_options); !s.ok()) {
    return env.Usage(s.message());
  }

  absl::StatusOr<Grid> grid = FetchGrid(env, args[0]);
  if (!grid.ok()) return env.Fail(grid.status());
  PlanOverlay overlay;
  int code = kExitOk;
  std::string summary;
  std::optional<double> applied_radius;
  bool kinematic_plan = false;
  if (request.has_value()) {
    absl::StatusOr<v1::PlanResponse> response = env.client().Plan(*request);
    if (!response.ok()) return env.Fail(response.status());
    applied_radius = response->robot_radius_cells();
    kinematic_plan = IsKinematicPlanner(response->planner());
    for (const v1::Cell& c : response->path())
      overlay.path.push_back(CoreCell(c));
    for (const v1::CellPoint& p : response->polyline())
      overlay.polyline.push_back(CellPoint{p.x(), p.y()});
    const bool kinematic = IsKinematicPlanner(response->planner());
    if (kinematic || request->options().smooth()) {
      // The poses are the path (a kinematic planner's, or a grid path
      // smoothed for the robot): drawn through their exact points.
      overlay.polyline.clear();
      for (const v1::CellPose& p : response->poses())
        overlay.polyline.push_back(CellPoint{p.x(), p.y()});
    }
    overlay.outlines = OutlinesAlong(
        *response, BodyOutline(*request, *grid, response->robot_radius_cells()));
    for (const v1::Cell& c : response->expanded())
      overlay.expanded.push_back(CoreCell(c));
    overlay.start = CoreCell(response->start());
    overlay.goal = CoreCell(response->goal());
    code = response->found() ? kExitOk : kExitNoPath;
    summary =
        response->path_size() > 0
            ? absl::StrFormat(
                  "path (%s): %d %s, cost %.6f, length %.6f, %d expansions",
                  response->planner(),
                  response->polyline_size() > 0 ? response->polyline_size()
                                                : response->path_size(),
                  response->polyline_size() > 0 ? "polyline vertices"
                  : response->any_angle()       ? "vertices"
                                                : "cells",
                  response->cost(), response->length(), response->expansions())
            : absl::StrFormat("no path (%s): %s: %s", response->planner(),
                              OutcomeName(response->outcome()),
                              response->reason());
    if (plan_flags.expansions) {
      absl::StrAppendFormat(
          &summary, ", %d expanded cells drawn%s", response->expanded_size(),
          response->expanded_truncated()
              ? " (truncated: the server's --max_returned_expansions)"
              : "");
    }
  }
  if (fleet_request.has_value()) {
    absl::StatusOr<v1::PlanFleetResponse> response = env.client().PlanFleet(*fleet_request);
    if (!response.ok()) return env.Fail(response.status());
    for (const v1::FleetPath& p : response->paths()) {
      std::vector<Cell>& cells = overlay.fleet_paths.emplace_back();
      for (const v1::Cell& c : p.cells()) cells.push_back(CoreCell(c));
    }
    code = response->found() ? kExitOk : kExitNoPath;
    summary = FleetPlanSummary(*response);
  }
  // After the plan, so a bad option is reported by the server first, with
  // its field's name.
  double cost_inscribed = 0.0;
  if (!applied_radius.has_value() || kinematic_plan) {
    absl::StatusOr<double> radius = GridRobotRadius(*grid, cost_options);
    if (!radius.ok()) return env.Usage(radius.status().message());
    // A kinematic plan applies no radius; its costs decay from the
    // footprint's inscribed one, as the server's do.
    if (kinematic_plan) {
      cost_inscribed = *radius;
    } else {
      applied_radius = *radius;
    }
  }
  grid = PlanningGridOf(*grid, cost_options, *applied_radius, cost_inscribed);
  if (!grid.ok()) return env.Usage(grid.status().message());
  if (!options.overlay.empty()) {
    absl::StatusOr<GeometricStructure> structure =
        DescribeStructure(options.overlay, *grid, env.options().cost.unknown_is_free);
    if (!structure.ok()) return env.Usage(structure.status().message());
    overlay.structure_segments = std::move(structure->segments);
    overlay.structure_points = std::move(structure->points);
    absl::StrAppend(&summary, summary.empty() ? "" : "\n",
                    StructureSummary(*structure));
  }
  pathctl::RenderOptions render_options;
  render_options.scale = options.scale;
  render_options.y_up = options.y_up;
  if (options.ascii) {
    absl::StatusOr<std::string> text =
        RenderText(*grid, overlay, render_options);
    if (!text.ok()) return env.Usage(text.status().message());
    env.out() << *text;
  }
  if (!options.out.empty()) {
    absl::StatusOr<Image> image = RenderImage(*grid, overlay, render_options);
    if (!image.ok()) return env.Usage(image.status().message());
    if (absl::Status s = WritePngFile(*image, options.out); !s.ok())
      return env.Fail(s);
    if (image->width >= grid->width()) {
      env.out() << absl::StrFormat("wrote %s (%dx%d pixels, %d per cell)\n",
                                   options.out, image->width, image->height,
                                   image->width / grid->width());
    } else {
      // Downsampled: one pixel per block of k x k cells.
      const int k = (grid->width() + image->width - 1) / image->width;
      env.out() << absl::StrFormat(
          "wrote %s (%dx%d pixels, one per %dx%d cells, the most blocking "
          "cost of each block)\n",
          options.out, image->width, image->height, k, k);
    }
  }
  if (!summary.empty()) env.out() << summary << "\n";
  return code;
}

constexpr absl::string_view kRenderFlags[] = {
    "plan", "out", "o", "ascii", "scale", "y_up", "overlay", "planner", "world", "via",
    "robots", "solver", "time_limit", "refine", "suboptimality", "restarts", "max_steps",
    "seed",
    "allow_partial", "simplify", "max_expansions", "heuristic_weight", "lookahead",
    "expansions", "connectivity", "cost_weight", "unknown_is_free", "robot_radius",
    "robot_radius_cells", "min_clearance",
    "min_clearance_cells", "footprint", "footprint_cells", "min_turning_radius",
    "min_turning_radius_cells", "motion_model", "reverse_penalty", "change_penalty",
    "non_straight_penalty", "cost_penalty", "start_yaw", "goal_yaw", "goal_yaw_tolerance",
    "lattice", "no_smooth", "smooth", "inflation_radius", "inflation_radius_cells",
    "cost_scaling_factor"};

}  // namespace

const Command kRenderCommand = {
    .name = "render",
    .synopsis = "NAME [--plan SX SY GX GY [--planner P] [--expansions]\n"
                " [plan and cost options]]\n"
                " (-o FILE.png [--scale N] | --ascii) [--y_up] [--overlay KIND]\n"
                "NAME --robots FILE [fleet plan options] (-o FILE.png | --ascii)",
    .help = "Draws map NAME as a PNG (-o) or as text (--ascii), and with --plan the\n"
            "path from (SX, SY) to (GX, GY), its start and goal, and with\n"
            "--expansions the cells the search expanded. Cost options that shape the\n"
            "planning grid (--robot_radius, --inflation_radius, --min_clearance)\n"
            "draw the grid the planners see: inscribed cells, and costs in shades.\n"
            "--overlay KIND draws what a geometric planner builds from the map under\n"
            "it (polygons, visibility, mesh, decomposition, voronoi), built here by\n"
            "the planners' own code.\n"
            "With a --footprint (or a robot radius) the robot's outline is drawn\n"
            "along the path, about one robot length apart.\n"
            "--robots FILE plans the robots of FILE with PlanFleet (as 'pathctl fleet\n"
            "plan') and draws each robot's path in its own colour, its start as a disc\n"
            "and its goal as a ring (text: letters a, b, ... and capitals).\n"
            "A map longer than 4096 cells on a side is drawn at one pixel per\n"
            "block of k x k cells (the smallest k that fits 4096 pixels), each\n"
            "pixel the block's most blocking cost (lethal wins), unless --scale is\n"
            "given.\n"
            "Exit code 3 when the plan found no path (the map is still drawn).",
    .flags = kRenderFlags,
    .run = Render,
    .map_arg = MapArg::kExisting,
};

}  // namespace pathd::pathctl
