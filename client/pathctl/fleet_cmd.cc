// pathctl table, nearest, trip and isochrone: the fleet map queries. Points
// are "X,Y;X,Y..." lists (cells, or metres with --world) like plan --via;
// costs print in metres beside cells; --output json prints the response,
// csv one row per entry, stop or ring vertex, and isochrone's geojson a
// FeatureCollection (RFC 7946) of the region in the map's world frame.
#include <cmath>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "client/pathctl/command.h"
#include "proto/geojson.h"

namespace pathd::pathctl {
namespace {

// "X,Y;X,Y..." as positions; INVALID_ARGUMENT naming `flag` and the point.
absl::StatusOr<std::vector<v1::Position>> ParsePoints(const std::string& text, bool world,
                                                      absl::string_view flag) {
  std::vector<v1::Position> out;
  const std::vector<std::string> points = absl::StrSplit(text, ';', absl::SkipWhitespace());
  for (size_t i = 0; i < points.size(); ++i) {
    const std::vector<std::string> xy = absl::StrSplit(points[i], ',');
    const std::string name = absl::StrCat("--", flag, " point ", i + 1);
    if (xy.size() != 2) {
      return absl::InvalidArgumentError(absl::StrCat(name, ": '", points[i], "' is not X,Y"));
    }
    static constexpr const char* kXY[] = {"X", "Y"};
    absl::StatusOr<v1::Position> p = PositionFromPair(Args(xy), world, kXY);
    if (!p.ok()) return absl::InvalidArgumentError(absl::StrCat(name, ": ", p.status().message()));
    out.push_back(*std::move(p));
  }
  if (out.empty()) {
    return absl::InvalidArgumentError(absl::StrCat("--", flag, " X,Y[;X,Y...] is required"));
  }
  return out;
}

std::string Metres(double v) { return absl::StrFormat("%.3f", v); }

// ---- table ----

int RunTable(CommandEnv& env, Args args) {
  const FleetOptions& o = env.options().fleet;
  if (args.size() != 1) return env.Usage("table takes NAME and --sources, --destinations");
  v1::TableRequest request;
  request.set_map(args[0]);
  absl::StatusOr<std::vector<v1::Position>> sources = ParsePoints(o.sources, o.world, "sources");
  if (!sources.ok()) return env.Usage(sources.status().message());
  absl::StatusOr<std::vector<v1::Position>> destinations =
      ParsePoints(o.destinations, o.world, "destinations");
  if (!destinations.ok()) return env.Usage(destinations.status().message());
  for (auto& p : *sources) *request.add_sources() = p;
  for (auto& p : *destinations) *request.add_destinations() = p;
  if (o.method == "backward") {
    request.set_method(v1::TABLE_METHOD_BACKWARD);
  } else if (o.method == "forward") {
    request.set_method(v1::TABLE_METHOD_FORWARD);
  } else if (!o.method.empty() && o.method != "auto") {
    return env.Usage(absl::StrCat("--method must be auto, backward or forward, not '",
                                  o.method, "'"));
  }
  if (absl::Status s = SetCostOptions(env.options().cost, request.mutable_options()); !s.ok()) {
    return env.Usage(s.message());
  }
  absl::StatusOr<v1::TableResponse> response = env.client().Table(request);
  if (!response.ok()) return env.Fail(response.status());
  if (env.json()) return env.PrintJson(*response);
  const int columns = response->destinations_size();
  if (env.csv()) {
    Table table({"source", "destination", "reachable", "cost_m", "length_m", "cost_cells",
                 "length_cells"});
    for (int k = 0; k < response->entries_size(); ++k) {
      const v1::TableEntry& e = response->entries(k);
      table.AddRow({absl::StrCat(k / columns), absl::StrCat(k % columns),
                    e.reachable() ? "true" : "false",
                    e.reachable() ? Metres(e.cost_m()) : "", e.reachable() ? Metres(e.length_m()) : "",
                    e.reachable() ? FormatNumber(e.cost()) : "",
                    e.reachable() ? FormatNumber(e.length()) : ""});
    }
    return env.PrintCsv(table);
  }
  std::ostream& out = env.out();
  out << absl::StrFormat(
      "map version: %d\nmethod:      %s (%d of %d fields cached)\nexpansions:  %d\n"
      "time:        %.3f ms\n\ncost (m), source row -> destination column ('-': unreachable)\n",
      response->map_version(),
      response->method() == v1::TABLE_METHOD_BACKWARD ? "backward" : "forward",
      response->fields_cached(),
      response->method() == v1::TABLE_METHOD_BACKWARD ? columns : 0, response->expansions(),
      response->planning_time_us() / 1000.0);
  std::vector<std::string> header{"from\\to"};
  for (int j = 0; j < columns; ++j) header.push_back(FormatCell(response->destinations(j)));
  Table table(header);
  for (int i = 0; i < response->sources_size(); ++i) {
    std::vector<std::string> row{FormatCell(response->sources(i))};
    for (int j = 0; j < columns; ++j) {
      const v1::TableEntry& e = response->entries(i * columns + j);
      row.push_back(e.reachable() ? Metres(e.cost_m()) : "-");
    }
    table.AddRow(row);
  }
  out << table.Aligned();
  return kExitOk;
}

// ---- nearest ----

int RunNearest(CommandEnv& env, Args args) {
  const FleetOptions& o = env.options().fleet;
  if (args.size() != 3) return env.Usage("nearest takes NAME X Y");
  v1::NearestRequest request;
  request.set_map(args[0]);
  static constexpr const char* kXY[] = {"X", "Y"};
  absl::StatusOr<v1::Position> point = PositionFromPair(args.subspan(1), o.world, kXY);
  if (!point.ok()) return env.Usage(point.status().message());
  *request.mutable_point() = *point;
  if (o.yaw.has_value()) {
    // A pose: its heading orients a polygon footprint.
    if (o.world) {
      v1::WorldPose* p = request.mutable_point()->mutable_world_pose();
      const v1::WorldPoint w = point->world();
      p->set_x(w.x());
      p->set_y(w.y());
      p->set_yaw(*o.yaw);
    } else {
      v1::CellPose* p = request.mutable_point()->mutable_cell_pose();
      const v1::Cell c = point->cell();
      p->set_x(c.x() + 0.5);
      p->set_y(c.y() + 0.5);
      p->set_yaw(*o.yaw);
    }
  }
  if (o.max_distance_m && o.max_distance_cells) {
    return env.Usage("give --max_distance (metres) or --max_distance_cells, not both");
  }
  if (o.max_distance_m) request.set_max_distance_m(*o.max_distance_m);
  if (o.max_distance_cells) request.set_max_distance_cells(*o.max_distance_cells);
  if (absl::Status s = SetCostOptions(env.options().cost, request.mutable_options()); !s.ok()) {
    return env.Usage(s.message());
  }
  if (absl::Status s = SetFootprint(env.options().robot, request.mutable_options()); !s.ok()) {
    return env.Usage(s.message());
  }
  absl::StatusOr<v1::NearestResponse> response = env.client().Nearest(request);
  if (!response.ok()) return env.Fail(response.status());
  const int code = response->found() ? kExitOk : kExitNoPath;
  if (env.json()) {
    env.PrintJson(*response);
    return code;
  }
  if (env.csv()) {
    Table table({"found", "x", "y", "world_x", "world_y", "distance_m", "distance_cells"});
    table.AddRow({response->found() ? "true" : "false", absl::StrCat(response->cell().x()),
                  absl::StrCat(response->cell().y()), Metres(response->world().x()),
                  Metres(response->world().y()), Metres(response->distance_m()),
                  FormatNumber(response->distance_cells())});
    env.PrintCsv(table);
    return code;
  }
  std::ostream& out = env.out();
  out << absl::StrFormat("map version: %d\nrequested:   %s\n", response->map_version(),
                         FormatCell(response->requested()));
  if (!response->found()) {
    out << "found:       no (no free cell within the distance)\n";
    return code;
  }
  out << absl::StrFormat(
      "found:       yes\nnearest:     %s, world (%.3f, %.3f) m\ndistance:    %.3f m (%s cells)\n"
      "robot:       %s\n",
      FormatCell(response->cell()), response->world().x(), response->world().y(),
      response->distance_m(), FormatNumber(response->distance_cells()),
      response->footprint_checked()
          ? std::string("polygon footprint")
          : (response->robot_radius_cells() > 0
                 ? absl::StrFormat("radius %s cells", FormatNumber(response->robot_radius_cells()))
                 : std::string("a point")));
  return code;
}

// ---- trip ----

int RunTrip(CommandEnv& env, Args args) {
  const FleetOptions& o = env.options().fleet;
  if (args.size() != 1) return env.Usage("trip takes NAME and --waypoints");
  v1::TripRequest request;
  request.set_map(args[0]);
  absl::StatusOr<std::vector<v1::Position>> stops = ParsePoints(o.waypoints, o.world, "waypoints");
  if (!stops.ok()) return env.Usage(stops.status().message());
  for (auto& p : *stops) *request.add_waypoints() = p;
  if (o.end == "fixed_last") {
    request.set_end(v1::TRIP_END_FIXED_LAST);
  } else if (o.end == "any") {
    request.set_end(v1::TRIP_END_ANY);
  } else if (!o.end.empty() && o.end != "round_trip") {
    return env.Usage(
        absl::StrCat("--end must be round_trip, fixed_last or any, not '", o.end, "'"));
  }
  if (!o.planner.empty()) {
    absl::StatusOr<v1::Planner> planner = PlannerFromName(o.planner);
    if (!planner.ok()) return env.Usage(planner.status().message());
    request.set_planner(*planner);
  }
  if (absl::Status s = SetCostOptions(env.options().cost, request.mutable_options()); !s.ok()) {
    return env.Usage(s.message());
  }
  absl::StatusOr<v1::TripResponse> response = env.client().Trip(request);
  if (!response.ok()) return env.Fail(response.status());
  const int code = response->found() ? kExitOk : kExitNoPath;
  if (env.json()) {
    env.PrintJson(*response);
    return code;
  }
  if (env.csv()) {
    Table table({"position", "waypoint", "x", "y"});
    for (int k = 0; k < response->order_size(); ++k) {
      const int w = response->order(k);
      const v1::Position& p = request.waypoints(w);
      table.AddRow({absl::StrCat(k), absl::StrCat(w),
                    p.has_cell() ? absl::StrCat(p.cell().x()) : Metres(p.world().x()),
                    p.has_cell() ? absl::StrCat(p.cell().y()) : Metres(p.world().y())});
    }
    env.PrintCsv(table);
    return code;
  }
  std::ostream& out = env.out();
  out << absl::StrFormat("map version: %d\nfound:       %s\n", response->map_version(),
                         response->found() ? "yes" : "no");
  if (!response->reason().empty()) out << "reason:      " << response->reason() << "\n";
  if (response->order_size() == 0) return code;
  out << absl::StrFormat(
      "order:       %s%s\ncost:        %.3f m (%s cells)\nlower bound: %.3f m (%s; gap %.2f%%)\n"
      "method:      %s%s\npath:        %d cells, %.3f m\ntime:        table %.3f ms, order "
      "%.3f ms, legs %.3f ms\n",
      absl::StrJoin(response->order(), " "),
      request.end() == v1::TRIP_END_FIXED_LAST || request.end() == v1::TRIP_END_ANY ? ""
                                                                                     : " 0",
      response->cost_m(), FormatNumber(response->cost()), response->lower_bound_m(),
      response->bound_method(), 100.0 * response->gap(), response->method(),
      response->exact() ? " (optimal)" : "", response->plan().path_size(),
      response->plan().length_m(), response->table_time_us() / 1000.0,
      response->order_time_us() / 1000.0, response->legs_time_us() / 1000.0);
  return code;
}

// ---- isochrone ----

int RunIsochrone(CommandEnv& env, Args args) {
  const FleetOptions& o = env.options().fleet;
  if (args.size() != 3) return env.Usage("isochrone takes NAME X Y and --budget");
  v1::IsochroneRequest request;
  request.set_map(args[0]);
  static constexpr const char* kXY[] = {"X", "Y"};
  absl::StatusOr<v1::Position> start = PositionFromPair(args.subspan(1), o.world, kXY);
  if (!start.ok()) return env.Usage(start.status().message());
  *request.mutable_start() = *start;
  if (o.budget_m.has_value() == o.budget_cells.has_value()) {
    return env.Usage("give --budget (metres) or --budget_cells, one of them");
  }
  if (o.budget_m) request.set_budget_m(*o.budget_m);
  if (o.budget_cells) request.set_budget_cells(*o.budget_cells);
  if (absl::Status s = SetCostOptions(env.options().cost, request.mutable_options()); !s.ok()) {
    return env.Usage(s.message());
  }
  absl::StatusOr<v1::IsochroneResponse> response = env.client().Isochrone(request);
  if (!response.ok()) return env.Fail(response.status());
  if (env.json()) return env.PrintJson(*response);
  if (env.options().global.output == OutputFormat::kGeoJson) {
    env.out() << IsochroneGeoJson(*response, request.map());
    return kExitOk;
  }
  if (env.csv()) {
    // One row per ring vertex, in world metres and cells.
    Table table({"polygon", "ring", "vertex", "world_x", "world_y", "cell_x", "cell_y"});
    for (int p = 0; p < response->polygons_size(); ++p) {
      const v1::IsochronePolygon& poly = response->polygons(p);
      for (int ring = 0; ring <= poly.holes_size(); ++ring) {
        const v1::CellRing& cells = ring == 0 ? poly.exterior() : poly.holes(ring - 1);
        const v1::WorldRing& world =
            ring == 0 ? poly.world_exterior() : poly.world_holes(ring - 1);
        for (int v = 0; v < cells.points_size(); ++v) {
          table.AddRow({absl::StrCat(p), absl::StrCat(ring), absl::StrCat(v),
                        Metres(world.points(v).x()), Metres(world.points(v).y()),
                        FormatNumber(cells.points(v).x()), FormatNumber(cells.points(v).y())});
        }
      }
    }
    return env.PrintCsv(table);
  }
  int holes = 0;
  int vertices = 0;
  for (const v1::IsochronePolygon& p : response->polygons()) {
    holes += p.holes_size();
    vertices += p.exterior().points_size();
    for (const v1::CellRing& h : p.holes()) vertices += h.points_size();
  }
  env.out() << absl::StrFormat(
      "map version: %d\nstart:       %s\nbudget:      %.3f m (%s cells)\n"
      "reachable:   %d cells, %.3f m^2\npolygons:    %d (%d holes, %d vertices)\n"
      "expansions:  %d\n(--output geojson prints the region as GeoJSON)\n",
      response->map_version(), FormatCell(response->start()), response->budget_m(),
      FormatNumber(response->budget_cells()), response->reachable_cells(), response->area_m2(),
      response->polygons_size(), holes, vertices, response->expansions());
  return kExitOk;
}

constexpr absl::string_view kTableFlags[] = {
    "world", "sources", "destinations", "method", "connectivity", "cost_weight",
    "unknown_is_free", "robot_radius", "robot_radius_cells", "min_clearance",
    "min_clearance_cells", "inflation_radius", "inflation_radius_cells", "cost_scaling_factor"};
constexpr absl::string_view kNearestFlags[] = {
    "world", "yaw", "max_distance", "max_distance_cells", "unknown_is_free", "robot_radius",
    "robot_radius_cells", "footprint", "footprint_cells"};
constexpr absl::string_view kTripFlags[] = {
    "world", "waypoints", "end", "planner", "connectivity", "cost_weight", "unknown_is_free",
    "robot_radius", "robot_radius_cells", "min_clearance", "min_clearance_cells",
    "inflation_radius", "inflation_radius_cells", "cost_scaling_factor"};
constexpr absl::string_view kIsochroneFlags[] = {
    "world", "budget", "budget_cells", "connectivity", "cost_weight", "unknown_is_free",
    "robot_radius", "robot_radius_cells", "min_clearance", "min_clearance_cells",
    "inflation_radius", "inflation_radius_cells", "cost_scaling_factor"};

}  // namespace

const Command kTableCommand = {
    .name = "table",
    .synopsis = "NAME --sources X,Y[;X,Y...] --destinations X,Y[;X,Y...]\n"
                " [--method auto|backward|forward] [--world] [cost options]",
    .help = "Prints the cheapest cost (metres) from every source to every destination\n"
            "on map NAME, as OSRM's table; '-' marks a pair with no path. --output csv\n"
            "gives one row per pair with costs and lengths in metres and cells. The\n"
            "server computes one cost-to-go field per destination (kept in its cache,\n"
            "so asking again is nearly free) or one search per source, whichever\n"
            "--method (default auto: fields when destinations <= sources) says.",
    .flags = kTableFlags,
    .run = RunTable,
    .map_arg = MapArg::kExisting,
};

const Command kNearestCommand = {
    .name = "nearest",
    .synopsis = "NAME X Y [--world] [--max_distance M | --max_distance_cells C]\n"
                " [--robot_radius M | --footprint '[[x, y], ...]' [--yaw R]]",
    .help = "Prints the nearest cell to (X, Y) where the robot may stand: outside the\n"
            "robot radius of every obstacle, or with a polygon footprint (at heading\n"
            "--yaw) touching no blocked cell. Exit code 3 when there is none within\n"
            "the distance (default 1024 cells).",
    .flags = kNearestFlags,
    .run = RunNearest,
    .map_arg = MapArg::kExisting,
};

const Command kTripCommand = {
    .name = "trip",
    .synopsis = "NAME --waypoints X,Y[;X,Y...] [--end round_trip|fixed_last|any]\n"
                " [--planner P] [--world] [cost options]",
    .help = "Prints the order to visit the waypoints in, starting at the first: back to\n"
            "it (round_trip, the default), ending at the last (fixed_last) or wherever\n"
            "is cheapest (any). Exact up to 12 stops (Held-Karp), 2-opt + Or-opt local\n"
            "search above, with a lower bound and the gap to it; the legs are planned\n"
            "as one path (--output json has it in plan). Exit code 3 when no order\n"
            "joins every stop.",
    .flags = kTripFlags,
    .run = RunTrip,
    .map_arg = MapArg::kExisting,
};

const Command kIsochroneCommand = {
    .name = "isochrone",
    .synopsis = "NAME X Y --budget M | --budget_cells C [--world] [cost options]\n"
                " [--output table|json|csv|geojson]",
    .help = "Prints the region reachable from (X, Y) within a cost budget: every cell\n"
            "whose cheapest cost from the start is at most the budget, as polygons\n"
            "with holes. --output geojson prints it as a GeoJSON FeatureCollection in\n"
            "the map's world frame (metres), csv one row per ring vertex.",
    .flags = kIsochroneFlags,
    .run = RunIsochrone,
    .map_arg = MapArg::kExisting,
    .geojson = true,
};

}  // namespace pathd::pathctl
