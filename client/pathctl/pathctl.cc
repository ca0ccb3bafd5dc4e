// Implementation of the pathctl commands.
#include "proto/planner_names.h"
#include "client/pathctl/pathctl.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <memory>
#include <random>
#include <span>
#include <iostream>
#include <optional>
#include <sstream>
#include <thread>
#include <utility>

#include <curl/curl.h>

#include "absl/flags/commandlineflag.h"
#include "absl/flags/reflection.h"
#include "absl/status/status.h"
#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_replace.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "client/pathctl/load_generator.h"
#include "client/pathctl/map_convert.h"
#include "client/map_source.h"
#include "client/pathctl/navigate_script.h"
#include "client/pathctl/navigate_session.h"
#include "client/pathctl/progress.h"
#include "client/pathctl/render.h"
#include "core/map/grid.h"
#include "core/map_io/map_io.h"
#include "core/status_macros.h"
#include "google/protobuf/struct.pb.h"
#include "google/protobuf/util/json_util.h"

namespace pathd::pathctl {
namespace {

using Args = std::span<const std::string>;

// Largest map `maps get --cells` renders; beyond this ASCII is unreadable and
// the response would be megabytes.
constexpr int32_t kMaxRenderWidth = 1024;
constexpr int64_t kMaxRenderCells = int64_t{1} << 20;

constexpr char kSynopsis[] =
    R"(usage:
  pathctl [flags] maps create NAME --from FILE [--replace] [--resolution R]
  pathctl [flags] maps list
  pathctl [flags] maps get NAME [--cells]
  pathctl [flags] maps delete NAME
  pathctl [flags] maps set NAME X Y COST [--expected_version V]
  pathctl [flags] maps rect NAME X0 Y0 X1 Y1 COST [--expected_version V]
  pathctl [flags] maps watch NAME [--from_version V] [--count N]
  pathctl [flags] maps import NAME FILE [--replace] [--resolution R]
                       [--occupied_thresh T] [--free_thresh T] [--negate]
  pathctl [flags] maps export NAME FILE
  pathctl [flags] plan NAME SX SY GX GY [--planner P] [--connectivity 4|8]
                       [--cost_weight W] [--unknown_is_free]
                       [--max_expansions N] [--world] [--simplify]
                       [--robot_radius M | --robot_radius_cells C]
                       [--heuristic_weight W] [--lookahead N]
                       [--cost_to_go_file F] [--pf_* ...]
                       [--goal_tolerance C | --goal_tolerance_m M]
                       [--via X,Y[;X,Y...] [--allow_partial]] [--expansions]
                       [--progress]
  pathctl [flags] batch FILE|- [--planner P] [--world] [--max_expansions N]
                       [--heuristic_weight W] [--simplify] [--lookahead N]
                       [cost options]
  pathctl [flags] navigate NAME SX SY GX GY [--script FILE] [cost options]
  pathctl [flags] cost-to-go NAME GX GY [--window X,Y,W,H]
                       [--cost_to_go_file F] [--world] [cost options]
  pathctl [flags] check NAME X1 Y1 [X2 Y2 ...] [--world] [cost options]
  pathctl [flags] check NAME --path_file F [--world] [cost options]
  pathctl [flags] cache-stats
  pathctl [flags] health [SERVICE]
  pathctl [flags] metrics [PREFIX ...] [--metrics_address HOST:PORT]
  pathctl [flags] bench NAME [--concurrency N] [--duration T] [--warmup T]
                       [--requests N] [--channels K] [--seed S]
                       [--planner P] [cost options]
  pathctl [flags] bench [NAME] --movingai FILE.map [...]
  pathctl [flags] render NAME [--plan SX SY GX GY [--planner P] [--expansions]
                       [plan and cost options]]
                       (-o FILE.png [--scale N] | --ascii) [--y_up]
  pathctl completion bash
  pathctl --help
)";

std::string PlannerNames() {
  std::vector<absl::string_view> names;
  for (const WirePlanner& p : WirePlanners()) names.push_back(p.name);
  return absl::StrJoin(names, ", ");
}

// Shared state of one command run: where output goes and the lazily made
// client, so usage errors never touch the network.
class Env {
 public:
  Env(const Options& options, std::ostream& out, std::ostream& err)
      : options_(options), out_(out), err_(err) {}

  const Options& options() const { return options_; }
  std::ostream& out() { return out_; }
  std::ostream& err() { return err_; }

  const client::PathdClient& client() {
    if (client_ == nullptr) {
      client_ = std::make_unique<client::PathdClient>(
          client::MakeChannel(options_.server, credentials_), options_.timeout);
    }
    return *client_;
  }

  // Reads the TLS and token files once, before any command connects;
  // a message on `err` and the exit code when they are unusable.
  std::optional<int> LoadCredentials() {
    absl::StatusOr<client::ClientCredentials> credentials =
        client::LoadClientCredentials(options_.credentials);
    if (!credentials.ok()) {
      return absl::IsInvalidArgument(credentials.status())
                 ? Usage(credentials.status().message())
                 : Fail(credentials.status());
    }
    credentials_ = *std::move(credentials);
    if (!credentials_.token.empty() && credentials_.tls_ca_pem.empty() &&
        !client::IsLoopbackAddress(options_.server)) {
      err_ << "warning: sending the token without TLS: anyone on the network "
              "path to "
           << options_.server << " can read it; use --tls_ca\n";
    }
    return std::nullopt;
  }

  const client::ClientCredentials& credentials() const { return credentials_; }

  int Usage(absl::string_view problem) {
    err_ << "error: " << problem << "\n\n"
         << kSynopsis << "run 'pathctl --help' for details\n";
    return kExitUsage;
  }

  int Fail(const absl::Status& status) {
    err_ << "error: " << absl::StatusCodeToString(status.code()) << ": "
         << status.message() << "\n";
    return ExitCodeForStatus(status.code());
  }

  // Prints `message` with protobuf's canonical proto3 JSON mapping. Default
  // values are printed too, so `"found": false` is visible to scripts.
  int PrintJson(const google::protobuf::Message& message) {
    absl::StatusOr<std::string> json = MessageToJson(message, false);
    if (!json.ok()) return Fail(json.status());
    out_ << *json;
    return kExitOk;
  }

  bool csv() const { return options_.output == OutputFormat::kCsv; }

  int PrintCsv(const Table& table) {
    out_ << table.Csv();
    return kExitOk;
  }

  // The usage error of a command asked for a format it cannot print; `why`
  // says what it prints instead.
  int Unsupported(absl::string_view command, absl::string_view why) {
    err_ << "error: " << command << " has no --output "
         << OutputFormatName(options_.output) << ": " << why << "\n";
    return kExitUsage;
  }

