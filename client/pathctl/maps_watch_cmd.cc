// pathctl maps watch: a WatchMap stream printed one line (or JSON object,
// or CSV row) per map version.
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/strip.h"
#include "client/pathctl/command.h"
#include "google/protobuf/util/json_util.h"

namespace pathd::pathctl {
namespace {

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
int MapsWatch(CommandEnv& env, Args args) {
  const MapsOptions& options = env.options().maps;
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
    } else if (env.json()) {
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

constexpr absl::string_view kWatchFlags[] = {"from_version", "count"};

}  // namespace

const Command kMapsWatchCommand = {
    .name = "maps watch",
    .synopsis = "NAME [--from_version V] [--count N]",
    .help = "Prints one line per new version of map NAME as it happens: \"version V\n"
            "updated: N cells in R rects: (x0,y0)-(x1,y1) ...\", \"version V resync:\n"
            "whole map WxH\", \"version V replaced: whole map WxH\" or \"version V\n"
            "deleted\" (then it exits 0). --from_version is the version already held\n"
            "(0: none; another than the current one starts with the whole map);\n"
            "--count stops after N events. No deadline: --timeout does not apply.",
    .flags = kWatchFlags,
    .run = MapsWatch,
    .map_arg = MapArg::kExisting,
};

}  // namespace pathd::pathctl
