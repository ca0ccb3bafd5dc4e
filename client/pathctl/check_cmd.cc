// pathctl check: whether a path (cells or world points) is valid on a
// map's current version, by IsPathValid.
#include "client/pathctl/check_cmd.h"

#include <cmath>
#include <string>
#include <utility>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "client/pathctl/command.h"
#include "client/pathctl/files.h"
#include "core/status_macros.h"

namespace pathd::pathctl {
namespace {

// Poses from positional "X Y" pairs, cells or (with --world) metres.
absl::StatusOr<std::vector<v1::Position>> PosesFromArgs(Args args, bool world) {
  if (args.empty() || args.size() % 2 != 0) {
    return absl::InvalidArgumentError(
        "check takes NAME and X Y pairs (or NAME --path_file F)");
  }
  std::vector<v1::Position> poses;
  for (size_t i = 0; i < args.size(); i += 2) {
    const std::string x_name = absl::StrCat("X", i / 2 + 1);
    const std::string y_name = absl::StrCat("Y", i / 2 + 1);
    const char* const names[] = {x_name.c_str(), y_name.c_str()};
    PATHD_ASSIGN_OR_RETURN(v1::Position pose,
                           PositionFromPair(args.subspan(i, 2), world, names));
    poses.push_back(std::move(pose));
  }
  return poses;
}

// Up to 32 indices, then how many more (--json has them all); "none" for
// an empty list.
std::string FormatIndices(
    const google::protobuf::RepeatedField<int32_t>& indices) {
  constexpr int kShown = 32;
  if (indices.empty()) return "none";
  if (indices.size() <= kShown) return absl::StrJoin(indices, " ");
  return absl::StrCat(
      absl::StrJoin(indices.begin(), indices.begin() + kShown, " "), " ... (",
      indices.size(), " in all)");
}

int Check(CommandEnv& env, Args args) {
  const CheckOptions& options = env.options().check;
  if (args.empty()) return env.Usage("check takes NAME X1 Y1 [X2 Y2 ...]");
  v1::IsPathValidRequest request;
  request.set_map(args[0]);
  absl::StatusOr<std::vector<v1::Position>> poses;
  if (!options.path_file.empty()) {
    if (args.size() != 1) {
      return env.Usage(
          "check takes the poses from --path_file or the command line, "
          "not both");
    }
    absl::StatusOr<std::string> text = ReadTextFile(options.path_file);
    if (!text.ok()) return env.Fail(text.status());
    poses = ParsePathFile(*text, options.path_file, options.world);
  } else {
    poses = PosesFromArgs(args.subspan(1), options.world);
  }
  if (!poses.ok()) return env.Usage(poses.status().message());
  for (v1::Position& pose : *poses) *request.add_path() = std::move(pose);
  if (absl::Status s = SetCostOptions(env.options().cost, request.mutable_options());
      !s.ok()) {
    return env.Usage(s.message());
  }
  if (absl::Status s = SetFootprint(env.options().robot, request.mutable_options()); !s.ok()) {
    return env.Usage(s.message());
  }

  absl::StatusOr<v1::IsPathValidResponse> response =
      env.client().IsPathValid(request);
  if (!response.ok()) return env.Fail(response.status());
  const int code = response->valid() ? kExitOk : kExitInvalidPath;
  if (env.json()) {
    const int print_code = env.PrintJson(*response);
    return print_code == kExitOk ? code : print_code;
  }
  if (env.csv()) {
    Table table({"valid", "map_version", "poses", "cost", "length",
                 "invalid_poses", "invalid_steps", "reason"});
    table.AddRow({response->valid() ? "true" : "false",
                  absl::StrCat(response->map_version()),
                  absl::StrCat(request.path_size()),
                  response->valid() ? FormatNumber(response->cost()) : "",
                  response->valid() ? FormatNumber(response->length()) : "",
                  absl::StrJoin(response->invalid_indices(), " "),
                  absl::StrJoin(response->invalid_steps(), " "), response->reason()});
    env.PrintCsv(table);
    return code;
  }
  std::ostream& out = env.out();
  out << "valid:         " << (response->valid() ? "yes" : "no") << "\n"
      << absl::StrFormat("map version:   %d\nposes:         %d\n",
                         response->map_version(), request.path_size());
  if (response->robot_radius_cells() > 0) {
    out << absl::StrFormat("robot radius:  %g cells\n",
                           response->robot_radius_cells());
  }
  if (response->footprint_checked()) out << "footprint:     checked at every pose and step\n";
  if (response->valid()) {
    if (!response->footprint_checked()) {
      out << absl::StrFormat("cost:          %.6f\n", response->cost());
    }
    out << absl::StrFormat("length:        %.6f (%g m)\n", response->length(),
                           response->length_m());
    return code;
  }
  out << "invalid poses: " << FormatIndices(response->invalid_indices()) << "\n"
      << "invalid steps: " << FormatIndices(response->invalid_steps()) << "\n"
      << "reason:        " << response->reason() << "\n";
  return code;
}

}  // namespace

absl::StatusOr<std::vector<v1::Position>> ParsePathFile(
    absl::string_view text, absl::string_view file_name, bool world) {
  std::vector<v1::Position> poses;
  int line_number = 0;
  for (absl::string_view line : absl::StrSplit(text, '\n')) {
    ++line_number;
    line = absl::StripAsciiWhitespace(line);
    if (line.empty() || absl::StartsWith(line, "#")) continue;
    const std::vector<absl::string_view> fields =
        absl::StrSplit(line, absl::ByAnyChar(" \t,"), absl::SkipEmpty());
    v1::Position pose;
    bool ok = fields.size() == 2;
    if (fields.size() == 3) {
      // "X Y YAW": a pose, X Y in metres (--world) or cell coordinates.
      double x = 0.0, y = 0.0, yaw = 0.0;
      ok = absl::SimpleAtod(fields[0], &x) && absl::SimpleAtod(fields[1], &y) &&
           absl::SimpleAtod(fields[2], &yaw) && std::isfinite(x) && std::isfinite(y) &&
           std::isfinite(yaw);
      if (world) {
        pose.mutable_world_pose()->set_x(x);
        pose.mutable_world_pose()->set_y(y);
        pose.mutable_world_pose()->set_yaw(yaw);
      } else {
        pose.mutable_cell_pose()->set_x(x);
        pose.mutable_cell_pose()->set_y(y);
        pose.mutable_cell_pose()->set_yaw(yaw);
      }
    } else if (ok && world) {
      double x = 0.0;
      double y = 0.0;
      ok = absl::SimpleAtod(fields[0], &x) && absl::SimpleAtod(fields[1], &y) &&
           std::isfinite(x) && std::isfinite(y);
      pose.mutable_world()->set_x(x);
      pose.mutable_world()->set_y(y);
    } else if (ok) {
      int32_t x = 0;
      int32_t y = 0;
      ok = absl::SimpleAtoi(fields[0], &x) && absl::SimpleAtoi(fields[1], &y);
      pose.mutable_cell()->set_x(x);
      pose.mutable_cell()->set_y(y);
    }
    if (!ok) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s:%d: '%s' is not \"X Y\" (%s) or \"X Y YAW\" (a pose, radians)", file_name,
          line_number, line, world ? "two finite numbers, metres" : "two integers, cells"));
    }
    poses.push_back(std::move(pose));
  }
  if (poses.empty()) {
    return absl::InvalidArgumentError(absl::StrCat(file_name, ": no poses"));
  }
  return poses;
}

constexpr absl::string_view kCheckFlags[] = {
    "world", "path_file", "connectivity", "cost_weight", "unknown_is_free",
    "robot_radius", "robot_radius_cells", "footprint", "footprint_cells"};

const Command kCheckCommand = {
    .name = "check",
    .synopsis = "NAME X1 Y1 [X2 Y2 ...] [--world] [cost options] [--footprint F]\n"
                "NAME --path_file F [--world] [cost options] [--footprint F]",
    .help = "Checks a path on map NAME's current version: every pose free for the\n"
            "robot and every step a legal move. The poses come from the line or\n"
            "from --path_file (one \"X Y\" per line, or \"X Y YAW\" for a pose with its\n"
            "heading). With --footprint (metres, Nav2's syntax) the robot's outline is\n"
            "checked at every pose, turned to its heading, and along every step.\n"
            "Exit code 4 when the path is not valid; the invalid poses and steps are\n"
            "listed.",
    .flags = kCheckFlags,
    .run = Check,
    .map_arg = MapArg::kExisting,
};

}  // namespace pathd::pathctl