 private:
  const Options& options_;
  std::ostream& out_;
  std::ostream& err_;
  std::unique_ptr<client::PathdClient> client_;
  client::ClientCredentials credentials_;
};

absl::Status BadArg(absl::string_view what, absl::string_view text,
                    absl::string_view expected) {
  return absl::InvalidArgumentError(
      absl::StrCat(what, ": '", text, "' is not ", expected));
}

// Parses args[i] as the integer named names[i].
absl::StatusOr<std::vector<int32_t>> ParseInts(
    Args args, std::span<const char* const> names) {
  std::vector<int32_t> values;
  for (size_t i = 0; i < args.size(); ++i) {
    int32_t value = 0;
    if (!absl::SimpleAtoi(args[i], &value)) {
      return BadArg(names[i], args[i], "an integer");
    }
    values.push_back(value);
  }
  return values;
}

absl::StatusOr<std::vector<double>> ParseDoubles(
    Args args, std::span<const char* const> names) {
  std::vector<double> values;
  for (size_t i = 0; i < args.size(); ++i) {
    double value = 0;
    if (!absl::SimpleAtod(args[i], &value) || !std::isfinite(value)) {
      return BadArg(names[i], args[i], "a finite number");
    }
    values.push_back(value);
  }
  return values;
}

std::string FormatCell(const v1::Cell& cell) {
  return absl::StrFormat("(%d,%d)", cell.x(), cell.y());
}

void PrintMapInfo(std::ostream& out, const v1::MapInfo& info) {
  out << absl::StrFormat(
      "name:        %s\n"
      "size:        %d x %d cells\n"
      "resolution:  %g m/cell\n"
      "origin:      (%g, %g) m, yaw %g rad\n"
      "version:     %d\n"
      "free cells:  %d\n"
      "blocked:     %d\n",
      info.name(), info.width(), info.height(), info.resolution(),
      info.origin().x(), info.origin().y(), info.origin().yaw(), info.version(),
      info.free_cells(), info.blocked_cells());
}

// Maps as CSV: one row per map, every MapInfo figure in its own column.
Table MapInfoCsv(std::span<const v1::MapInfo* const> maps) {
  Table table({"name", "width", "height", "resolution", "origin_x", "origin_y",
               "origin_yaw", "version", "free_cells", "blocked_cells"});
  for (const v1::MapInfo* info : maps) {
    table.AddRow({info->name(), absl::StrCat(info->width()),
                  absl::StrCat(info->height()), FormatNumber(info->resolution()),
                  FormatNumber(info->origin().x()), FormatNumber(info->origin().y()),
                  FormatNumber(info->origin().yaw()), absl::StrCat(info->version()),
                  absl::StrCat(info->free_cells()),
                  absl::StrCat(info->blocked_cells())});
  }
  return table;
}

// CreateMap, with a progress line on stderr while the server receives and
// parses `request` (--progress bars only): the call is unary, so the line
// shows what is being sent and for how long, not a fraction. `file` names it.
absl::StatusOr<v1::CreateMapResponse> CreateMapWithProgress(
    Env& env, const v1::CreateMapRequest& request, const std::string& file) {
  if (!env.options().progress_bars) return env.client().CreateMap(request);
  const double bytes = static_cast<double>(request.ByteSizeLong());
  ProgressBar bar(env.err(),
                  absl::StrFormat("maps create %s: sending %s (%.1f MiB)",
                                  request.name(), file, bytes / (1024 * 1024)),
                  0, ProgressBar::Unit::kSeconds, true);
  std::future<absl::StatusOr<v1::CreateMapResponse>> response =
      std::async(std::launch::async,
                 [&env, &request] { return env.client().CreateMap(request); });
  const absl::Time started = absl::Now();
  while (response.wait_for(absl::ToChronoMilliseconds(
             ProgressBar::kRedrawInterval)) != std::future_status::ready) {
    bar.Update(absl::ToDoubleSeconds(absl::Now() - started));
  }
  bar.Update(absl::ToDoubleSeconds(absl::Now() - started));
  bar.Finish();
  return response.get();
}

// --- maps ------------------------------------------------------------------

int MapsCreate(Env& env, Args args) {
  const Options& options = env.options();
  if (args.size() != 1) return env.Usage("maps create takes one NAME");
  if (options.from.empty()) return env.Usage("maps create needs --from FILE");
  const client::MapFileKind kind = client::DetectMapFileKind(options.from);
  if (kind == client::MapFileKind::kUnknown) {
    return env.Usage(
        absl::StrCat("--from ", options.from,
                     ": unknown map file type; expected .map (Moving "
                     "AI) or .yaml/.yml (ROS map_server)"));
  }
  if (options.resolution < 0 || !std::isfinite(options.resolution)) {
    return env.Usage(
        "--resolution must be a positive number of metres per cell");
  }
  if (kind == client::MapFileKind::kRosYaml && options.resolution != 0) {
    return env.Usage(
        "--resolution applies to .map files; a ROS map's YAML sets "
        "its own resolution");
  }
  v1::CreateMapRequest request;
  request.set_name(args[0]);
  request.set_replace(options.replace);
  request.set_resolution(options.resolution);
  if (absl::Status status =
          client::SetMapSourceFromFile(options.from, &request);
      !status.ok()) {
    return env.Fail(status);
  }
  absl::StatusOr<v1::CreateMapResponse> response =
      CreateMapWithProgress(env, request, options.from);
  if (!response.ok()) return env.Fail(response.status());
  if (options.json) return env.PrintJson(*response);
  if (env.csv()) {
    const v1::MapInfo* info[] = {&response->info()};
    return env.PrintCsv(MapInfoCsv(info));
  }
  env.out() << (response->info().version() > 1 ? "replaced" : "created")
            << " map " << args[0] << "\n";
  PrintMapInfo(env.out(), response->info());
  return kExitOk;
}

int MapsList(Env& env, Args args) {
  if (!args.empty()) return env.Usage("maps list takes no arguments");
  absl::StatusOr<v1::ListMapsResponse> response = env.client().ListMaps();
  if (!response.ok()) return env.Fail(response.status());
  if (env.options().json) return env.PrintJson(*response);
  if (env.csv()) {
    std::vector<const v1::MapInfo*> maps;
    for (const v1::MapInfo& info : response->maps()) maps.push_back(&info);
    return env.PrintCsv(MapInfoCsv(maps));
  }
  if (response->maps().empty()) {
    env.out() << "no maps\n";
    return kExitOk;
  }
  Table table({"NAME", "SIZE", "RESOLUTION", "VERSION", "FREE", "BLOCKED"});
  for (const v1::MapInfo& info : response->maps()) {
    table.AddRow({info.name(), absl::StrFormat("%dx%d", info.width(), info.height()),
                  absl::StrFormat("%g", info.resolution()), absl::StrCat(info.version()),
                  absl::StrCat(info.free_cells()), absl::StrCat(info.blocked_cells())});
  }
  env.out() << table.Aligned();
  return kExitOk;
}

int MapsGet(Env& env, Args args) {
  if (args.size() != 1) return env.Usage("maps get takes one NAME");
  if (env.options().cells && env.csv()) {
    return env.Unsupported("maps get --cells",
                           "the cells print as ASCII (table) or base64 (json)");
  }
  v1::GetMapRequest request;
  request.set_name(args[0]);
  request.set_include_cells(env.options().cells);
  absl::StatusOr<v1::GetMapResponse> response = env.client().GetMap(request);
  if (!response.ok()) return env.Fail(response.status());
  if (env.options().json) return env.PrintJson(*response);
  const v1::MapInfo& info = response->info();
  if (env.csv()) {
    const v1::MapInfo* maps[] = {&info};
    return env.PrintCsv(MapInfoCsv(maps));
  }
  PrintMapInfo(env.out(), info);
  if (!env.options().cells) return kExitOk;
  const int64_t cell_count = int64_t{info.width()} * info.height();
  if (info.width() > kMaxRenderWidth || cell_count > kMaxRenderCells) {
    return env.Usage(absl::StrFormat(
        "--cells renders maps up to %d columns and %d cells; %s is %dx%d",
        kMaxRenderWidth, kMaxRenderCells, info.name(), info.width(),
        info.height()));
  }
  if (static_cast<int64_t>(response->cells().size()) != cell_count) {
    return env.Fail(absl::InternalError(absl::StrFormat(
        "server sent %d cell bytes for a %dx%d map", response->cells().size(),
        info.width(), info.height())));
  }
  env.out() << "\n"
            << RenderCells(info.width(), info.height(), response->cells());
  return kExitOk;
}

int MapsDelete(Env& env, Args args) {
  if (args.size() != 1) return env.Usage("maps delete takes one NAME");
  absl::StatusOr<v1::DeleteMapResponse> response =
      env.client().DeleteMap(args[0]);
  if (!response.ok()) return env.Fail(response.status());
  if (env.options().json) return env.PrintJson(*response);
  if (env.csv()) {
    Table table({"name", "last_version"});
    table.AddRow({args[0], absl::StrCat(response->last_version())});
    return env.PrintCsv(table);
  }
  env.out() << "deleted map " << args[0] << " (was at version "
            << response->last_version() << ")\n";
  return kExitOk;
}

int SendUpdate(Env& env, v1::UpdateMapRequest& request) {
  if (env.options().expected_version.has_value()) {
    request.set_expected_version(*env.options().expected_version);
  }
  absl::StatusOr<v1::UpdateMapResponse> response =
      env.client().UpdateMap(request);
  if (!response.ok()) return env.Fail(response.status());
  if (env.options().json) return env.PrintJson(*response);
  if (env.csv()) {
    Table table({"name", "version", "cells_changed"});
    table.AddRow({request.name(), absl::StrCat(response->version()),
                  absl::StrCat(response->cells_changed())});
    return env.PrintCsv(table);
  }
  env.out() << "map " << request.name() << " now at version "
            << response->version() << " (" << response->cells_changed()
            << (response->cells_changed() == 1 ? " cell" : " cells")
            << " changed)\n";
  return kExitOk;
}

int MapsSet(Env& env, Args args) {
  if (args.size() != 4) return env.Usage("maps set takes NAME X Y COST");
  static constexpr const char* kNames[] = {"X", "Y"};
  absl::StatusOr<std::vector<int32_t>> xy =
      ParseInts(args.subspan(1, 2), kNames);
  if (!xy.ok()) return env.Usage(xy.status().message());
  absl::StatusOr<uint32_t> cost = ParseCost(args[3]);
  if (!cost.ok()) return env.Usage(cost.status().message());
  v1::UpdateMapRequest request;
  request.set_name(args[0]);
  v1::CellChange* change = request.add_changes();
  change->mutable_cell()->set_x((*xy)[0]);
  change->mutable_cell()->set_y((*xy)[1]);
  change->set_cost(*cost);
  return SendUpdate(env, request);
}

int MapsRect(Env& env, Args args) {
  if (args.size() != 6)
    return env.Usage("maps rect takes NAME X0 Y0 X1 Y1 COST");
  static constexpr const char* kNames[] = {"X0", "Y0", "X1", "Y1"};
  absl::StatusOr<std::vector<int32_t>> c =
      ParseInts(args.subspan(1, 4), kNames);
  if (!c.ok()) return env.Usage(c.status().message());
  absl::StatusOr<uint32_t> cost = ParseCost(args[5]);
  if (!cost.ok()) return env.Usage(cost.status().message());
  v1::UpdateMapRequest request;
  request.set_name(args[0]);
  v1::CellChange* change = request.add_changes();
  // Any two opposite corners name the same rectangle; the wire wants min/max.
  v1::CellRect* rect = change->mutable_rect();
  rect->set_x_min(std::min((*c)[0], (*c)[2]));
  rect->set_y_min(std::min((*c)[1], (*c)[3]));
  rect->set_x_max(std::max((*c)[0], (*c)[2]));
  rect->set_y_max(std::max((*c)[1], (*c)[3]));
  change->set_cost(*cost);
  return SendUpdate(env, request);
}

// Rectangles of an UPDATED event printed in full; more are only counted.
constexpr int kMaxPrintedRects = 16;

std::string FormatRect(const v1::CellRect& r) {
  if (r.x_min() == r.x_max() && r.y_min() == r.y_max()) {
    return absl::StrFormat("(%d,%d)", r.x_min(), r.y_min());
  }
  return absl::StrFormat("(%d,%d)-(%d,%d)", r.x_min(), r.y_min(), r.x_max(),
                         r.y_max());
}

// One line per event, e.g. "version 7 updated: 2 cells in 1 rect: (3,4)-(4,4)".
std::string FormatMapEvent(const v1::MapEvent& event) {
  switch (event.kind()) {
    case v1::MAP_EVENT_KIND_UPDATED: {
      int64_t cells = 0;
      std::vector<std::string> rects;
      for (const v1::ChangedRect& change : event.changes()) {
        cells += static_cast<int64_t>(change.costs().size());
        if (static_cast<int>(rects.size()) < kMaxPrintedRects) {
          rects.push_back(FormatRect(change.rect()));
        }
      }
      if (event.changes_size() > kMaxPrintedRects) {
        rects.push_back(absl::StrFormat(
            "+%d more", event.changes_size() - kMaxPrintedRects));
      }
      return absl::StrFormat(
          "version %d updated: %d %s in %d %s%s%s", event.version(), cells,
          cells == 1 ? "cell" : "cells", event.changes_size(),
          event.changes_size() == 1 ? "rect" : "rects",
          rects.empty() ? "" : ": ", absl::StrJoin(rects, " "));
    }
    case v1::MAP_EVENT_KIND_RESYNC:
    case v1::MAP_EVENT_KIND_REPLACED:
      return absl::StrFormat(
          "version %d %s: whole map %dx%d", event.version(),
          event.kind() == v1::MAP_EVENT_KIND_RESYNC ? "resync" : "replaced",
          event.info().width(), event.info().height());
    case v1::MAP_EVENT_KIND_DELETED:
      return absl::StrFormat("version %d deleted", event.version());
    default:
      return absl::StrFormat("version %d: unknown event kind %d",
                             event.version(), static_cast<int>(event.kind()));
  }
}

// The CSV columns of `maps watch`, one row per event: the kind without its
// prefix, the map size of whole-map events, and the changed cells and
// rectangles (all of them) of UPDATED ones.
constexpr const char* kMapEventCsvHeader[] = {
    "version", "kind", "width", "height", "changed_cells", "changed_rects", "rects"};

std::vector<std::string> MapEventCsvRow(const v1::MapEvent& event) {
  absl::string_view kind = v1::MapEventKind_Name(event.kind());
  absl::ConsumePrefix(&kind, "MAP_EVENT_KIND_");
  const bool whole_map = event.kind() == v1::MAP_EVENT_KIND_RESYNC ||
                         event.kind() == v1::MAP_EVENT_KIND_REPLACED;
  int64_t cells = 0;
  std::vector<std::string> rects;
  for (const v1::ChangedRect& change : event.changes()) {
    cells += static_cast<int64_t>(change.costs().size());
    rects.push_back(FormatRect(change.rect()));
  }
  return {absl::StrCat(event.version()), std::string(kind),
          whole_map ? absl::StrCat(event.info().width()) : "",
          whole_map ? absl::StrCat(event.info().height()) : "",
          absl::StrCat(cells), absl::StrCat(event.changes_size()),
          absl::StrJoin(rects, " ")};
}

// Streams until --count events, the map's deletion, or an error. No deadline:
// watching is open-ended, so --timeout does not apply.
int MapsWatch(Env& env, Args args) {
  const Options& options = env.options();
  if (args.size() != 1) return env.Usage("maps watch takes one NAME");
  if (options.count < 0) return env.Usage("--count must be >= 0");
  v1::WatchMapRequest request;
  request.set_name(args[0]);
  request.set_from_version(options.from_version);
  grpc::ClientContext context;
  std::unique_ptr<grpc::ClientReaderInterface<v1::MapEvent>> reader =
      env.client().WatchMap(&context, request);
  google::protobuf::util::JsonPrintOptions json_options;
  json_options.always_print_primitive_fields = true;
  int64_t printed = 0;
  bool stopped = false;
  if (env.csv()) {
    env.out() << CsvRecord({std::begin(kMapEventCsvHeader),
                            std::end(kMapEventCsvHeader)})
              << std::flush;
  }
  v1::MapEvent event;
  while (reader->Read(&event)) {
    if (env.csv()) {
      env.out() << CsvRecord(MapEventCsvRow(event));
    } else if (options.json) {
      std::string line;
      if (!google::protobuf::util::MessageToJsonString(event, &line,
                                                       json_options)
               .ok()) {
        context.TryCancel();
        reader->Finish();
        return env.Fail(absl::InternalError("cannot print an event as JSON"));
      }
      env.out() << line << "\n";
    } else {
      env.out() << FormatMapEvent(event) << "\n";
    }
    // Flushed per event: the reader of a pipe wants each line as it happens.
    env.out() << std::flush;
    if (options.count > 0 && ++printed == options.count) {
      stopped = true;
      context.TryCancel();
      break;
    }
  }
  const grpc::Status status = reader->Finish();
  if (stopped || status.ok()) return kExitOk;
  return env.Fail(client::FromGrpcStatus(status));
}

// `maps import NAME FILE`: like `maps create --from`, plus PNG occupancy
// images (alone, or named by a map_server YAML), decoded here.
int MapsImport(Env& env, Args args) {
  const Options& options = env.options();
  if (args.size() != 2) return env.Usage("maps import takes NAME FILE");
  const std::string& file = args[1];
  const std::string lower = absl::AsciiStrToLower(file);
  const bool png = absl::EndsWith(lower, ".png");
  const bool yaml =
      absl::EndsWith(lower, ".yaml") || absl::EndsWith(lower, ".yml");
  if (!png && !yaml && !absl::EndsWith(lower, ".map")) {
    return env.Usage(absl::StrCat(
        file,
        ": unknown map file type; expected .map (Moving AI), .yaml/.yml "
        "(ROS map_server) or .png (occupancy image)"));
  }
  if (options.resolution < 0 || !std::isfinite(options.resolution)) {
    return env.Usage(
        "--resolution must be a positive number of metres per cell");
  }
  if (yaml && options.resolution != 0) {
    return env.Usage(
        "--resolution applies to .map and .png files; a ROS map's YAML sets "
        "its own resolution");
  }
  const bool thresholds = options.occupied_thresh.has_value() ||
                          options.free_thresh.has_value() || options.negate;
  if (!png && thresholds) {
    return env.Usage(
        "--occupied_thresh, --free_thresh and --negate apply to .png files; a "
        "ROS map's YAML sets its own");
  }
  PngImportOptions png_options;
  if (options.resolution > 0) png_options.resolution = options.resolution;
  png_options.occupied_thresh =
      options.occupied_thresh.value_or(png_options.occupied_thresh);
  png_options.free_thresh =
      options.free_thresh.value_or(png_options.free_thresh);
  png_options.negate = options.negate;
  if (!(png_options.free_thresh >= 0 &&
        png_options.free_thresh < png_options.occupied_thresh &&
        png_options.occupied_thresh <= 1)) {
    return env.Usage(absl::StrFormat(
        "need 0 <= --free_thresh < --occupied_thresh <= 1, got %g and %g",
        png_options.free_thresh, png_options.occupied_thresh));
  }
  v1::CreateMapRequest request;
  request.set_name(args[0]);
  request.set_replace(options.replace);
  request.set_resolution(options.resolution);
  absl::StatusOr<ImportKind> kind =
      SetImportSource(file, png_options, &request);
  if (!kind.ok()) return env.Fail(kind.status());
  absl::StatusOr<v1::CreateMapResponse> response =
      CreateMapWithProgress(env, request, file);
  if (!response.ok()) return env.Fail(response.status());
  if (options.json) return env.PrintJson(*response);
  if (env.csv()) {
    const v1::MapInfo* info[] = {&response->info()};
    return env.PrintCsv(MapInfoCsv(info));
  }
  env.out() << (response->info().version() > 1 ? "replaced" : "created")
            << " map " << args[0] << " from " << file << "\n";
  PrintMapInfo(env.out(), response->info());
  return kExitOk;
}

// The map's current cells as a Grid with its resolution and origin.
absl::StatusOr<Grid> FetchGrid(Env& env, const std::string& name) {
  v1::GetMapRequest request;
  request.set_name(name);
  request.set_include_cells(true);
  PATHD_ASSIGN_OR_RETURN(const v1::GetMapResponse response,
                         env.client().GetMap(request));
  const v1::MapInfo& info = response.info();
  const std::string& cells = response.cells();
  absl::StatusOr<Grid> grid =
      Grid::FromCells(info.width(), info.height(),
                      std::vector<uint8_t>(cells.begin(), cells.end()));
  if (!grid.ok()) {
    return absl::InternalError(
        absl::StrFormat("server sent %d cell bytes for a %dx%d map",
                        cells.size(), info.width(), info.height()));
  }
  grid->set_resolution(info.resolution() > 0 ? info.resolution() : 1.0);
  grid->set_origin(
      GridOrigin{info.origin().x(), info.origin().y(), info.origin().yaw()});
  return grid;
}

// `maps export NAME FILE`: .map or .yaml (+ .pgm), warning on stderr about
// the cells the format cannot hold.
int MapsExport(Env& env, Args args) {
  if (args.size() != 2) return env.Usage("maps export takes NAME FILE");
  const std::string& file = args[1];
  const std::string lower = absl::AsciiStrToLower(file);
  const bool yaml =
      absl::EndsWith(lower, ".yaml") || absl::EndsWith(lower, ".yml");
  if (!yaml && !absl::EndsWith(lower, ".map")) {
    return env.Usage(absl::StrCat(
        file,
        ": unknown map file type; export writes .map (Moving AI) or "
        ".yaml/.yml (ROS map_server YAML + PGM)"));
  }
  absl::StatusOr<Grid> grid = FetchGrid(env, args[0]);
  if (!grid.ok()) return env.Fail(grid.status());
  absl::StatusOr<ExportLoss> loss = ExportMapFile(*grid, file);
  if (!loss.ok()) return env.Fail(loss.status());
  const auto warn = [&](int64_t cells, absl::string_view what) {
    if (cells == 0) return;
    env.err() << "warning: " << cells << (cells == 1 ? " cell " : " cells ")
              << what << "\n";
  };
  warn(loss->weighted,
       yaml ? "of cost 1..252 written as free (trinary PGM)"
            : "of cost 1..252 written as 'S' (passable, read back as free)");
  warn(loss->inscribed, "inscribed (253) written as occupied");
  warn(loss->unknown,
       "unknown (255) written as 'O' (out of bounds, read back as lethal)");
  const std::string pgm = yaml ? PgmPathFor(file) : "";
  if (env.options().json) {
    google::protobuf::Struct json;
    auto& fields = *json.mutable_fields();
    fields["map"].set_string_value(args[0]);
    fields["file"].set_string_value(file);
    if (yaml) fields["pgm"].set_string_value(pgm);
    fields["width"].set_number_value(grid->width());
    fields["height"].set_number_value(grid->height());
    fields["weighted_cells"].set_number_value(static_cast<double>(loss->weighted));
    fields["inscribed_cells"].set_number_value(static_cast<double>(loss->inscribed));
    fields["unknown_cells"].set_number_value(static_cast<double>(loss->unknown));
    return env.PrintJson(json);
  }
  if (env.csv()) {
    Table table({"map", "file", "pgm", "width", "height", "weighted_cells",
                 "inscribed_cells", "unknown_cells"});
    table.AddRow({args[0], file, pgm, absl::StrCat(grid->width()),
                  absl::StrCat(grid->height()), absl::StrCat(loss->weighted),
                  absl::StrCat(loss->inscribed), absl::StrCat(loss->unknown)});
    return env.PrintCsv(table);
  }
  env.out() << "wrote " << file;
  if (yaml) env.out() << " and " << pgm;
  env.out() << absl::StrFormat(" (%dx%d cells)\n", grid->width(),
                               grid->height());
  return kExitOk;
}

int Maps(Env& env, Args args) {
  if (args.empty()) {
    return env.Usage(
        "maps needs a subcommand: create, list, get, delete, set, rect, watch, "
        "import, export");
  }
  const std::string& sub = args[0];
  Args rest = args.subspan(1);
  if (sub == "create") return MapsCreate(env, rest);
  if (sub == "list") return MapsList(env, rest);
  if (sub == "get") return MapsGet(env, rest);
  if (sub == "delete") return MapsDelete(env, rest);
  if (sub == "set") return MapsSet(env, rest);
  if (sub == "rect") return MapsRect(env, rest);
  if (sub == "watch") return MapsWatch(env, rest);
  if (sub == "import") return MapsImport(env, rest);
  if (sub == "export") return MapsExport(env, rest);
  return env.Usage(
      absl::StrCat("unknown maps subcommand '", sub,
                   "'; expected create, list, get, delete, set, rect, watch, "
                   "import, export"));
}

// --- plan --------------------------------------------------------------------

// The options every planning command takes: connectivity, cost weight,
// unknown cells and robot radius. INVALID_ARGUMENT (a usage error) for a bad
// combination.
absl::Status SetCostOptions(const Options& options, v1::PlanOptions* plan_options) {
  switch (options.connectivity) {
    case 0:
      break;
    case 4:
      plan_options->set_connectivity(v1::CONNECTIVITY_FOUR);
      break;
    case 8:
      plan_options->set_connectivity(v1::CONNECTIVITY_EIGHT);
      break;
    default:
      return absl::InvalidArgumentError(absl::StrCat(
          "--connectivity must be 4 or 8, not ", options.connectivity));
  }
  if (options.cost_weight.has_value()) {
    plan_options->set_cost_weight(*options.cost_weight);
  }
  plan_options->set_unknown_is_free(options.unknown_is_free);
  if (options.robot_radius_m.has_value() && options.robot_radius_cells.has_value()) {
    return absl::InvalidArgumentError(
        "give --robot_radius (metres) or --robot_radius_cells, not both");
  }
  if (options.robot_radius_m.has_value()) {
    plan_options->set_robot_radius_m(*options.robot_radius_m);
  }
  if (options.robot_radius_cells.has_value()) {
    plan_options->set_robot_radius_cells(*options.robot_radius_cells);
  }
  return absl::OkStatus();
}

// The progress line of `plan --progress`: "expansions N  best f F  T s".
std::string FormatProgress(const v1::PlanProgress& progress) {
  return absl::StrFormat(
      "progress: %d expansions, best f %s, %.3f s", progress.expansions(),
      progress.has_best_f() ? absl::StrFormat("%.3f", progress.best_f()) : "-",
      progress.elapsed_us() / 1e6);
}

// "GOAL_OCCUPIED" for PLAN_OUTCOME_GOAL_OCCUPIED.
std::string OutcomeName(v1::PlanOutcome outcome) {
  absl::string_view name = v1::PlanOutcome_Name(outcome);
  absl::ConsumePrefix(&name, "PLAN_OUTCOME_");
  return std::string(name);
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
absl::StatusOr<v1::PlanResponse> PlanWithProgress(Env& env,
                                                  const v1::PlanRequest& request) {
  const bool terminal = env.options().stderr_is_terminal;
  std::unique_ptr<grpc::ClientContext> context =
      client::MakeContext(env.options().timeout);
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
// with `world` a point in metres.
absl::StatusOr<v1::Position> PositionFromPair(Args xy, bool world,
                                              std::span<const char* const> names) {
  v1::Position position;
  if (world) {
    PATHD_ASSIGN_OR_RETURN(const std::vector<double> p,
                           ParseDoubles(xy, names));
    position.mutable_world()->set_x(p[0]);
    position.mutable_world()->set_y(p[1]);
  } else {
    PATHD_ASSIGN_OR_RETURN(const std::vector<int32_t> p,
                           ParseInts(xy, names));
    position.mutable_cell()->set_x(p[0]);
    position.mutable_cell()->set_y(p[1]);
  }
  return position;
}

// Adds --via's "X,Y;X,Y..." to request.via: cells, or world metres with
// --world. INVALID_ARGUMENT (a usage error) naming the bad point.
absl::Status AddViaPoints(const Options& options, v1::PlanRequest* request) {
  if (options.via.empty()) return absl::OkStatus();
  const std::vector<std::string> points =
      absl::StrSplit(options.via, ';', absl::SkipWhitespace());
  for (size_t i = 0; i < points.size(); ++i) {
    const std::vector<std::string> xy = absl::StrSplit(points[i], ',');
    const std::string name = absl::StrCat("--via point ", i + 1);
    if (xy.size() != 2) {
      return absl::InvalidArgumentError(
          absl::StrCat(name, ": '", points[i], "' is not X,Y"));
    }
    static constexpr const char* kXY[] = {"X", "Y"};
    absl::StatusOr<v1::Position> via = PositionFromPair(Args(xy), options.world, kXY);
    if (!via.ok()) {
      return absl::InvalidArgumentError(
          absl::StrCat(name, ": ", via.status().message()));
    }
    *request->add_via() = *std::move(via);
  }
  return absl::OkStatus();
}

// A plan's path as CSV, one row per cell (vertex when any-angle) with its
// world point; only the header when there is no path.
Table PlanPathCsv(const v1::PlanResponse& response) {
  Table table({"x", "y", "world_x", "world_y"});
  const bool has_world = response.world_path_size() == response.path_size();
  for (int i = 0; i < response.path_size(); ++i) {
    const v1::Cell& cell = response.path(i);
    table.AddRow({absl::StrCat(cell.x()), absl::StrCat(cell.y()),
                  has_world ? FormatNumber(response.world_path(i).x()) : "",
                  has_world ? FormatNumber(response.world_path(i).y()) : ""});
  }
  return table;
}

int Plan(Env& env, Args args) {
  const Options& options = env.options();
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
  if (absl::Status s = SetCostOptions(options, plan_options); !s.ok()) {
    return env.Usage(s.message());
  }
  plan_options->set_max_expansions(options.max_expansions);
  if (options.heuristic_weight.has_value()) {
    plan_options->set_heuristic_weight(*options.heuristic_weight);
  }
  if (options.goal_tolerance_cells.has_value() &&
      options.goal_tolerance_m.has_value()) {
    return env.Usage(
        "give --goal_tolerance (cells) or --goal_tolerance_m, not both");
  }
  if (options.goal_tolerance_cells.has_value()) {
    plan_options->set_goal_tolerance_cells(*options.goal_tolerance_cells);
  }
  if (options.goal_tolerance_m.has_value()) {
    plan_options->set_goal_tolerance_m(*options.goal_tolerance_m);
  }
  if (absl::Status s = AddViaPoints(options, &request); !s.ok()) {
    return env.Usage(s.message());
  }
  request.set_allow_partial(options.allow_partial);
  plan_options->set_return_expansions(options.expansions);
  plan_options->set_simplify(options.simplify);
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
  if (options.json) {
    const int print_code = env.PrintJson(*response);
    return print_code == kExitOk ? code : print_code;
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
      "start:       %s\n"
      "goal:        %s",
      response->planner(), response->map_version(),
      FormatCell(response->start()), FormatCell(response->goal()));
  if (response->goal_substituted()) {
    out << " (substituted for blocked "
        << FormatCell(response->requested_goal()) << ")";
  }
  out << "\n";
  if (response->robot_radius_cells() > 0) {
    out << absl::StrFormat("robot radius: %g cells\n", response->robot_radius_cells());
  }
  // A partial plan (--allow_partial) has a path without found.
  const bool has_path = response->path_size() > 0;
  if (has_path) {
    out << absl::StrFormat("cost:        %.6f\nlength:      %.6f\n",
                           response->cost(), response->length());
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
  if (response->outcome() == v1::PLAN_OUTCOME_LOCAL_MINIMUM) {
    out << absl::StrFormat("stalled at:  (%.3f, %.3f)\n", response->stall_point().x(),
                           response->stall_point().y());
  }
  if (!response->trajectory().empty()) {
    out << "trajectory (" << response->trajectory().size() << " points)\n";
  }
  if (!response->cost_to_go().empty() && !options.cost_to_go_file.empty()) {
    out << "cost-to-go:  " << response->cost_to_go().size() << " cells written to "
        << options.cost_to_go_file << "\n";
  }
  out << absl::StrFormat("time:        %d us\n", response->planning_time_us());
  if (has_path) {
    out << "path (" << response->path_size()
        << (response->any_angle() ? " vertices, any-angle" : " cells")
        << "): " << FormatPath(response->path()) << "\n";
    if (options.world) {
      std::vector<std::string> points;
      for (const v1::WorldPoint& p : response->world_path()) {
        points.push_back(absl::StrFormat("(%g,%g)", p.x(), p.y()));
      }
      out << "world path (m): " << absl::StrJoin(points, " ") << "\n";
    }
  }
  return code;
}

// --- navigate ----------------------------------------------------------------

absl::StatusOr<std::string> ReadTextFile(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return absl::NotFoundError(absl::StrCat("cannot read ", path));
  std::stringstream text;
  text << file.rdbuf();
  if (file.bad()) return absl::DataLossError(absl::StrCat("error reading ", path));
  return text.str();
}

// --- batch -------------------------------------------------------------------

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
int Batch(Env& env, Args args) {
  const Options& options = env.options();
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
  if (absl::Status s = SetCostOptions(options, &shared); !s.ok()) {
    return env.Usage(s.message());
  }
  shared.set_max_expansions(options.max_expansions);
  if (options.heuristic_weight.has_value()) {
    shared.set_heuristic_weight(*options.heuristic_weight);
  }
  shared.set_simplify(options.simplify);
  shared.set_lookahead(options.lookahead);
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
  std::unique_ptr<grpc::ClientContext> context = client::MakeContext(options.timeout);
  // A load balancer routing by map sends the whole stream to the replica of
  // the first item's map (see UsageText).
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
                  ProgressBar::Unit::kCount, options.progress_bars);
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
    } else if (options.json) {
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
  (options.json || env.csv() ? env.err() : env.out()) << absl::StrFormat(
      "summary: %d of %d answered: %d found, %d no path, %d errors in %.3f s "
      "(%.1f plans/s)\n",
      answered, items->size(), found, no_path, errors, seconds,
      seconds > 0 ? answered / seconds : 0.0);
  if (!status.ok()) return env.Fail(client::FromGrpcStatus(status));
  return errors > 0 ? kExitError : kExitOk;
}

int Navigate(Env& env, Args args) {
  const Options& options = env.options();
  if (args.size() != 5) return env.Usage("navigate takes NAME SX SY GX GY");
  if (env.csv()) {
    return env.Unsupported("navigate",
                           "it prints a log of script steps and pushed paths; "
                           "use --output table, or json for one NavigateResponse "
                           "per line");
  }
  if (options.world) {
    return env.Usage("navigate takes cells (a script moves the robot cell by "
                     "cell); --world does not apply");
  }
  static constexpr const char* kNames[] = {"SX", "SY", "GX", "GY"};
  absl::StatusOr<std::vector<int32_t>> p = ParseInts(args.subspan(1), kNames);
  if (!p.ok()) return env.Usage(p.status().message());
  v1::NavigateOpen open;
  open.set_map(args[0]);
  open.mutable_start()->mutable_cell()->set_x((*p)[0]);
  open.mutable_start()->mutable_cell()->set_y((*p)[1]);
  open.mutable_goal()->mutable_cell()->set_x((*p)[2]);
  open.mutable_goal()->mutable_cell()->set_y((*p)[3]);
  if (absl::Status s = SetCostOptions(options, open.mutable_options()); !s.ok()) {
    return env.Usage(s.message());
  }
  std::vector<ScriptStep> script;
  if (!options.script.empty()) {
    absl::StatusOr<std::string> text = ReadTextFile(options.script);
    if (!text.ok()) return env.Fail(text.status());
    absl::StatusOr<std::vector<ScriptStep>> parsed =
        ParseNavigateScript(*text, options.script);
    if (!parsed.ok()) {
      // The message already says where; the command synopsis would not help.
      env.err() << "error: " << parsed.status().message() << "\n";
      return kExitUsage;
    }
    script = *std::move(parsed);
  }
  if (absl::Status s =
          RunNavigateSession(env.client(), open, script, options.json, env.out());
      !s.ok()) {
    return env.Fail(s);
  }
  return kExitOk;
}

// --- check -------------------------------------------------------------------

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

int Check(Env& env, Args args) {
  const Options& options = env.options();
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
  if (absl::Status s = SetCostOptions(options, request.mutable_options());
      !s.ok()) {
    return env.Usage(s.message());
  }

  absl::StatusOr<v1::IsPathValidResponse> response =
      env.client().IsPathValid(request);
  if (!response.ok()) return env.Fail(response.status());
  const int code = response->valid() ? kExitOk : kExitInvalidPath;
  if (options.json) {
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
  if (response->valid()) {
    out << absl::StrFormat("cost:          %.6f\nlength:        %.6f\n",
                           response->cost(), response->length());
    return code;
  }
  out << "invalid poses: " << FormatIndices(response->invalid_indices()) << "\n"
      << "invalid steps: " << FormatIndices(response->invalid_steps()) << "\n"
      << "reason:        " << response->reason() << "\n";
  return code;
}

// --- cost-to-go --------------------------------------------------------------

// Largest window printed as a table; bigger ones go to --cost_to_go_file.
constexpr int32_t kMaxTableColumns = 16;
constexpr int32_t kMaxTableRows = 64;

// "X,Y,W,H" as a CellWindow.
absl::StatusOr<v1::CellWindow> ParseWindow(absl::string_view text) {
  const std::vector<std::string> parts = absl::StrSplit(text, ',');
  static constexpr const char* kNames[] = {"--window X", "--window Y",
                                           "--window W", "--window H"};
  if (parts.size() != 4) {
    return absl::InvalidArgumentError(absl::StrCat(
        "--window takes X,Y,W,H (first column, first row, width, height), not '",
        text, "'"));
  }
  absl::StatusOr<std::vector<int32_t>> v = ParseInts(parts, kNames);
  if (!v.ok()) return v.status();
  if ((*v)[2] <= 0 || (*v)[3] <= 0) {
    return absl::InvalidArgumentError(absl::StrCat(
        "--window width and height must be positive, not ", (*v)[2], "x", (*v)[3]));
  }
  v1::CellWindow window;
  window.set_x((*v)[0]);
  window.set_y((*v)[1]);
  window.set_width((*v)[2]);
  window.set_height((*v)[3]);
  return window;
}

// The field as rows of numbers with column and row labels, "inf" where the
// goal cannot be reached.
std::string FormatCostTable(const v1::CostToGoResponse& response) {
  const v1::CellWindow& w = response.window();
  std::string text = "  y\\x";
  for (int32_t x = 0; x < w.width(); ++x) {
    absl::StrAppendFormat(&text, " %7d", w.x() + x);
  }
  text.push_back('\n');
  for (int32_t y = 0; y < w.height(); ++y) {
    absl::StrAppendFormat(&text, "%5d", w.y() + y);
    for (int32_t x = 0; x < w.width(); ++x) {
      const float v = response.cost(y * w.width() + x);
      absl::StrAppend(&text, std::isfinite(v) ? absl::StrFormat(" %7.2f", v)
                                              : std::string("     inf"));
    }
    text.push_back('\n');
  }
  return text;
}

int CostToGo(Env& env, Args args) {
  const Options& options = env.options();
  if (args.size() != 3) return env.Usage("cost-to-go takes NAME GX GY");
  v1::CostToGoRequest request;
  request.set_map(args[0]);
  static constexpr const char* kNames[] = {"GX", "GY"};
  if (options.world) {
    absl::StatusOr<std::vector<double>> g = ParseDoubles(args.subspan(1), kNames);
    if (!g.ok()) return env.Usage(g.status().message());
    request.mutable_goal()->mutable_world()->set_x((*g)[0]);
    request.mutable_goal()->mutable_world()->set_y((*g)[1]);
  } else {
    absl::StatusOr<std::vector<int32_t>> g = ParseInts(args.subspan(1), kNames);
    if (!g.ok()) {
      return env.Usage(absl::StrCat(g.status().message(),
                                    " (use --world for coordinates in metres)"));
    }
    request.mutable_goal()->mutable_cell()->set_x((*g)[0]);
    request.mutable_goal()->mutable_cell()->set_y((*g)[1]);
  }
  if (absl::Status s = SetCostOptions(options, request.mutable_options());
      !s.ok()) {
    return env.Usage(s.message());
  }
  if (!options.window.empty()) {
    absl::StatusOr<v1::CellWindow> window = ParseWindow(options.window);
    if (!window.ok()) return env.Usage(window.status().message());
    *request.mutable_window() = *window;
  }
  absl::StatusOr<v1::CostToGoResponse> response = env.client().CostToGo(request);
  if (!response.ok()) return env.Fail(response.status());
  const v1::CellWindow& w = response->window();
  if (int64_t{w.width()} * w.height() != response->cost_size()) {
    return env.Fail(absl::InternalError(absl::StrFormat(
        "server sent %d costs for a %dx%d window", response->cost_size(),
        w.width(), w.height())));
  }
  if (!options.cost_to_go_file.empty()) {
    if (absl::Status s =
            WriteCostToGoCsv(options.cost_to_go_file, w.width(), response->cost());
        !s.ok()) {
      return env.Fail(s);
    }
  }
  if (options.json) return env.PrintJson(*response);
  if (env.csv()) {
    // Long form, one row per cell: what plotting and data-frame tools read.
    Table table({"x", "y", "cost"});
    for (int32_t y = 0; y < w.height(); ++y) {
      for (int32_t x = 0; x < w.width(); ++x) {
        table.AddRow({absl::StrCat(w.x() + x), absl::StrCat(w.y() + y),
                      FormatNumber(response->cost(y * w.width() + x))});
      }
    }
    return env.PrintCsv(table);
  }
  const int64_t reachable =
      std::count_if(response->cost().begin(), response->cost().end(),
                    [](float v) { return std::isfinite(v); });
  std::ostream& out = env.out();
  out << absl::StrFormat(
      "map version: %d\n"
      "goal:        %s\n"
      "window:      x %d..%d, y %d..%d (%dx%d cells)\n"
      "reachable:   %d of %d cells\n"
      "cache hit:   %s\n"
      "expansions:  %d\n",
      response->map_version(), FormatCell(response->goal()), w.x(),
      w.x() + w.width() - 1, w.y(), w.y() + w.height() - 1, w.width(),
      w.height(), reachable, response->cost_size(),
      response->cache_hit() ? "yes" : "no", response->expansions());
  if (!options.cost_to_go_file.empty()) {
    out << "cost-to-go:  " << response->cost_size() << " cells written to "
        << options.cost_to_go_file << "\n";
  } else if (w.width() <= kMaxTableColumns && w.height() <= kMaxTableRows) {
    out << "\n" << FormatCostTable(*response);
  } else {
    out << absl::StrFormat(
        "(tables go up to %dx%d cells: give --cost_to_go_file F for the CSV, "
        "or a smaller --window)\n",
        kMaxTableColumns, kMaxTableRows);
  }
  return kExitOk;
}

// --- cache-stats -------------------------------------------------------------

int CacheStats(Env& env, Args args) {
  if (!args.empty()) return env.Usage("cache-stats takes no arguments");
  absl::StatusOr<v1::GetCacheStatsResponse> response =
      env.client().GetCacheStats();
  if (!response.ok()) return env.Fail(response.status());
  if (env.options().json) return env.PrintJson(*response);
  const bool csv = env.csv();
  Table table(csv ? std::vector<std::string>{"cache", "entries", "bytes",
                                             "budget_bytes", "hits", "misses",
                                             "evictions", "repairs", "rebuilds"}
                  : std::vector<std::string>{"CACHE", "ENTRIES", "BYTES", "BUDGET",
                                             "HITS", "MISSES", "EVICTIONS",
                                             "REPAIRS", "REBUILDS"});
  for (const v1::CacheStats& c : response->caches()) {
    table.AddRow({c.name(), absl::StrCat(c.entries()), absl::StrCat(c.bytes()),
                  absl::StrCat(c.budget_bytes()), absl::StrCat(c.hits()),
                  absl::StrCat(c.misses()), absl::StrCat(c.evictions()),
                  absl::StrCat(c.repairs()), absl::StrCat(c.rebuilds())});
  }
  if (csv) {
    // Navigate sessions' D* Lite state is memory like a cache's: one more
    // row, so the CSV carries everything the table shows.
    table.AddRow({"navigate_sessions", absl::StrCat(response->sessions()),
                  absl::StrCat(response->session_bytes())});
    return env.PrintCsv(table);
  }
  env.out() << table.Aligned();
  env.out() << absl::StrFormat("sessions:    %d open, %d bytes of D* Lite state\n",
                               response->sessions(), response->session_bytes());
  return kExitOk;
}

// --- health ------------------------------------------------------------------

int Health(Env& env, Args args) {
  if (args.size() > 1) return env.Usage("health takes at most one SERVICE");
  const std::string service = args.empty() ? "" : args[0];
  absl::StatusOr<grpc::health::v1::HealthCheckResponse> response =
      env.client().CheckHealth(service);
  if (!response.ok()) return env.Fail(response.status());
  using grpc::health::v1::HealthCheckResponse;
  if (env.options().json) {
    if (const int code = env.PrintJson(*response); code != kExitOk) return code;
  } else if (env.csv()) {
    Table table({"service", "status"});
    table.AddRow({service, HealthCheckResponse::ServingStatus_Name(response->status())});
    env.PrintCsv(table);
  } else {
    env.out() << HealthCheckResponse::ServingStatus_Name(response->status())
              << "\n";
  }
  // Probes (scripts, container health checks) read the exit code.
  return response->status() == HealthCheckResponse::SERVING ? kExitOk
                                                            : kExitError;
}

// --- metrics -----------------------------------------------------------------

// Appends what libcurl receives to a std::string.
size_t AppendToString(char* data, size_t size, size_t count, void* out) {
  static_cast<std::string*>(out)->append(data, size * count);
  return size * count;
}

// GET http://`address`/metrics; UNAVAILABLE when it cannot be fetched or the
// answer is not 200.
absl::StatusOr<std::string> FetchMetrics(const std::string& address,
                                         absl::Duration timeout) {
  const std::string url = absl::StrCat("http://", address, "/metrics");
  std::unique_ptr<CURL, decltype(&curl_easy_cleanup)> curl(curl_easy_init(),
                                                           &curl_easy_cleanup);
  if (curl == nullptr) return absl::InternalError("cannot initialise libcurl");
  std::string body;
  char curl_error[CURL_ERROR_SIZE] = {};
  curl_easy_setopt(curl.get(), CURLOPT_URL, url.c_str());
  curl_easy_setopt(curl.get(), CURLOPT_WRITEFUNCTION, &AppendToString);
  curl_easy_setopt(curl.get(), CURLOPT_WRITEDATA, &body);
  curl_easy_setopt(curl.get(), CURLOPT_ERRORBUFFER, curl_error);
  curl_easy_setopt(curl.get(), CURLOPT_TIMEOUT_MS,
                   static_cast<long>(absl::ToInt64Milliseconds(timeout)));
  // The endpoint may gzip the text when asked; "" accepts what libcurl can
  // decode.
  curl_easy_setopt(curl.get(), CURLOPT_ACCEPT_ENCODING, "");
  curl_easy_setopt(curl.get(), CURLOPT_NOSIGNAL, 1L);
  if (const CURLcode code = curl_easy_perform(curl.get()); code != CURLE_OK) {
    return absl::UnavailableError(absl::StrCat(
        "cannot fetch ", url, ": ",
        curl_error[0] != '\0' ? curl_error : curl_easy_strerror(code),
        " (is pathd running with --metrics_address=", address, "?)"));
  }
  long http_status = 0;
  curl_easy_getinfo(curl.get(), CURLINFO_RESPONSE_CODE, &http_status);
  if (http_status != 200) {
    return absl::UnavailableError(
        absl::StrCat("GET ", url, " answered HTTP ", http_status));
  }
  return body;
}

int Metrics(Env& env, Args args) {
  if (env.options().output != OutputFormat::kTable) {
    return env.Unsupported("metrics",
                           "it prints pathd's Prometheus text exposition, "
                           "which Prometheus tools read; use --output table");
  }
  absl::StatusOr<std::string> text =
      FetchMetrics(env.options().metrics_address, env.options().timeout);
  if (!text.ok()) return env.Fail(text.status());
  env.out() << FilterMetricsText(*text, std::vector<std::string>(args.begin(), args.end()));
  return kExitOk;
}

// --- bench -------------------------------------------------------------------

// Distinct random queries when a map has no scenario file; the load cycles
// through them.
constexpr int kRandomQueries = 1000;

// Where the benchmark's queries come from, for the report.
struct BenchQueries {
  std::vector<v1::PlanRequest> requests;
  std::string source;
};

// `count` start/goal pairs drawn uniformly (fixed seed) from the cells a
// robot centre may occupy on `map`; pairs in different components make
// NO_PATH answers, which the report counts.
absl::StatusOr<std::vector<std::pair<v1::Cell, v1::Cell>>> RandomEndpoints(
    const v1::GetMapResponse& map, bool unknown_is_free, uint64_t seed, int count) {
  std::vector<int64_t> free_cells;
  const std::string& cells = map.cells();
  for (size_t i = 0; i < cells.size(); ++i) {
    const auto cost = static_cast<uint8_t>(cells[i]);
    if (cost < 253 || (cost == 255 && unknown_is_free)) {
      free_cells.push_back(static_cast<int64_t>(i));
    }
  }
  if (free_cells.empty()) {
    return absl::FailedPreconditionError(
        absl::StrCat("map ", map.info().name(), " has no free cell to plan between"));
  }
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<size_t> pick(0, free_cells.size() - 1);
  const int64_t width = map.info().width();
  auto cell = [&] {
    const int64_t i = free_cells[pick(rng)];
    v1::Cell c;
    c.set_x(static_cast<int32_t>(i % width));
    c.set_y(static_cast<int32_t>(i / width));
    return c;
  };
  std::vector<std::pair<v1::Cell, v1::Cell>> pairs;
  for (int q = 0; q < count; ++q) {
    v1::Cell start = cell();
    pairs.emplace_back(std::move(start), cell());
  }
  return pairs;
}

v1::Cell ToProtoCell(const Cell& cell) {
  v1::Cell c;
  c.set_x(cell.x);
  c.set_y(cell.y);
  return c;
}

// Loads --movingai into the server as `name` (replacing it) and returns its
// scenario file's pairs, or, when the map has none, random ones.
absl::StatusOr<std::vector<std::pair<v1::Cell, v1::Cell>>> MovingAiEndpoints(
    Env& env, const std::string& name, std::string* source) {
  const Options& options = env.options();
  v1::CreateMapRequest create;
  create.set_name(name);
  create.set_replace(true);
  PATHD_RETURN_IF_ERROR(client::SetMapSourceFromFile(options.movingai, &create));
  PATHD_RETURN_IF_ERROR(env.client().CreateMap(create).status());
  const std::string scen = options.movingai + ".scen";
  absl::StatusOr<std::string> text = ReadTextFile(scen);
  if (!text.ok()) {
    v1::GetMapRequest get;
    get.set_name(name);
    get.set_include_cells(true);
    PATHD_ASSIGN_OR_RETURN(v1::GetMapResponse map, env.client().GetMap(get));
    *source = absl::StrCat(kRandomQueries, " random pairs of free cells (no ", scen, ")");
    return RandomEndpoints(map, options.unknown_is_free, options.seed, kRandomQueries);
  }
  PATHD_ASSIGN_OR_RETURN(std::vector<Scenario> scenarios,
                         ParseMovingAiScenarios(*text, scen));
  if (scenarios.empty()) {
    return absl::InvalidArgumentError(absl::StrCat(scen, " has no scenarios"));
  }
  std::vector<std::pair<v1::Cell, v1::Cell>> pairs;
  for (const Scenario& s : scenarios) {
    pairs.emplace_back(ToProtoCell(s.start), ToProtoCell(s.goal));
  }
  *source = absl::StrCat(scenarios.size(), " scenarios of ", scen);
  return pairs;
}

// The request every benchmark query shares: map, planner and cost options.
// INVALID_ARGUMENT (a usage error) for a bad planner or option.
absl::StatusOr<v1::PlanRequest> BenchBaseRequest(const Options& options,
                                                 const std::string& name) {
  v1::PlanRequest base;
  base.set_map(name);
  if (!options.planner.empty()) {
    PATHD_ASSIGN_OR_RETURN(v1::Planner planner, PlannerFromName(options.planner));
    base.set_planner(planner);
  }
  PATHD_RETURN_IF_ERROR(SetCostOptions(options, base.mutable_options()));
  base.mutable_options()->set_max_expansions(options.max_expansions);
  if (options.heuristic_weight.has_value()) {
    base.mutable_options()->set_heuristic_weight(*options.heuristic_weight);
  }
  return base;
}

// The plan requests of a benchmark: `base` between each pair, shuffled with
// --seed so a time-bounded run samples the whole list (scenario files are
// sorted by length).
absl::StatusOr<BenchQueries> MakeBenchQueries(Env& env, const v1::PlanRequest& base) {
  const Options& options = env.options();
  const std::string& name = base.map();
  BenchQueries queries;
  std::vector<std::pair<v1::Cell, v1::Cell>> pairs;
  if (!options.movingai.empty()) {
    PATHD_ASSIGN_OR_RETURN(pairs, MovingAiEndpoints(env, name, &queries.source));
  } else {
    v1::GetMapRequest get;
    get.set_name(name);
    get.set_include_cells(true);
    PATHD_ASSIGN_OR_RETURN(v1::GetMapResponse map, env.client().GetMap(get));
    PATHD_ASSIGN_OR_RETURN(pairs, RandomEndpoints(map, options.unknown_is_free,
                                                  options.seed, kRandomQueries));
    queries.source = absl::StrCat(kRandomQueries, " random pairs of free cells");
  }
  std::mt19937_64 rng(options.seed);
  std::shuffle(pairs.begin(), pairs.end(), rng);
  for (auto& [start, goal] : pairs) {
    v1::PlanRequest& request = queries.requests.emplace_back(base);
    *request.mutable_start()->mutable_cell() = std::move(start);
    *request.mutable_goal()->mutable_cell() = std::move(goal);
  }
  return queries;
}

// The progress bar of a benchmark, fed by RunPlanLoad about once a second:
// elapsed of --warmup, then elapsed of --duration (requests of --requests
// when the run is bounded by a count only), with the requests, the current
// rate and the errors as its detail.
class BenchProgress {
 public:
  explicit BenchProgress(Env& env) : env_(env) {}

  void Update(const client::LoadProgress& p) {
    const Options& options = env_.options();
    const bool by_count = !p.warming_up && options.duration == absl::ZeroDuration();
    if (bar_ == nullptr || p.warming_up != warming_up_) {
      if (bar_ != nullptr) bar_->Finish();
      warming_up_ = p.warming_up;
      last_requests_ = 0;
      last_elapsed_ = absl::ZeroDuration();
      const double total =
          p.warming_up ? absl::ToDoubleSeconds(options.warmup)
          : by_count   ? static_cast<double>(options.requests)
                       : absl::ToDoubleSeconds(options.duration);
      // The phase began p.elapsed ago, so the bar shows at once and its own
      // rate (for --requests) counts from the phase's start.
      bar_ = std::make_unique<ProgressBar>(
          env_.err(), p.warming_up ? "warm-up" : "bench  ", total,
          by_count ? ProgressBar::Unit::kCount : ProgressBar::Unit::kSeconds,
          true, &absl::Now, absl::Now() - p.elapsed);
    }
    const double seconds = absl::ToDoubleSeconds(p.elapsed - last_elapsed_);
    const double rate =
        seconds > 0 ? static_cast<double>(p.requests - last_requests_) / seconds : 0;
    last_requests_ = p.requests;
    last_elapsed_ = p.elapsed;
    bar_->Update(by_count ? static_cast<double>(p.requests)
                          : absl::ToDoubleSeconds(p.elapsed),
                 absl::StrFormat("%d requests  %.0f req/s now  %d errors",
                                 p.requests, rate, p.errors));
  }

  // Ends the bar's line so the report starts on a fresh one; a completed
  // run's bar shows its final figures rather than the last second's.
  void Close(const absl::StatusOr<client::LoadReport>& report) {
    if (bar_ == nullptr) return;
    if (report.ok() && !warming_up_) {
      const bool by_count = env_.options().duration == absl::ZeroDuration();
      bar_->Update(by_count ? static_cast<double>(report->requests)
                            : absl::ToDoubleSeconds(report->elapsed),
                   absl::StrFormat("%d requests  %.0f req/s  %d errors",
                                   report->requests, report->requests_per_second,
                                   report->errors()));
    }
    bar_->Finish();
  }

 private:
  Env& env_;
  std::unique_ptr<ProgressBar> bar_;
  bool warming_up_ = false;
  int64_t last_requests_ = 0;
  absl::Duration last_elapsed_;
};

double Micros(absl::Duration d) { return absl::ToDoubleMicroseconds(d); }

int PrintBenchJson(Env& env, const std::string& name, const std::string& source,
                   const client::LoadReport& report) {
  const Options& options = env.options();
  google::protobuf::Struct json;
  auto& fields = *json.mutable_fields();
  fields["map"].set_string_value(name);
  fields["planner"].set_string_value(options.planner.empty() ? "default"
                                                             : options.planner);
  fields["queries"].set_string_value(source);
  fields["concurrency"].set_number_value(options.concurrency);
  fields["channels"].set_number_value(options.channels);
  fields["elapsed_s"].set_number_value(absl::ToDoubleSeconds(report.elapsed));
  fields["requests"].set_number_value(static_cast<double>(report.requests));
  fields["ok"].set_number_value(static_cast<double>(report.ok));
  fields["no_path"].set_number_value(static_cast<double>(report.no_path));
  fields["errors"].set_number_value(static_cast<double>(report.errors()));
  auto& by_code = *fields["errors_by_code"].mutable_struct_value()->mutable_fields();
  for (size_t c = 0; c < report.errors_by_code.size(); ++c) {
    if (report.errors_by_code[c] == 0) continue;
    by_code[absl::StatusCodeToString(static_cast<absl::StatusCode>(c))]
        .set_number_value(static_cast<double>(report.errors_by_code[c]));
  }
  fields["requests_per_second"].set_number_value(report.requests_per_second);
  auto& latency = *fields["latency_us"].mutable_struct_value()->mutable_fields();
  latency["min"].set_number_value(Micros(report.latency.min));
  latency["mean"].set_number_value(Micros(report.latency.mean));
  latency["p50"].set_number_value(Micros(report.latency.p50));
  latency["p95"].set_number_value(Micros(report.latency.p95));
  latency["p99"].set_number_value(Micros(report.latency.p99));
  latency["max"].set_number_value(Micros(report.latency.max));
  return env.PrintJson(json);
}

// "CODE N" for every status code the load saw errors of.
std::vector<std::string> ErrorsByCode(const client::LoadReport& report) {
  std::vector<std::string> errors;
  for (size_t c = 0; c < report.errors_by_code.size(); ++c) {
    if (report.errors_by_code[c] == 0) continue;
    errors.push_back(absl::StrCat(
        absl::StatusCodeToString(static_cast<absl::StatusCode>(c)), " ",
        report.errors_by_code[c]));
  }
  return errors;
}

// One row of figures, the same as --json's (latencies in microseconds, of
// the OK answers); errors by code as "CODE N" pairs separated by spaces.
int PrintBenchCsv(Env& env, const std::string& name, const std::string& source,
                  const client::LoadReport& report) {
  const Options& options = env.options();
  const std::vector<std::string> errors = ErrorsByCode(report);
  const client::LatencySummary& l = report.latency;
  Table table({"map", "planner", "queries", "concurrency", "channels", "elapsed_s",
               "requests", "ok", "no_path", "errors", "errors_by_code",
               "requests_per_second", "latency_min_us", "latency_mean_us",
               "latency_p50_us", "latency_p95_us", "latency_p99_us",
               "latency_max_us"});
  table.AddRow({name, options.planner.empty() ? "default" : options.planner, source,
                absl::StrCat(options.concurrency), absl::StrCat(options.channels),
                FormatNumber(absl::ToDoubleSeconds(report.elapsed)),
                absl::StrCat(report.requests), absl::StrCat(report.ok),
                absl::StrCat(report.no_path), absl::StrCat(report.errors()),
                absl::StrJoin(errors, " "), FormatNumber(report.requests_per_second),
                FormatNumber(Micros(l.min)), FormatNumber(Micros(l.mean)),
                FormatNumber(Micros(l.p50)), FormatNumber(Micros(l.p95)),
                FormatNumber(Micros(l.p99)), FormatNumber(Micros(l.max))});
  return env.PrintCsv(table);
}

void PrintBenchText(Env& env, const std::string& name, const std::string& source,
                    const client::LoadReport& report) {
  const Options& options = env.options();
  const std::vector<std::string> errors = ErrorsByCode(report);
  const client::LatencySummary& l = report.latency;
  env.out() << absl::StrFormat(
      "map:         %s\n"
      "planner:     %s\n"
      "queries:     %s\n"
      "load:        %d concurrent requests over %d channel(s), %.2f s measured\n"
      "requests:    %d (%d ok, %d of them without a path; %d errors)\n"
      "throughput:  %.1f requests/s\n"
      "latency us:  p50 %.0f  p95 %.0f  p99 %.0f  max %.0f  (min %.0f, mean %.0f; "
      "ok answers)\n"
      "errors:      %s\n",
      name, options.planner.empty() ? "the server's default" : options.planner,
      source, options.concurrency, options.channels,
      absl::ToDoubleSeconds(report.elapsed), report.requests, report.ok,
      report.no_path, report.errors(), report.requests_per_second, Micros(l.p50),
      Micros(l.p95), Micros(l.p99), Micros(l.max), Micros(l.min), Micros(l.mean),
      errors.empty() ? "none" : absl::StrJoin(errors, ", "));
}

int Bench(Env& env, Args args) {
  const Options& options = env.options();
  std::string name;
  if (!options.movingai.empty()) {
    if (args.size() > 1) return env.Usage("bench --movingai FILE takes at most one NAME");
    if (client::DetectMapFileKind(options.movingai) != client::MapFileKind::kMovingAi) {
      return env.Usage(absl::StrCat("--movingai ", options.movingai,
                                    ": expected a Moving AI .map file"));
    }
    name = args.empty() ? std::filesystem::path(options.movingai).stem().string()
                        : args[0];
  } else {
    if (args.size() != 1) return env.Usage("bench takes NAME (or --movingai FILE)");
    name = args[0];
  }
  if (options.concurrency < 1) return env.Usage("--concurrency must be at least 1");
  if (options.channels < 1) return env.Usage("--channels must be at least 1");
  if (options.requests < 0) return env.Usage("--requests must not be negative");
  if (options.duration < absl::ZeroDuration() || options.warmup < absl::ZeroDuration()) {
    return env.Usage("--duration and --warmup must not be negative");
  }
  if (options.duration == absl::ZeroDuration() && options.requests == 0) {
    return env.Usage("--duration 0 needs --requests N, or the load never ends");
  }
  absl::StatusOr<v1::PlanRequest> base = BenchBaseRequest(options, name);
  if (!base.ok()) return env.Usage(base.status().message());
  absl::StatusOr<BenchQueries> queries = MakeBenchQueries(env, *base);
  if (!queries.ok()) return env.Fail(queries.status());

  client::LoadOptions load;
  load.concurrency = options.concurrency;
  load.duration = options.duration;
  load.max_requests = options.requests;
  load.warmup = options.warmup;
  BenchProgress bar(env);
  std::function<void(const client::LoadProgress&)> progress;
  if (options.progress_bars) {
    progress = [&bar](const client::LoadProgress& p) { bar.Update(p); };
  }
  absl::StatusOr<client::LoadReport> report =
      client::RunPlanLoad(options.server, env.credentials(), options.channels,
                          options.timeout, queries->requests, load, progress);
  bar.Close(report);
  if (!report.ok()) return env.Fail(report.status());
  if (options.json) return PrintBenchJson(env, name, queries->source, *report);
  if (env.csv()) return PrintBenchCsv(env, name, queries->source, *report);
  PrintBenchText(env, name, queries->source, *report);
  return kExitOk;
}

// --- completion --------------------------------------------------------------

int Completion(Env& env, Args args) {
  if (args.size() != 1 || args[0] != "bash") {
    return env.Usage("completion takes the shell: bash");
  }
  if (env.options().output != OutputFormat::kTable) {
    return env.Unsupported("completion", "it prints a bash script");
  }
  env.out() << BashCompletionScript(PathctlCompletionSpec());
  return kExitOk;
}

// --- render ------------------------------------------------------------------

// The Plan request of `render NAME SX SY GX GY`: the plan command's options
// that change the path (planner, cost options, limits, via points), and
// always the expanded cells when --expansions asks to draw them.
absl::StatusOr<v1::PlanRequest> RenderPlanRequest(const Options& options,
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
  PATHD_RETURN_IF_ERROR(SetCostOptions(options, plan_options));
  plan_options->set_max_expansions(options.max_expansions);
  if (options.heuristic_weight.has_value()) {
    plan_options->set_heuristic_weight(*options.heuristic_weight);
  }
  plan_options->set_simplify(options.simplify);
  plan_options->set_lookahead(options.lookahead);
  plan_options->set_return_expansions(options.expansions);
  PATHD_RETURN_IF_ERROR(AddViaPoints(options, &request));
  request.set_allow_partial(options.allow_partial);
  return request;
}

Cell CoreCell(const v1::Cell& cell) { return Cell{cell.x(), cell.y()}; }

// `render NAME [--plan SX SY GX GY] (-o FILE.png | --ascii)`: GetMap, an
// optional Plan, then the picture.
int Render(Env& env, Args args) {
  const Options& options = env.options();
  if (options.output != OutputFormat::kTable) {
    return env.Unsupported(
        "render", "it draws a picture; 'plan --output json' prints the path");
  }
  if (args.size() != 1 && args.size() != 5) {
    return env.Usage("render takes NAME, or NAME --plan SX SY GX GY");
  }
  const bool plan = args.size() == 5;
  if (options.plan && !plan)
    return env.Usage("--plan needs SX SY GX GY after NAME");
  if (options.expansions && !plan) {
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
        RenderPlanRequest(options, args[0], args.subspan(1));
    if (!built.ok()) return env.Usage(built.status().message());
    request = *std::move(built);
  }

  absl::StatusOr<Grid> grid = FetchGrid(env, args[0]);
  if (!grid.ok()) return env.Fail(grid.status());
  PlanOverlay overlay;
  int code = kExitOk;
  std::string summary;
  if (request.has_value()) {
    absl::StatusOr<v1::PlanResponse> response = env.client().Plan(*request);
    if (!response.ok()) return env.Fail(response.status());
    for (const v1::Cell& c : response->path())
      overlay.path.push_back(CoreCell(c));
    for (const v1::Cell& c : response->expanded())
      overlay.expanded.push_back(CoreCell(c));
    overlay.start = CoreCell(response->start());
    overlay.goal = CoreCell(response->goal());
    code = response->found() ? kExitOk : kExitNoPath;
    summary =
        response->path_size() > 0
            ? absl::StrFormat(
                  "path (%s): %d %s, cost %.6f, length %.6f, %d expansions",
                  response->planner(), response->path_size(),
                  response->any_angle() ? "vertices" : "cells",
                  response->cost(), response->length(), response->expansions())
            : absl::StrFormat("no path (%s): %s: %s", response->planner(),
                              OutcomeName(response->outcome()),
                              response->reason());
    if (options.expansions) {
      absl::StrAppendFormat(
          &summary, ", %d expanded cells drawn%s", response->expanded_size(),
          response->expanded_truncated()
              ? " (truncated: the server's --max_returned_expansions)"
              : "");
    }
  }
  RenderOptions render_options;
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
    env.out() << absl::StrFormat("wrote %s (%dx%d pixels, %d per cell)\n",
                                 options.out, image->width, image->height,
                                 image->width / grid->width());
  }
  if (!summary.empty()) env.out() << summary << "\n";
  return code;
}

}  // namespace

int ExitCodeForStatus(absl::StatusCode code) {
  switch (code) {
    case absl::StatusCode::kOk:
      return kExitOk;
    case absl::StatusCode::kUnavailable:
      return kExitUnavailable;
    case absl::StatusCode::kDeadlineExceeded:
      return kExitDeadline;
    case absl::StatusCode::kNotFound:
      return kExitNotFound;
    case absl::StatusCode::kUnauthenticated:
    case absl::StatusCode::kPermissionDenied:
      return kExitDenied;
    default:
      return kExitError;
  }
}

CompletionSpec PathctlCompletionSpec() {
  CompletionSpec spec;
  spec.commands = {"maps",   "plan",        "batch",  "navigate", "cost-to-go",
                   "check",  "cache-stats", "health", "metrics",  "bench",
                   "render", "completion", "help"};
  spec.subcommands["maps"] = {"create", "list",  "get",    "delete", "set",
                              "rect",   "watch", "import", "export"};
  spec.subcommands["completion"] = {"bash"};
  spec.map_name_after = {"maps get", "maps delete", "maps set", "maps rect",
                         "maps watch", "plan", "navigate", "cost-to-go",
                         "check", "bench", "render", "maps export"};
  spec.file_after = {"batch"};
  // pathctl's own flags, not the ones Abseil and gRPC register.
  for (const auto& [name, flag] : absl::GetAllFlags()) {
    if (flag->IsRetired() || !absl::EndsWith(flag->Filename(), "pathctl/main.cc")) {
      continue;
    }
    (flag->IsOfType<bool>() ? spec.bool_flags : spec.value_flags)
        .emplace_back(name);
  }
  std::sort(spec.value_flags.begin(), spec.value_flags.end());
  std::sort(spec.bool_flags.begin(), spec.bool_flags.end());
  for (const WirePlanner& p : WirePlanners()) {
    spec.flag_values["planner"].emplace_back(p.name);
  }
  spec.flag_values["output"] = {"table", "json", "csv"};
  spec.flag_values["connectivity"] = {"4", "8"};
  spec.flag_values["pf_attractive"] = {"quadratic", "conic"};
  spec.file_flags = {"from",     "path_file", "script", "cost_to_go_file",
                     "movingai", "out",       "o"};
  return spec;
}

std::string FilterMetricsText(absl::string_view text,
                              const std::vector<std::string>& prefixes) {
  if (prefixes.empty()) return std::string(text);
  std::string filtered;
  for (absl::string_view line : absl::StrSplit(text, '\n', absl::SkipEmpty())) {
    // "# HELP name ...", "# TYPE name ..." or "name{labels} value".
    absl::string_view name = line;
    if (absl::ConsumePrefix(&name, "# HELP ") || absl::ConsumePrefix(&name, "# TYPE ")) {
      name = name.substr(0, name.find(' '));
    } else {
      name = name.substr(0, name.find_first_of("{ "));
    }
    for (const std::string& prefix : prefixes) {
      if (absl::StartsWith(name, prefix)) {
        absl::StrAppend(&filtered, line, "\n");
        break;
      }
    }
  }
  return filtered;
}

absl::StatusOr<uint32_t> ParseCost(absl::string_view text) {
  static constexpr std::pair<absl::string_view, uint32_t> kNamed[] = {
      {"free", 0}, {"inscribed", 253}, {"lethal", 254}, {"unknown", 255}};
  for (const auto& [name, cost] : kNamed) {
    if (text == name) return cost;
  }
  uint32_t cost = 0;
  if (!absl::SimpleAtoi(text, &cost) || cost > 255) {
    return BadArg("COST", text, "0..255, free, inscribed, lethal or unknown");
  }
  return cost;
}

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
    if (ok && world) {
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
          "%s:%d: '%s' is not \"X Y\" (%s)", file_name, line_number, line,
          world ? "two finite numbers, metres" : "two integers, cells"));
    }
    poses.push_back(std::move(pose));
  }
  if (poses.empty()) {
    return absl::InvalidArgumentError(absl::StrCat(file_name, ": no poses"));
  }
  return poses;
}

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

