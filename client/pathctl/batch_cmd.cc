// pathctl batch: every line of a file through one PlanBatch stream (a
// writer thread feeds it), answers printed as they arrive, then a summary.
#include "client/pathctl/batch_cmd.h"

#include <cmath>
#include <iostream>
#include <iterator>
#include <memory>
#include <optional>
#include <sstream>
#include <thread>
#include <utility>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "client/pathctl/command.h"
#include "client/pathctl/files.h"
#include "client/pathctl/map_name.h"
#include "client/pathctl/progress.h"
#include "google/protobuf/util/json_util.h"

namespace pathd::pathctl {
namespace {

// One answer of `pathctl batch` as a line: "ID found cost C length L
// expansions N time T us", "ID no-path OUTCOME: reason" or "ID error CODE
// OUTCOME: message".
std::string FormatBatchAnswer(const v1::PlanBatchResponse& answer) {
  const std::string& id = answer.request_id();
  if (answer.has_error()) {
    const v1::PlanError& e = answer.error();
    return absl::StrFormat(
        "%s error %s %s: %s", id,
        absl::StatusCodeToString(static_cast<absl::StatusCode>(e.code())),
        OutcomeName(e.outcome()), e.message());
  }
  const v1::PlanResponse& r = answer.result();
  if (r.found()) {
    return absl::StrFormat("%s found cost %.6f length %.6f expansions %d time %d us",
                           id, r.cost(), r.length(), r.expansions(),
                           r.planning_time_us());
  }
  return absl::StrFormat("%s no-path %s: %s", id, OutcomeName(r.outcome()),
                         r.reason());
}

// The CSV columns of `batch`, one row per answer: status is found, no-path
// or error; an error's status code and message fill code and message.
constexpr const char* kBatchCsvHeader[] = {
    "id", "status", "outcome", "cost", "length", "expansions", "time_us",
    "code", "message"};

std::vector<std::string> BatchAnswerCsvRow(const v1::PlanBatchResponse& answer) {
  if (answer.has_error()) {
    const v1::PlanError& e = answer.error();
    return {answer.request_id(), "error", OutcomeName(e.outcome()), "", "", "", "",
            absl::StatusCodeToString(static_cast<absl::StatusCode>(e.code())),
            e.message()};
  }
  const v1::PlanResponse& r = answer.result();
  return {answer.request_id(), r.found() ? "found" : "no-path",
          OutcomeName(r.outcome()), r.found() ? FormatNumber(r.cost()) : "",
          r.found() ? FormatNumber(r.length()) : "", absl::StrCat(r.expansions()),
          absl::StrCat(r.planning_time_us()), "", r.reason()};
}

// Sends every item of a batch file through one PlanBatch stream (a writer
// thread, because writes block while the server is at its in-flight bound)
// and prints each answer as it arrives, then a summary. --timeout bounds the
// whole batch.
int Batch(CommandEnv& env, Args args) {
  const PlanFlags& options = env.options().plan;
  if (args.size() != 1) return env.Usage("batch takes FILE (or - for stdin)");
  const std::string& file = args[0];
  std::string text;
  if (file == "-") {
    std::stringstream in;
    in << std::cin.rdbuf();
    text = in.str();
  } else {
    absl::StatusOr<std::string> read = ReadTextFile(file);
    if (!read.ok()) return env.Fail(read.status());
    text = *std::move(read);
  }
  absl::StatusOr<std::vector<BatchItem>> items =
      ParseBatchFile(text, file == "-" ? "stdin" : file, options.world);
  if (!items.ok()) return env.Usage(items.status().message());
  v1::PlanOptions shared;
  if (absl::Status s = SetCostOptions(env.options().cost, &shared); !s.ok()) {
    return env.Usage(s.message());
  }
  shared.set_max_expansions(options.max_expansions);
  if (options.heuristic_weight.has_value()) {
    shared.set_heuristic_weight(*options.heuristic_weight);
  }
  shared.set_simplify(options.simplify);
  shared.set_lookahead(options.lookahead);
  if (absl::Status s = SetPathEncoding(options.path_encoding, &shared); !s.ok()) {
    return env.Usage(s.message());
  }
  {
    // The robot's shape and motion apply to every line (headings do not:
    // the lines have none).
    v1::PlanRequest robot;
    if (absl::Status s = SetRobotOptions(env.options().robot, &robot); !s.ok()) {
      return env.Usage(s.message());
    }
    shared.MergeFrom(robot.options());
  }
  std::optional<v1::Planner> default_planner;
  if (!options.planner.empty()) {
    absl::StatusOr<v1::Planner> planner = PlannerFromName(options.planner);
    if (!planner.ok()) return env.Usage(planner.status().message());
    default_planner = *planner;
  }
  for (BatchItem& item : *items) {
    *item.request.mutable_options() = shared;
    if (item.request.planner() == v1::PLANNER_UNSPECIFIED && default_planner) {
      item.request.set_planner(*default_planner);
    }
  }

  const absl::Time started = absl::Now();
  std::unique_ptr<grpc::ClientContext> context = client::MakeContext(env.global().timeout);
  // A load balancer routing by map sends the whole stream to the replica of
  // the first item's map (see "pathctl --help").
  auto stream = env.client().PlanBatch(
      context.get(), items->empty() ? "" : items->front().request.map());
  std::thread writer([&stream, &items] {
    v1::PlanBatchRequest message;
    for (BatchItem& item : *items) {
      message.set_request_id(item.id);
      *message.mutable_request() = std::move(item.request);
      // A failed write means the stream ended; Finish says why.
      if (!stream->Write(message)) break;
    }
    stream->WritesDone();
  });
  google::protobuf::util::JsonPrintOptions json_options;
  json_options.always_print_primitive_fields = true;
  int64_t found = 0;
  int64_t no_path = 0;
  int64_t errors = 0;
  if (env.csv()) {
    env.out() << CsvRecord({std::begin(kBatchCsvHeader), std::end(kBatchCsvHeader)})
              << std::flush;
  }
  ProgressBar bar(env.err(), "batch", static_cast<double>(items->size()),
                  ProgressBar::Unit::kCount, env.global().progress_bars);
  v1::PlanBatchResponse answer;
  while (stream->Read(&answer)) {
    if (answer.has_error()) {
      ++errors;
    } else if (answer.result().found()) {
      ++found;
    } else {
      ++no_path;
    }
    // The answers and the bar share the terminal: the answer goes above it.
    bar.Clear();
    if (env.csv()) {
      env.out() << CsvRecord(BatchAnswerCsvRow(answer));
    } else if (env.json()) {
      std::string line;
      if (!google::protobuf::util::MessageToJsonString(answer, &line, json_options)
               .ok()) {
        line = absl::StrCat("{\"requestId\": \"", answer.request_id(), "\"}");
      }
      env.out() << line << "\n";
    } else {
      env.out() << FormatBatchAnswer(answer) << "\n";
    }
    env.out() << std::flush;
    bar.Update(static_cast<double>(found + no_path + errors),
               absl::StrFormat("%d found, %d no path, %d errors", found, no_path,
                               errors));
  }
  bar.Finish();
  writer.join();
  const grpc::Status status = stream->Finish();
  const double seconds = absl::ToDoubleSeconds(absl::Now() - started);
  const int64_t answered = found + no_path + errors;
  // With --json or --output csv stdout holds only answers, one per line.
  (env.json() || env.csv() ? env.err() : env.out()) << absl::StrFormat(
      "summary: %d of %d answered: %d found, %d no path, %d errors in %.3f s "
      "(%.1f plans/s)\n",
      answered, items->size(), found, no_path, errors, seconds,
      seconds > 0 ? answered / seconds : 0.0);
  if (!status.ok()) return env.Fail(client::FromGrpcStatus(status));
  return errors > 0 ? kExitError : kExitOk;
}

}  // namespace

absl::StatusOr<std::vector<BatchItem>> ParseBatchFile(absl::string_view text,
                                                      absl::string_view file_name,
                                                      bool world) {
  std::vector<BatchItem> items;
  int line_number = 0;
  for (absl::string_view line : absl::StrSplit(text, '\n')) {
    ++line_number;
    line = absl::StripAsciiWhitespace(line);
    if (line.empty() || absl::StartsWith(line, "#")) continue;
    const std::vector<absl::string_view> fields =
        absl::StrSplit(line, absl::ByAnyChar(" \t"), absl::SkipEmpty());
    const auto bad = [&](absl::string_view problem) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s:%d: %s (expected \"ID MAP SX SY GX GY [PLANNER]\")", file_name,
          line_number, problem));
    };
    if (fields.size() != 6 && fields.size() != 7) {
      return bad(absl::StrFormat("%d fields", fields.size()));
    }
    if (absl::Status name = ValidateMapName(fields[1]); !name.ok()) {
      return bad(name.message());
    }
    BatchItem item;
    item.id = std::string(fields[0]);
    item.request.set_map(std::string(fields[1]));
    v1::Position* positions[] = {item.request.mutable_start(),
                                 item.request.mutable_goal()};
    for (int i = 0; i < 2; ++i) {
      const absl::string_view x = fields[2 + 2 * i];
      const absl::string_view y = fields[3 + 2 * i];
      if (world) {
        double wx = 0.0;
        double wy = 0.0;
        if (!absl::SimpleAtod(x, &wx) || !absl::SimpleAtod(y, &wy) ||
            !std::isfinite(wx) || !std::isfinite(wy)) {
          return bad(absl::StrCat("'", x, " ", y, "' is not two finite numbers"));
        }
        positions[i]->mutable_world()->set_x(wx);
        positions[i]->mutable_world()->set_y(wy);
      } else {
        int32_t cx = 0;
        int32_t cy = 0;
        if (!absl::SimpleAtoi(x, &cx) || !absl::SimpleAtoi(y, &cy)) {
          return bad(absl::StrCat("'", x, " ", y, "' is not two integers"));
        }
        positions[i]->mutable_cell()->set_x(cx);
        positions[i]->mutable_cell()->set_y(cy);
      }
    }
    if (fields.size() == 7) {
      absl::StatusOr<v1::Planner> planner = PlannerFromName(fields[6]);
      if (!planner.ok()) return bad(planner.status().message());
      item.request.set_planner(*planner);
    }
    items.push_back(std::move(item));
  }
  if (items.empty()) {
    return absl::InvalidArgumentError(absl::StrCat(file_name, ": no requests"));
  }
  return items;
}

