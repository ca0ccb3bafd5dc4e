// pathctl plan: one Plan call (or PlanStream with --progress) from SX SY
// to GX GY, printed as text, JSON or a CSV of the path.
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "client/pathctl/command.h"
#include "google/protobuf/descriptor.h"
#include "google/protobuf/message.h"
#include "client/pathctl/cost_to_go_cmd.h"
#include "proto/geojson.h"

namespace pathd::pathctl {
namespace {

// The progress line of `plan --progress`: "expansions N  best f F  T s".
std::string FormatProgress(const v1::PlanProgress& progress) {
  return absl::StrFormat(
      "progress: %d expansions, best f %s, %.3f s", progress.expansions(),
      progress.has_best_f() ? absl::StrFormat("%.3f", progress.best_f()) : "-",
      progress.elapsed_us() / 1e6);
}

// Sets fields of `message` (scalar numbers only) from `list`,
// "KEY=VALUE[,KEY=VALUE...]" with the message's field names: --ant_colony
// and --reaction_diffusion. Reflection keeps the keys the proto's, so a new
// option needs no code here. The server checks the ranges.
absl::Status SetFieldsFromList(absl::string_view flag, absl::string_view list,
                               google::protobuf::Message* message) {
  const google::protobuf::Descriptor* descriptor = message->GetDescriptor();
  const google::protobuf::Reflection* reflection = message->GetReflection();
  for (absl::string_view item : absl::StrSplit(list, ',', absl::SkipWhitespace())) {
    const std::pair<absl::string_view, absl::string_view> kv =
        absl::StrSplit(item, absl::MaxSplits('=', 1));
    const absl::string_view key = absl::StripAsciiWhitespace(kv.first);
    const absl::string_view value = absl::StripAsciiWhitespace(kv.second);
    const google::protobuf::FieldDescriptor* field =
        descriptor->FindFieldByName(std::string(key));
    if (field == nullptr) {
      std::vector<std::string> known;
      for (int i = 0; i < descriptor->field_count(); ++i) {
        known.push_back(descriptor->field(i)->name());
      }
      return absl::InvalidArgumentError(
          absl::StrCat("--", flag, ": unknown key '", key, "' (known: ",
                       absl::StrJoin(known, ", "), ")"));
    }
    bool ok = false;
    switch (field->cpp_type()) {
      case google::protobuf::FieldDescriptor::CPPTYPE_INT32: {
        int32_t v;
        ok = absl::SimpleAtoi(value, &v);
        if (ok) reflection->SetInt32(message, field, v);
        break;
      }
      case google::protobuf::FieldDescriptor::CPPTYPE_INT64: {
        int64_t v;
        ok = absl::SimpleAtoi(value, &v);
        if (ok) reflection->SetInt64(message, field, v);
        break;
      }
      case google::protobuf::FieldDescriptor::CPPTYPE_UINT64: {
        uint64_t v;
        ok = absl::SimpleAtoi(value, &v);
        if (ok) reflection->SetUInt64(message, field, v);
        break;
      }
      case google::protobuf::FieldDescriptor::CPPTYPE_DOUBLE: {
        double v;
        ok = absl::SimpleAtod(value, &v);
        if (ok) reflection->SetDouble(message, field, v);
        break;
      }
      default:
        break;
    }
    if (!ok) {
      return absl::InvalidArgumentError(absl::StrCat(
          "--", flag, ": ", key, "='", value, "' is not a ", field->cpp_type_name()));
    }
  }
  return absl::OkStatus();
}

// A PlanError as the status it stands for, its typed outcome appended to the
// message.
absl::Status FromPlanError(const v1::PlanError& error) {
  std::string message = error.message();
  if (error.outcome() != v1::PLAN_OUTCOME_UNSPECIFIED) {
    absl::StrAppend(&message, " (outcome ", OutcomeName(error.outcome()), ")");
  }
  return absl::Status(static_cast<absl::StatusCode>(error.code()), message);
}

// Plan through PlanStream, showing its progress on stderr: one line rewritten
// in place on a terminal, one line per event otherwise (logs, pipes).
absl::StatusOr<v1::PlanResponse> PlanWithProgress(CommandEnv& env,
                                                  const v1::PlanRequest& request) {
  const bool terminal = env.global().stderr_is_terminal;
  std::unique_ptr<grpc::ClientContext> context =
      client::MakeContext(env.global().timeout);
  std::unique_ptr<grpc::ClientReaderInterface<v1::PlanStreamEvent>> reader =
      env.client().PlanStream(context.get(), request);
  std::optional<v1::PlanResponse> result;
  std::optional<v1::PlanError> error;
  bool line_open = false;
  v1::PlanStreamEvent event;
  while (reader->Read(&event)) {
    switch (event.kind_case()) {
      case v1::PlanStreamEvent::kProgress:
        if (terminal) {
          // \r and erase-to-end-of-line: the line shrinks as well as grows.
          env.err() << "\r" << FormatProgress(event.progress()) << "\033[K"
                    << std::flush;
          line_open = true;
        } else {
          env.err() << FormatProgress(event.progress()) << "\n" << std::flush;
        }
        break;
      case v1::PlanStreamEvent::kResult:
        result = std::move(*event.mutable_result());
        break;
      case v1::PlanStreamEvent::kError:
        error = std::move(*event.mutable_error());
        break;
      case v1::PlanStreamEvent::KIND_NOT_SET:
        break;
    }
  }
  if (line_open) env.err() << "\n";
  const grpc::Status status = reader->Finish();
  if (error.has_value()) return FromPlanError(*error);
  if (!status.ok()) return client::FromGrpcStatus(status);
  if (!result.has_value()) {
    return absl::InternalError("PlanStream ended without a final event");
  }
  return *std::move(result);
}

// One position from two arguments (`names` word the errors): a cell, or

// A plan's path as CSV, one row per cell (vertex when any-angle; polyline
// vertex in cell coordinates for the geometric planners) with its world
// point; only the header when there is no path.
Table PlanPathCsv(const v1::PlanResponse& response) {
  Table table({"x", "y", "world_x", "world_y"});
  if (response.polyline_size() > 0) {
    const bool has_world = response.world_polyline_size() == response.polyline_size();
    for (int i = 0; i < response.polyline_size(); ++i) {
      table.AddRow({FormatNumber(response.polyline(i).x()),
                    FormatNumber(response.polyline(i).y()),
                    has_world ? FormatNumber(response.world_polyline(i).x()) : "",
                    has_world ? FormatNumber(response.world_polyline(i).y()) : ""});
    }
    return table;
  }
  const bool has_world = response.world_path_size() == response.path_size();
  for (int i = 0; i < response.path_size(); ++i) {
    const v1::Cell& cell = response.path(i);
    table.AddRow({absl::StrCat(cell.x()), absl::StrCat(cell.y()),
                  has_world ? FormatNumber(response.world_path(i).x()) : "",
                  has_world ? FormatNumber(response.world_path(i).y()) : ""});
  }
  return table;
}

int Plan(CommandEnv& env, Args args) {
  const PlanFlags& options = env.options().plan;
  if (args.size() != 5) return env.Usage("plan takes NAME SX SY GX GY");
  v1::PlanRequest request;
  request.set_map(args[0]);
  static constexpr const char* kNames[] = {"SX", "SY", "GX", "GY"};
  if (options.world) {
    absl::StatusOr<std::vector<double>> p =
        ParseDoubles(args.subspan(1), kNames);
    if (!p.ok()) return env.Usage(p.status().message());
    request.mutable_start()->mutable_world()->set_x((*p)[0]);
    request.mutable_start()->mutable_world()->set_y((*p)[1]);
    request.mutable_goal()->mutable_world()->set_x((*p)[2]);
    request.mutable_goal()->mutable_world()->set_y((*p)[3]);
  } else {
    absl::StatusOr<std::vector<int32_t>> p = ParseInts(args.subspan(1), kNames);
    if (!p.ok()) {
      return env.Usage(absl::StrCat(
          p.status().message(), " (use --world for coordinates in metres)"));
    }
    request.mutable_start()->mutable_cell()->set_x((*p)[0]);
    request.mutable_start()->mutable_cell()->set_y((*p)[1]);
    request.mutable_goal()->mutable_cell()->set_x((*p)[2]);
    request.mutable_goal()->mutable_cell()->set_y((*p)[3]);
  }
  if (!options.planner.empty()) {
    absl::StatusOr<v1::Planner> planner = PlannerFromName(options.planner);
    if (!planner.ok()) return env.Usage(planner.status().message());
    request.set_planner(*planner);
  }
  v1::PlanOptions* plan_options = request.mutable_options();
  if (absl::Status s = SetCostOptions(env.options().cost, plan_options); !s.ok()) {
    return env.Usage(s.message());
  }
  plan_options->set_max_expansions(options.max_expansions);
  if (options.heuristic_weight.has_value()) {
    plan_options->set_heuristic_weight(*options.heuristic_weight);
  }
  if (options.goal_tolerance_cells.has_value() &&
      options.goal_tolerance_m.has_value()) {
    return env.Usage(
        "give --goal_tolerance (metres) or --goal_tolerance_cells, not both");
  }
  if (options.goal_tolerance_cells.has_value()) {
    plan_options->set_goal_tolerance_cells(*options.goal_tolerance_cells);
  }
  if (options.goal_tolerance_m.has_value()) {
    plan_options->set_goal_tolerance_m(*options.goal_tolerance_m);
  }
  if (absl::Status s = AddViaPoints(options.via, options.world, &request); !s.ok()) {
    return env.Usage(s.message());
  }
  request.set_allow_partial(options.allow_partial);
  if (options.snap_start_max_m.has_value() && options.snap_start_max_cells.has_value()) {
    return env.Usage("give --snap_start_max (metres) or --snap_start_max_cells, not both");
  }
  if (!options.snap_start &&
      (options.snap_start_max_m.has_value() || options.snap_start_max_cells.has_value())) {
    return env.Usage("--snap_start_max/--snap_start_max_cells need --snap_start");
  }
  plan_options->set_snap_start(options.snap_start);
  if (options.snap_start_max_m) plan_options->set_snap_start_max_m(*options.snap_start_max_m);
  if (options.snap_start_max_cells) {
    plan_options->set_snap_start_max_cells(*options.snap_start_max_cells);
  }
  plan_options->set_return_expansions(options.expansions);
  plan_options->set_simplify(options.simplify);
  if (absl::Status s = SetPathEncoding(options.path_encoding, plan_options); !s.ok()) {
    return env.Usage(s.message());
  }
  plan_options->set_lookahead(options.lookahead);
  plan_options->set_return_cost_to_go(!options.cost_to_go_file.empty());
  v1::PotentialFieldOptions* pf = plan_options->mutable_potential_field();
  if (options.pf_attractive == "quadratic") {
    pf->set_attractive(v1::ATTRACTIVE_POTENTIAL_QUADRATIC);
  } else if (options.pf_attractive == "conic") {
    pf->set_attractive(v1::ATTRACTIVE_POTENTIAL_CONIC);
  } else if (!options.pf_attractive.empty()) {
    return env.Usage(absl::StrCat("--pf_attractive must be quadratic or conic, not '",
                                  options.pf_attractive, "'"));
  }
  pf->set_attractive_gain(options.pf_attractive_gain);
  pf->set_switch_distance(options.pf_switch_distance);
  pf->set_repulsive_gain(options.pf_repulsive_gain);
  pf->set_influence_distance(options.pf_influence);
  pf->set_step_size(options.pf_step);
  pf->set_max_steps(options.pf_max_steps);
  if (absl::Status s = SetFieldsFromList("ant_colony", options.ant_colony,
                                         plan_options->mutable_ant_colony());
      !s.ok()) {
    return env.Usage(s.message());
  }
  if (absl::Status s = SetFieldsFromList("reaction_diffusion", options.reaction_diffusion,
                                         plan_options->mutable_reaction_diffusion());
      !s.ok()) {
    return env.Usage(s.message());
  }
  if (absl::Status s = SetRobotOptions(env.options().robot, &request); !s.ok()) {
    return env.Usage(s.message());
  }

  absl::StatusOr<v1::PlanResponse> response =
      options.progress ? PlanWithProgress(env, request) : env.client().Plan(request);
  if (!response.ok()) return env.Fail(response.status());
  const int code = response->found() ? kExitOk : kExitNoPath;
  if (!options.cost_to_go_file.empty()) {
    if (response->cost_to_go().empty()) {
      env.err() << "warning: planner " << response->planner()
                << " returned no cost-to-go field (only distance_transform and "
                   "distance_transform_exact do); nothing written\n";
    } else if (absl::Status s = WriteCostToGoCsv(options.cost_to_go_file,
                                                 response->cost_to_go_width(),
                                                 response->cost_to_go());
               !s.ok()) {
      return env.Fail(s);
    }
  }
  if (env.json()) {
    const int print_code = env.PrintJson(*response);
    return print_code == kExitOk ? code : print_code;
  }
  if (env.options().global.output == OutputFormat::kGeoJson) {
    env.out() << PlanGeoJson(*response, request.map());
    return code;
  }
  if (env.csv()) {
    env.PrintCsv(PlanPathCsv(*response));
    return code;
  }
  std::ostream& out = env.out();
  absl::string_view outcome = v1::PlanOutcome_Name(response->outcome());
  absl::ConsumePrefix(&outcome, "PLAN_OUTCOME_");
  out << "found:       " << (response->found() ? "yes" : "no") << "\n"
      << "outcome:     " << outcome << "\n";
  if (!response->reason().empty())
    out << "reason:      " << response->reason() << "\n";
  out << absl::StrFormat(
      "planner:     %s\n"
      "map version: %d\n"
      "start:       %s%s\n"
      "goal:        %s",
      response->planner(), response->map_version(),
      FormatCell(response->start()),
      response->start_snapped()
          ? absl::StrFormat(" (snapped from blocked %s, %.3f m away)",
                            FormatCell(response->requested_start()),
                            response->snap_distance_m())
          : std::string(),
      FormatCell(response->goal()));
  if (response->goal_substituted()) {
    out << " (substituted for blocked "
        << FormatCell(response->requested_goal()) << ")";
  }
  out << "\n";
  if (response->robot_radius_cells() > 0) {
    out << absl::StrFormat("robot radius: %g cells (%g m)\n", response->robot_radius_cells(),
                           response->robot_radius_m());
  }
  // A partial plan (--allow_partial) has a path without found.
  const bool has_path = response->path_size() > 0;
  if (has_path) {
    out << absl::StrFormat("cost:        %.6f (%g m)\nlength:      %.6f (%g m)\n",
                           response->cost(), response->cost_m(), response->length(),
                           response->length_m());
  }
  if (request.via_size() > 0) {
    const int reached = response->reached_goal_index();
    out << absl::StrFormat(
        "via:         %d point%s; reached %s\n", request.via_size(),
        request.via_size() == 1 ? "" : "s",
        reached < 0 ? std::string("none")
        : reached == request.via_size()
            ? std::string("the goal")
            : absl::StrFormat("via[%d] (goal index %d)", reached, reached));
    if (response->leg_end_indices_size() > 0) {
      out << "legs end at: path["
          << absl::StrJoin(response->leg_end_indices(), "], path[") << "]\n";
    }
  }
  out << absl::StrFormat("expansions:  %d\n", response->expansions());
  if (options.expansions) {
    out << absl::StrFormat("expanded:    %d cells returned%s\n",
                           response->expanded_size(),
                           response->expanded_truncated()
                               ? " (truncated: the server's --max_returned_expansions)"
                               : "");
  }
  // Only the caching planners fill these; elsewhere "no" would mislead.
  if (request.planner() == v1::PLANNER_DSTAR_LITE ||
      request.planner() == v1::PLANNER_SPM) {
    out << "cache hit:   " << (response->cache_hit() ? "yes" : "no") << "\n"
        << absl::StrFormat("repaired:    %d cells\n", response->repaired_cells());
  }
  if (response->episodes() > 0) {
    out << absl::StrFormat("episodes:    %d\n", response->episodes());
  }
  if (response->has_ant_colony()) {
    const v1::AntColonyReport& aco = response->ant_colony();
    out << absl::StrFormat(
        "ant colony:  best path from iteration %d of %d run (%s); %d ants "
        "reached the goal, %d died\n",
        aco.best_iteration(), aco.iterations_run(), aco.stopped_by(),
        aco.ants_reached_goal(), aco.ants_died());
  }
  if (response->has_reaction_diffusion()) {
    const v1::ReactionDiffusionReport& rd = response->reaction_diffusion();
    out << absl::StrFormat(
        "front:       %d steps, %d cells reached, speed %.4g cells/time\n"
        "vs exact:    arrival time off by %.2f%% mean, %.2f%% max; optimum "
        "%.6g",
        rd.steps(), rd.reached_cells(), rd.front_speed(),
        100.0 * rd.mean_relative_error(), 100.0 * rd.max_relative_error(),
        rd.optimal_cost());
    if (rd.cost_ratio() > 0.0) {
      out << absl::StrFormat(", path cost %.4f x optimum, %d escapes", rd.cost_ratio(),
                             rd.escapes());
    }
    out << "\n";
  }
  if (response->outcome() == v1::PLAN_OUTCOME_LOCAL_MINIMUM) {
    out << absl::StrFormat("stalled at:  (%.3f, %.3f)\n", response->stall_point().x(),
                           response->stall_point().y());
  }
  if (!response->trajectory().empty()) {
    out << "trajectory (" << response->trajectory().size() << " points)\n";
  }
  if (response->has_clearance()) {
    out << absl::StrFormat("clearance:   %g cells (%g m) at the narrowest point\n",
                           response->min_clearance_cells(), response->min_clearance_m());
  }
  if (!response->cost_to_go().empty() && !options.cost_to_go_file.empty()) {
    out << "cost-to-go:  " << response->cost_to_go().size() << " cells written to "
        << options.cost_to_go_file << "\n";
  }
  out << absl::StrFormat("time:        %d us\n", response->planning_time_us());
  if (has_path) {
    if (response->polyline_size() > 0) {
      std::vector<std::string> points;
      for (const v1::CellPoint& p : response->polyline()) {
        points.push_back(absl::StrFormat("(%g,%g)", p.x(), p.y()));
      }
      out << "polyline (" << response->polyline_size()
          << " vertices, cell coordinates): " << absl::StrJoin(points, " ") << "\n";
    }
    const bool kinematic = IsKinematicPlanner(response->planner());
    if (!kinematic && request.options().smooth() && response->poses_size() > 0) {
      out << absl::StrFormat("poses:       %d, smoothed for the robot%s\n", response->poses_size(),
                             response->has_footprint_collision()
                                 ? absl::StrFormat("; the footprint collides at pose %d",
                                                   response->footprint_collision())
                                 : "; the footprint is free at every pose");
    }
    if (kinematic && response->poses_size() > 0) {
      int cusps = 0;
      for (int i = 1; i < response->reverse_size(); ++i) {
        cusps += response->reverse(i) != response->reverse(i - 1);
      }
      const v1::WorldPose& last = response->world_poses(response->world_poses_size() - 1);
      out << absl::StrFormat(
          "poses:       %d (%d cusp%s), ends at (%g, %g) m facing %g rad in frame %s\n",
          response->poses_size(), cusps, cusps == 1 ? "" : "s", last.x(), last.y(), last.yaw(),
          response->frame_id());
    }
    out << "path (" << response->path_size()
        << (response->any_angle()            ? " vertices, any-angle"
            : response->polyline_size() > 0 ? " cells crossed"
                                             : " cells")
        << "): " << FormatPath(response->path()) << "\n";
    if (options.world) {
      std::vector<std::string> points;
      const bool polyline = response->world_polyline_size() > 0;
      for (const v1::WorldPoint& p :
           polyline ? response->world_polyline() : response->world_path()) {
        points.push_back(absl::StrFormat("(%g,%g)", p.x(), p.y()));
      }
      out << (polyline ? "world polyline (m): " : "world path (m): ")
          << absl::StrJoin(points, " ") << "\n";
    }
  }
  return code;
}

constexpr absl::string_view kPlanFlagNames[] = {
    "world", "planner", "max_expansions", "heuristic_weight", "simplify", "lookahead",
    "via", "allow_partial", "expansions", "goal_tolerance", "goal_tolerance_cells",
    "snap_start", "snap_start_max", "snap_start_max_cells",
    "cost_to_go_file", "pf_attractive", "pf_attractive_gain", "pf_switch_distance",
    "pf_repulsive_gain", "pf_influence", "pf_step", "pf_max_steps", "ant_colony",
    "reaction_diffusion", "progress", "path_encoding",
    "connectivity", "cost_weight", "unknown_is_free", "robot_radius",
    "robot_radius_cells", "min_clearance",
    "min_clearance_cells", "footprint", "footprint_cells", "min_turning_radius",
    "min_turning_radius_cells", "motion_model", "reverse_penalty", "change_penalty",
    "non_straight_penalty", "cost_penalty", "start_yaw", "goal_yaw", "goal_yaw_tolerance",
    "lattice", "no_smooth", "smooth", "inflation_radius", "inflation_radius_cells",
    "cost_scaling_factor"};

}  // namespace

const Command kPlanCommand = {
    .name = "plan",
    .synopsis = "NAME SX SY GX GY [--planner P] [--connectivity 4|8]\n"
                " [--cost_weight W] [--unknown_is_free]\n"
                " [--max_expansions N] [--world] [--simplify]\n"
                " [--robot_radius M | --robot_radius_cells C]\n"
                " [--min_clearance M | --min_clearance_cells C]\n"
                " [--inflation_radius M | --inflation_radius_cells C]\n"
                " [--cost_scaling_factor K]\n"
                " [--heuristic_weight W] [--lookahead N]\n"
                " [--cost_to_go_file F] [--pf_* ...]\n"
                " [--ant_colony K=V,...] [--reaction_diffusion K=V,...]\n"
                " [--goal_tolerance M | --goal_tolerance_cells C]\n"
                " [--snap_start [--snap_start_max M | --snap_start_max_cells C]]\n"
                " [--footprint \"[[x,y],...]\"] [--min_turning_radius M]\n"
                " [--motion_model dubins|reeds_shepp|differential|omnidirectional]\n"
                " [--start_yaw R] [--goal_yaw R] [--goal_yaw_tolerance R]\n"
                " [--reverse_penalty P] [--lattice L] [--no_smooth] [--smooth]\n"
                " [--via X,Y[;X,Y...] [--allow_partial]] [--expansions]\n"
                " [--progress] [--output table|json|csv|geojson]",
    .help = "Plans a path on map NAME from cell (SX, SY) to (GX, GY) (world metres\n"
            "with --world) and prints whether one was found, its cost, length,\n"
            "expansions and cells. Exit code 3 when no path was found (the outcome\n"
            "says why). --progress streams the search's progress to stderr.\n"
            "The kinematic planners (hybrid_astar, state_lattice) plan poses for the\n"
            "--footprint (metres) with --min_turning_radius; see docs/pathctl.md.\n"
            "--output geojson prints the path as a GeoJSON LineString in world metres.",
    .flags = kPlanFlagNames,
    .run = Plan,
    .map_arg = MapArg::kExisting,
    .geojson = true,
};

}  // namespace pathd::pathctl