std::string FormatPath(const google::protobuf::RepeatedPtrField<v1::Cell>& cells) {
  std::vector<std::string> parts;
  parts.reserve(cells.size());
  for (const v1::Cell& cell : cells) parts.push_back(FormatCell(cell));
  return absl::StrJoin(parts, " ");
}

namespace {

// Plan returns doubles, CostToGo the 4-byte floats the server stores.
template <typename T>
absl::Status WriteCsv(const std::string& path, int32_t width,
                      const google::protobuf::RepeatedField<T>& field) {
  if (width <= 0 || field.size() % width != 0) {
    return absl::DataLossError(absl::StrCat("cost-to-go field of ", field.size(),
                                            " values does not fill rows of ", width));
  }
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) {
    return absl::PermissionDeniedError(absl::StrCat("cannot write ", path));
  }
  std::string line;
  for (int i = 0; i < field.size(); ++i) {
    const double v = static_cast<double>(field.Get(i));
    if (i % width != 0) line.push_back(',');
    absl::StrAppend(&line, std::isfinite(v) ? absl::StrFormat("%.6f", v) : "inf");
    if (i % width == width - 1) {
      line.push_back('\n');
      file << line;
      line.clear();
    }
  }
  file << line;
  file.flush();
  if (!file) return absl::DataLossError(absl::StrCat("error writing ", path));
  return absl::OkStatus();
}

}  // namespace

