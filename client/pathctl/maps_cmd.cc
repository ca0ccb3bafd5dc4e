// pathctl maps create, list, get, delete, set and rect: the MapService calls
// that make, read, remove and edit one map. (watch is maps_watch_cmd.cc,
// import and export maps_io_cmd.cc.)
#include "client/pathctl/maps_cmd.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <future>
#include <span>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/pathctl/map_source.h"
#include "client/pathctl/command.h"
#include "client/pathctl/progress.h"
#include "core/status_macros.h"

namespace pathd::pathctl {
namespace {

// Largest map `maps get --cells` renders; beyond this ASCII is unreadable and
// the response would be megabytes.
constexpr int32_t kMaxRenderWidth = 1024;
constexpr int64_t kMaxRenderCells = int64_t{1} << 20;

int MapsCreate(CommandEnv& env, Args args) {
  const MapsOptions& options = env.options().maps;
  if (args.size() != 1) return env.Usage("maps create takes one NAME");
  if (options.from.empty()) return env.Usage("maps create needs --from FILE");
  const MapFileKind kind = DetectMapFileKind(options.from);
  if (kind == MapFileKind::kUnknown) {
    return env.Usage(
        absl::StrCat("--from ", options.from,
                     ": unknown map file type; expected .map (Moving "
                     "AI) or .yaml/.yml (ROS map_server)"));
  }
  if (options.resolution < 0 || !std::isfinite(options.resolution)) {
    return env.Usage(
        "--resolution must be a positive number of metres per cell");
  }
  if (kind == MapFileKind::kRosYaml && options.resolution != 0) {
    return env.Usage(
        "--resolution applies to .map files; a ROS map's YAML sets "
        "its own resolution");
  }
  v1::CreateMapRequest request;
  request.set_name(args[0]);
  request.set_replace(options.replace);
  request.set_resolution(options.resolution);
  if (absl::Status status =
          SetMapSourceFromFile(options.from, &request);
      !status.ok()) {
    return env.Fail(status);
  }
  absl::StatusOr<v1::CreateMapResponse> response =
      CreateMapWithProgress(env, request, options.from);
  if (!response.ok()) return env.Fail(response.status());
  if (env.json()) return env.PrintJson(*response);
  if (env.csv()) {
    const v1::MapInfo* info[] = {&response->info()};
    return env.PrintCsv(MapInfoCsv(info));
  }
  env.out() << (response->info().version() > 1 ? "replaced" : "created")
            << " map " << args[0] << "\n";
  PrintMapInfo(env.out(), response->info());
  return kExitOk;
}

int MapsList(CommandEnv& env, Args args) {
  if (!args.empty()) return env.Usage("maps list takes no arguments");
  absl::StatusOr<v1::ListMapsResponse> response = env.client().ListMaps();
  if (!response.ok()) return env.Fail(response.status());
  if (env.json()) return env.PrintJson(*response);
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

int MapsGet(CommandEnv& env, Args args) {
  if (args.size() != 1) return env.Usage("maps get takes one NAME");
  if (env.options().maps.cells && env.csv()) {
    return env.Unsupported("maps get --cells",
                           "the cells print as ASCII (table) or base64 (json)");
  }
  v1::GetMapRequest request;
  request.set_name(args[0]);
  request.set_include_cells(env.options().maps.cells);
  absl::StatusOr<v1::GetMapResponse> response = env.client().GetMap(request);
  if (!response.ok()) return env.Fail(response.status());
  if (env.json()) return env.PrintJson(*response);
  const v1::MapInfo& info = response->info();
  if (env.csv()) {
    const v1::MapInfo* maps[] = {&info};
    return env.PrintCsv(MapInfoCsv(maps));
  }
  PrintMapInfo(env.out(), info);
  if (!env.options().maps.cells) return kExitOk;
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

int MapsDelete(CommandEnv& env, Args args) {
  if (args.size() != 1) return env.Usage("maps delete takes one NAME");
  absl::StatusOr<v1::DeleteMapResponse> response =
      env.client().DeleteMap(args[0]);
  if (!response.ok()) return env.Fail(response.status());
  if (env.json()) return env.PrintJson(*response);
  if (env.csv()) {
    Table table({"name", "last_version"});
    table.AddRow({args[0], absl::StrCat(response->last_version())});
    return env.PrintCsv(table);
  }
  env.out() << "deleted map " << args[0] << " (was at version "
            << response->last_version() << ")\n";
  return kExitOk;
}

int SendUpdate(CommandEnv& env, v1::UpdateMapRequest& request) {
  if (env.options().maps.expected_version.has_value()) {
    request.set_expected_version(*env.options().maps.expected_version);
  }
  absl::StatusOr<v1::UpdateMapResponse> response =
      env.client().UpdateMap(request);
  if (!response.ok()) return env.Fail(response.status());
  if (env.json()) return env.PrintJson(*response);
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

int MapsSet(CommandEnv& env, Args args) {
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

int MapsRect(CommandEnv& env, Args args) {
  if (args.size() != 6)
    return env.Usage("maps rect takes NAME X0 Y0 X1 Y1 COST");
  static constexpr const char* kNames[] = {"X0", "Y0", "X1", "Y1"};
  absl::StatusOr<std::vector<int32_t>> c =
      ParseInts(args.subspan(1, 4), kNames);
  if (!c.ok()) return env.Usage(c.status().message());
  absl::StatusOr<uint32_t> cost = ParseCost(args[5]);
  if (!cost.ok()) return env.Usage(cost.status().message());
  // X0 Y0 is the first corner and X1 Y1 the last, as on the wire. Inverted
  // corners are refused as the server refuses them (server/map_store.cc),
  // not swapped: a script that got them wrong should hear about it.
  if ((*c)[0] > (*c)[2] || (*c)[1] > (*c)[3]) {
    return env.Fail(absl::InvalidArgumentError(absl::StrFormat(
        "change 0: rect (%d, %d)-(%d, %d) has min > max", (*c)[0], (*c)[1], (*c)[2],
        (*c)[3])));
  }
  v1::UpdateMapRequest request;
  request.set_name(args[0]);
  v1::CellChange* change = request.add_changes();
  v1::CellRect* rect = change->mutable_rect();
  rect->set_x_min((*c)[0]);
  rect->set_y_min((*c)[1]);
  rect->set_x_max((*c)[2]);
  rect->set_y_max((*c)[3]);
  change->set_cost(*cost);
  return SendUpdate(env, request);
}

constexpr absl::string_view kCreateFlags[] = {"from", "replace", "resolution"};
constexpr absl::string_view kGetFlags[] = {"cells"};
constexpr absl::string_view kUpdateFlags[] = {"expected_version"};

}  // namespace

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
    CommandEnv& env, const v1::CreateMapRequest& request, const std::string& file) {
  const size_t request_bytes = request.ByteSizeLong();
  // A map over one default-sized message is parsed here and streamed in
  // bands of rows (UploadMap), so no message comes near any server's limit.
  std::function<absl::StatusOr<v1::CreateMapResponse>()> call;
  v1::UploadMapHeader header;
  std::string cells;
  if (request_bytes > kUnaryCreateMapBytes &&
      request.source_case() != v1::CreateMapRequest::kMapDirFile) {
    PATHD_RETURN_IF_ERROR(UploadFromCreateRequest(request, &header, &cells));
    call = [&env, &header, &cells] { return env.client().UploadMap(header, cells); };
  } else {
    call = [&env, &request] { return env.client().CreateMap(request); };
  }
  if (!env.global().progress_bars) return call();
  const double bytes = static_cast<double>(request_bytes);
  ProgressBar bar(env.err(),
                  absl::StrFormat("maps create %s: sending %s (%.1f MiB)",
                                  request.name(), file, bytes / (1024 * 1024)),
                  0, ProgressBar::Unit::kSeconds, true);
  std::future<absl::StatusOr<v1::CreateMapResponse>> response =
      std::async(std::launch::async, call);
  const absl::Time started = absl::Now();
  while (response.wait_for(absl::ToChronoMilliseconds(
             ProgressBar::kRedrawInterval)) != std::future_status::ready) {
    bar.Update(absl::ToDoubleSeconds(absl::Now() - started));
  }
  bar.Update(absl::ToDoubleSeconds(absl::Now() - started));
  bar.Finish();
  return response.get();
}

const Command kMapsCreateCommand = {
    .name = "maps create",
    .synopsis = "NAME --from FILE [--replace] [--resolution R]",
    .help = "Creates map NAME from FILE: a Moving AI .map (sent as text) or a ROS\n"
            "map_server .yaml/.yml (the YAML and the image it names). --replace\n"
            "replaces an existing map of that name; --resolution sets a .map's\n"
            "metres per cell (default 1).",
    .flags = kCreateFlags,
    .run = MapsCreate,
    .map_arg = MapArg::kNew,
};

const Command kMapsListCommand = {
    .name = "maps list",
    .synopsis = "",
    .help = "Lists the server's maps: size, resolution, version, free and blocked cells.",
    .flags = {},
    .run = MapsList,
};

const Command kMapsGetCommand = {
    .name = "maps get",
    .synopsis = "NAME [--cells]",
    .help = "Prints map NAME's size, resolution, origin and version; --cells also\n"
            "draws its cells, one glyph per cell (maps up to 1024 columns).",
    .flags = kGetFlags,
    .run = MapsGet,
    .map_arg = MapArg::kExisting,
};

const Command kMapsDeleteCommand = {
    .name = "maps delete",
    .synopsis = "NAME",
    .help = "Deletes map NAME.",
    .flags = {},
    .run = MapsDelete,
    .map_arg = MapArg::kExisting,
};

const Command kMapsSetCommand = {
    .name = "maps set",
    .synopsis = "NAME X Y COST [--expected_version V]",
    .help = "Sets cell (X, Y) of map NAME to COST (0..255, or free, inscribed,\n"
            "lethal, unknown), making a new version; --expected_version applies it\n"
            "only at version V (ABORTED otherwise).",
    .flags = kUpdateFlags,
    .run = MapsSet,
    .map_arg = MapArg::kExisting,
};

const Command kMapsRectCommand = {
    .name = "maps rect",
    .synopsis = "NAME X0 Y0 X1 Y1 COST [--expected_version V]",
    .help = "Sets every cell of the rectangle from (X0, Y0) to (X1, Y1), both\n"
            "included, to COST. X0 <= X1 and Y0 <= Y1: inverted corners are refused\n"
            "as the server refuses them.",
    .flags = kUpdateFlags,
    .run = MapsRect,
    .map_arg = MapArg::kExisting,
};

}  // namespace pathd::pathctl