constexpr absl::string_view kBatchFlags[] = {
    "planner", "world", "max_expansions", "heuristic_weight", "simplify", "lookahead",
    "connectivity", "cost_weight", "unknown_is_free", "robot_radius",
    "robot_radius_cells", "min_clearance",
    "min_clearance_cells", "footprint", "footprint_cells", "min_turning_radius",
    "min_turning_radius_cells", "motion_model", "reverse_penalty", "change_penalty",
    "non_straight_penalty", "cost_penalty", "goal_yaw_tolerance", "lattice", "no_smooth", "smooth", "inflation_radius", "inflation_radius_cells",
    "cost_scaling_factor", "path_encoding"};

const Command kBatchCommand = {
    .name = "batch",
    .synopsis = "FILE|- [--planner P] [--world] [--max_expansions N]\n"
                " [--heuristic_weight W] [--simplify] [--lookahead N]\n"
                " [cost options]",
    .help = "Sends every request of FILE (- for stdin) through one PlanBatch stream:\n"
            "one \"ID MAP SX SY GX GY [PLANNER]\" per line (cells, or metres with\n"
            "--world; '#' starts a comment line). --planner is the default for lines\n"
            "without one; the other flags apply to every line. Prints one line per\n"
            "answer as it arrives, then a summary; --timeout bounds the whole batch.\n"
            "Exit code 1 when any item errored.",
    .flags = kBatchFlags,
    .run = Batch,
    .file_first = true,
};

}  // namespace pathd::pathctl