absl::Status WriteCostToGoCsv(const std::string& path, int32_t width,
                              const google::protobuf::RepeatedField<double>& field) {
  return WriteCsv(path, width, field);
}

absl::Status WriteCostToGoCsv(const std::string& path, int32_t width,
                              const google::protobuf::RepeatedField<float>& field) {
  return WriteCsv(path, width, field);
}

namespace {

bool IsNumber(absl::string_view text) {
  double unused;
  return absl::SimpleAtod(text, &unused);
}

}  // namespace

absl::StatusOr<v1::Planner> PlannerFromName(absl::string_view name) {
  if (std::optional<v1::Planner> planner = WirePlannerFromName(std::string_view(name.data(), name.size()))) return *planner;
  return absl::InvalidArgumentError(
      absl::StrCat("--planner: unknown planner '", name,
                   "'; valid planners: ", PlannerNames()));
}

std::string SynopsisText() { return kSynopsis; }

std::string UsageText() {
  return absl::StrCat(
      "pathctl: command-line client of the pathd path-planning daemon.\n\n",
      kSynopsis, R"(
flags (anywhere on the line, as --flag=value or --flag value):
  --server ADDR        pathd address; default $PATHD_SERVER, else 127.0.0.1:50051
  --timeout D          deadline of the call, e.g. 500ms, 30s (default 10s)
  --json               print the response message as proto3 JSON (= --output json)
  --output F           table (default: the text below), json (proto3 JSON; a
                       stream prints one object per line) or csv (a header
                       row, then rows: see "output formats")
  --no_progress        no progress bars (batch, bench, maps create --from);
                       they show only when stdout and stderr are terminals
  --tls_ca FILE        use TLS, trusting the server certificate if this PEM
                       CA (or the self-signed certificate itself) signed it
  --tls_cert FILE, --tls_key FILE
                       client certificate and key (PEM) for a pathd with
                       --tls_client_ca (mutual TLS); need --tls_ca
  --tls_server_name N  the name the server's certificate carries, when it
                       differs from the --server host (e.g. dialing an IP)
  --token_file FILE    send the token in FILE as 'authorization: Bearer ...'
                       on every call (for a pathd with --auth_tokens)
  --token T            the token itself (visible in the process list: prefer
                       --token_file); default $PATHD_TOKEN. Without --tls_ca
                       the token crosses the network in clear text (pathctl
                       warns unless the server is on this machine)
  --from FILE          maps create: .map is sent as Moving AI text; .yaml/.yml
                       as a ROS map_server map (the YAML plus the image it
                       names, relative to the YAML's folder)
  --replace            maps create, import: replace an existing map of that name
  --resolution R       maps create, import: metres per cell for .map (and
                       import's .png) files (default 1)
  --cells              maps get: also print the cells (maps up to 1024 columns)
  --expected_version V maps set/rect: apply only if the map is at version V
  --from_version V     maps watch: the version you hold; other than the current
                       one (0: none) starts with the whole map (resync)
  --count N            maps watch: stop after N events (default: until deleted)
  --planner P          plan: )",
      PlannerNames(), R"( (default: the server's, A*)
  --max_expansions N   plan: stop after N expansions (0: the server's limit)
  --world              plan, cost-to-go, check: coordinates are world metres, not cells
  --simplify           plan: keep only the turning points (ray-shooting line of
                       sight); the path becomes any-angle, never longer
  --heuristic_weight W plan: weighted_astar's w >= 1 (default 1.5)
  --lookahead N        plan: rtaa_star / lrta_star expansions per episode (64)
  --cost_to_go_file F  plan (distance_transform*), cost-to-go: write the
                       cost-to-go field as CSV (one row per line, inf =
                       unreachable); cost-to-go prints a table otherwise
  --window X,Y,W,H     cost-to-go: only columns X..X+W-1, rows Y..Y+H-1
  --goal_tolerance C   plan: when the goal cell is blocked, plan to the nearest
                       free cell within C cells and say so (up to 1024 cells)
  --goal_tolerance_m M plan: the same in metres
  --via X,Y[;X,Y...]   plan: visit these points in order before the goal (up to
                       256; metres with --world); one leg per point
  --allow_partial      plan: with --via, when a leg finds no path print the path
                       to the last reached point (exit code 3 still)
  --expansions         plan: ask for the cells the search expanded; prints how
                       many came back (--json prints them, as "expanded")
  --path_file F        check: read the path from F, one "X Y" per line ('#'
                       starts a comment line)
  --script FILE        navigate: replay this robot run (format below); without
                       it navigate prints the first path and closes
  --metrics_address A  metrics: pathd's --metrics_address (default
                       127.0.0.1:9464)
  --progress           plan: use PlanStream and show the search's progress
                       on stderr (one line updated in place on a terminal,
                       one line per event otherwise)
  --pf_attractive S    plan: potential_field: quadratic (default) or conic
  --pf_attractive_gain K, --pf_switch_distance D, --pf_repulsive_gain ETA,
  --pf_influence Q, --pf_step S, --pf_max_steps N
                       plan: potential_field parameters (cells; 0 = default)

  --concurrency N      bench: requests in flight; each worker sends its next
                       request when the previous answer arrives (default 4)
  --duration T         bench: measured time, e.g. 30s (default 10s; 0: until
                       --requests are done)
  --warmup T           bench: unmeasured load first (default 1s)
  --requests N         bench: stop after N measured requests (0: no limit)
  --channels K         bench: gRPC connections the workers share (default 1)
  --movingai FILE      bench: load FILE (a Moving AI .map) as NAME (default:
                       the file's stem), replacing a map of that name, and
                       take the queries from FILE.scen
  --seed S             bench: seed of the random queries and of the shuffle

  --plan               render: plan from SX SY to GX GY (given after NAME) and
                       draw the path; takes plan's options (--planner, --world,
                       --via, --simplify, --max_expansions, cost options)
  -o FILE, --out FILE  render: write the picture to FILE (PNG)
  --ascii              render: print the picture as text (maps up to 200x200)
  --scale N            render: pixels per cell, 1..64 (default: 16 for small
                       maps, less so the longer side is about 1024 pixels)
  --y_up               render: draw row 0 at the bottom (world y up), as a ROS
                       map's image shows it; default row 0 on top, as in a
                       .map file and maps get --cells
  --occupied_thresh T, --free_thresh T, --negate
                       maps import of a .png: map_server's thresholds (default
                       0.65 and 0.196) and colour inversion; see below

cost options (plan, navigate, cost-to-go, check):
  --connectivity N     4 or 8 (default 8)
  --cost_weight W      w in step = length * (1 + w * cost / 252) (default 1)
  --unknown_is_free    treat unknown cells (255) as free
  --robot_radius M     inflate lethal cells by the robot radius in metres
  --robot_radius_cells C  the same in cells

maps watch prints one line per map version: "version V updated: N cells in
R rects: (x0,y0)-(x1,y1) ...", "version V resync: whole map WxH", "version V
replaced: whole map WxH" or "version V deleted" (then it exits 0). It has no
deadline (--timeout does not apply); with --json each line is a MapEvent.

metrics prints pathd's Prometheus text (GET http://HOST:PORT/metrics, the
daemon's --metrics_address); with PREFIX arguments only the metrics whose name
starts with one of them, e.g. 'pathctl metrics pathd_requests pathd_maps'.
batch FILE (or - for stdin) sends every request of FILE through one PlanBatch
stream: one request per line, "ID MAP SX SY GX GY [PLANNER]" (cells, or
metres with --world; '#' starts a comment line). --planner is the default
for lines without one; --max_expansions, --heuristic_weight, --simplify,
--lookahead and the cost options apply to every line. It prints one line per
answer as it arrives (in finishing order), "ID found cost C length L
expansions N time T us", "ID no-path OUTCOME: reason" or "ID error CODE
OUTCOME: message", then "summary: A of N answered: F found, P no path, E
errors in S s" with the rate in plans/s. With --json each answer is a
PlanBatchResponse line and the summary goes to stderr. --timeout bounds the
whole batch. Exit code 0 when no item errored (no path is not an error), 1
when any item errored or the stream failed.
Every call about a map sends its name in the x-pathd-map header, which a load
balancer in front of several pathd replicas routes by (README, Deployment).
Through such a balancer a batch goes to the replica of its first line's map:
give it one map per file (lines naming a map held elsewhere answer NOT_FOUND),
and maps list, cache-stats and health reach whichever replica the balancer
picks; give --server a replica's own address to ask that one.
bench runs a closed-loop load of Plan calls. Its queries are the
scenarios of --movingai's .scen file, or 1000 random pairs of free cells of
NAME, shuffled with --seed and sent in a cycle. It prints throughput, latency
percentiles of the OK answers (exact, from every recorded sample), and errors
by status code; --json prints one object. When stdout and stderr are
terminals a progress bar (elapsed of the duration, requests, current rate,
errors) is redrawn on stderr about once a second. The exit code is 0 when the run completed, whatever the
answers; scripts read the error counts.

With --json, navigate prints each NavigateResponse as one line of JSON. Its
--timeout bounds each wait for an answer and for the server's close, not the
whole session.

arguments:
  X, Y                 cells: x is the column, y the row, from 0
  COST                 0..255 (Nav2 costmap values) or free (0), inscribed (253),
                       lethal (254), unknown (255)
  X0 Y0 X1 Y1          two opposite corners of a rectangle, both included
  Numbers such as -3 are arguments, not flags; "--" ends the flags.

maps get --cells prints one character per cell, row 0 first (a .map file's
first line; a ROS map's bottom image row):
  .    free (0)
  1-9  weighted 1..252; digit d covers costs 28(d-1)+1 .. 28d
  #    inscribed or lethal (253, 254)
  ?    unknown (255)

output formats (--output csv): one header row, then
  maps create/get/list  one row per map: name,width,height,resolution,
                        origin_x,origin_y,origin_yaw,version,free_cells,
                        blocked_cells (maps get --cells has no CSV)
  maps delete           name,last_version
  maps set/rect         name,version,cells_changed
  maps watch            one row per event: version,kind,width,height,
                        changed_cells,changed_rects,rects
  plan                  one row per path cell: x,y,world_x,world_y
  batch                 one row per answer: id,status,outcome,cost,length,
                        expansions,time_us,code,message (summary on stderr)
  check                 valid,map_version,poses,cost,length,invalid_poses,
                        invalid_steps,reason
  cost-to-go            one row per cell: x,y,cost (inf: unreachable)
  cache-stats           one row per cache, then navigate_sessions
  health                service,status
  bench                 one row of the --json figures
navigate has no CSV; metrics (Prometheus text) and completion (a script)
print only as table. Asking for a format a command has not is a usage error
(exit 2) naming the command and the format.

progress bars: batch (answers of total, rate), bench (elapsed of --warmup,
then of --duration) and maps create --from (what is being sent, for how
long) draw a bar on stderr, redrawn in place at most 10 times a second and
only after half a second of work, when stdout and stderr are both terminals
and --no_progress is not given.

completion: 'source <(pathctl completion bash)' completes commands, flags,
planner names, --output formats, files and, when the server answers within a
second, map names (from 'pathctl maps list' with the line's --server).
render --ascii draws the same, then 'o' expanded cells, '*' the path, 'S'
the start and 'G' the goal. Its PNG draws free cells white, weighted cells
grey (lighter for cheaper), inscribed dark grey, lethal black, unknown
blue-grey, expanded cells tinted amber, the path as a red line, the start as
a green and the goal as a blue disc.

maps import reads .map (Moving AI) and .yaml/.yml (ROS map_server) like maps
create --from, and PNG occupancy images: a bare .png, or one a YAML names.
A PNG pixel's grey level is the mean of its R, G and B; map_server's rules
then apply: p = (255 - grey) / 255 (grey / 255 with --negate), p >
occupied_thresh lethal, p < free_thresh free, otherwise unknown. A bare
.png gets --resolution (default 1 m) and origin (0, 0); a YAML's values
come from the YAML. maps export writes FILE by its extension: .map as Moving
AI ('.' free, 'S' weighted, '@' inscribed or lethal, 'O' unknown), or
.yaml/.yml plus a .pgm of the same name (map_server trinary: 254 free or
weighted, 0 inscribed or lethal, 205 unknown). Weighted costs, inscribed and
(in a .map) unknown cells do not survive the round trip; export warns with
their counts on stderr.

exit codes:
  0  success
  1  the call failed (server error, or a local file could not be read);
     stderr says "error: <GRPC_CODE>: <message>"; health: not SERVING;
     navigate: a script's expect-push or follow failed
     (codes 5-8 below take precedence for their status codes)
  2  usage error, also a bad navigate script line (FILE:LINE: problem) and a
     format a command cannot print
  3  plan ran but found no path (the outcome says why)
     (batch: 1 when any item errored, otherwise 0)
  4  check ran and the path is not valid on the map's current version
  5  UNAVAILABLE: the server cannot be reached or is shutting down
  6  DEADLINE_EXCEEDED: the call ran past --timeout
  7  NOT_FOUND: the map (or a local file named on the line) does not exist
  8  UNAUTHENTICATED or PERMISSION_DENIED (also a local file not writable)
     (render --plan: 3 when the plan found no path; the map is still drawn)

)",
      kNavigateScriptHelp);
}

absl::StatusOr<CommandLine> SplitCommandLine(int argc,
                                             const char* const* argv) {
  CommandLine line;
  bool flags_ended = false;
  for (int i = 1; i < argc; ++i) {
    const absl::string_view arg = argv[i];
    if (flags_ended || arg.size() < 2 || arg[0] != '-' || IsNumber(arg)) {
      line.positional.emplace_back(arg);
      continue;
    }
    if (arg == "--") {
      flags_ended = true;
      continue;
    }
    absl::string_view body = arg.substr(arg[1] == '-' ? 2 : 1);
    std::optional<absl::string_view> value;
    if (size_t eq = body.find('='); eq != absl::string_view::npos) {
      value = body.substr(eq + 1);
      body = body.substr(0, eq);
    }
    // --tls-ca reads as --tls_ca: the issues and other tools spell flags
    // with hyphens, absl with underscores.
    const std::string name = absl::StrReplaceAll(body, {{"-", "_"}});
    if (name == "help" || name == "h") {
      line.help = true;
      continue;
    }
    absl::CommandLineFlag* flag = absl::FindCommandLineFlag(name);
    if (flag == nullptr && absl::StartsWith(name, "no") && !value.has_value()) {
      // --nofoo clears boolean flag foo.
      absl::CommandLineFlag* negated =
          absl::FindCommandLineFlag(name.substr(2));
      if (negated != nullptr && negated->IsOfType<bool>()) {
        line.flags.emplace_back(absl::StrCat("--", name));
        continue;
      }
    }
    if (flag == nullptr || flag->IsRetired()) {
      return absl::InvalidArgumentError(absl::StrCat("unknown flag --", name));
    }
    if (flag->IsOfType<bool>() && !value.has_value()) {
      line.flags.emplace_back(absl::StrCat("--", name));
      continue;
    }
    if (!value.has_value()) {
      if (i + 1 >= argc) {
        return absl::InvalidArgumentError(
            absl::StrCat("flag --", name, " needs a value"));
      }
      value = argv[++i];
    }
    // Parsing here sets the flag to the same value absl::ParseCommandLine will
    // set it to, so validating is harmless.
    std::string error;
    if (!flag->ParseFrom(*value, &error)) {
      return absl::InvalidArgumentError(
          absl::StrCat("flag --", name, "='", *value, "': ", error));
    }
    line.flags.emplace_back(absl::StrCat("--", name, "=", *value));
  }
  return line;
}

std::string ResolveServerAddress(const std::string& flag_value,
                                 const char* env_value) {
  if (!flag_value.empty()) return flag_value;
  if (env_value != nullptr && env_value[0] != '\0') return env_value;
  return client::kDefaultServerAddress;
}

char CellGlyph(uint8_t cost) {
  if (cost == 0) return '.';
  if (cost <= 252) return static_cast<char>('1' + (cost - 1) / 28);
  if (cost == 255) return '?';
  return '#';
}

std::string RenderCells(int32_t width, int32_t height,
                        absl::string_view cells) {
  std::string text;
  text.reserve(static_cast<size_t>(width + 1) * static_cast<size_t>(height));
  for (int32_t y = 0; y < height; ++y) {
    for (int32_t x = 0; x < width; ++x) {
      text.push_back(CellGlyph(static_cast<uint8_t>(
          cells[static_cast<size_t>(y) * static_cast<size_t>(width) +
                static_cast<size_t>(x)])));
    }
    text.push_back('\n');
  }
  return text;
}

int Run(const Options& options, const std::vector<std::string>& args,
        std::ostream& out, std::ostream& err) {
  Env env(options, out, err);
  if (args.empty()) return env.Usage("missing command");
  const std::string& command = args[0];
  Args rest = Args(args).subspan(1);
  // metrics is plain HTTP to the metrics port: no TLS, no token.
  if (command != "help" && command != "metrics") {
    if (std::optional<int> failed = env.LoadCredentials()) return *failed;
  }
  if (command == "maps") return Maps(env, rest);
  if (command == "plan") return Plan(env, rest);
  if (command == "navigate") return Navigate(env, rest);
  if (command == "cost-to-go") return CostToGo(env, rest);
  if (command == "check") return Check(env, rest);
  if (command == "cache-stats") return CacheStats(env, rest);
  if (command == "health") return Health(env, rest);
  if (command == "metrics") return Metrics(env, rest);
  if (command == "batch") return Batch(env, rest);
  if (command == "bench") return Bench(env, rest);
  if (command == "completion") return Completion(env, rest);
  if (command == "render") return Render(env, rest);
  if (command == "help") {
    out << UsageText();
    return kExitOk;
  }
  return env.Usage(absl::StrCat("unknown command '", command,
                                "'; expected maps, plan, navigate, cost-to-go, "
                                "check, cache-stats, health, metrics, batch, bench or "
                                "completion"));
  return env.Usage(absl::StrCat(
      "unknown command '", command,
      "'; expected maps, plan, navigate, cost-to-go, "
      "check, cache-stats, health, metrics, batch, bench or render"));
}

}  // namespace pathd::pathctl
