// pathctl maps stats: what the geometric planners build from a map (the
// polygonal model, visibility graph, navigation mesh, cell decomposition,
// Voronoi graph), with sizes, memory and build time. Built here from the
// fetched map by the planners' own code (core/geometry/structure.h), so the
// figures are this machine's and do not depend on what the server cached.
#include "client/pathctl/maps_stats_cmd.h"

#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "client/pathctl/command.h"
#include "client/pathctl/output.h"
#include "core/geometry/structure.h"

namespace pathd::pathctl {

std::string StructureSummary(const GeometricStructure& s) {
  std::vector<std::string> counts;
  for (const auto& [name, count] : s.counts) {
    counts.push_back(absl::StrFormat("%d %s", count, name));
  }
  return absl::StrFormat("%s: %s; %.1f KiB; built in %.3f ms", s.kind,
                         absl::StrJoin(counts, ", "), s.bytes / 1024.0,
                         absl::ToDoubleMilliseconds(s.build_time));
}

namespace {

int MapsStats(CommandEnv& env, Args args) {
  if (args.size() != 1) return env.Usage("maps stats takes one NAME");
  if (env.json()) {
    return env.Unsupported("maps stats", "use --output csv for a table");
  }
  std::vector<std::string> kinds;
  const std::string& only = env.options().render.overlay;
  if (!only.empty()) {
    kinds.push_back(only);
  } else {
    for (std::string_view k : StructureKinds()) kinds.emplace_back(k);
  }
  absl::StatusOr<Grid> grid = FetchGrid(env, args[0]);
  if (!grid.ok()) return env.Fail(grid.status());
  std::vector<GeometricStructure> structures;
  for (const std::string& kind : kinds) {
    absl::StatusOr<GeometricStructure> s =
        DescribeStructure(kind, *grid, env.options().cost.unknown_is_free);
    if (!s.ok()) return env.Usage(s.status().message());
    structures.push_back(*std::move(s));
  }
  if (env.csv()) {
    Table table({"structure", "count", "name", "bytes", "build_ms"});
    for (const GeometricStructure& s : structures) {
      for (const auto& [name, count] : s.counts) {
        table.AddRow({s.kind, absl::StrCat(count), name, absl::StrCat(s.bytes),
                      absl::StrFormat("%.3f", absl::ToDoubleMilliseconds(s.build_time))});
      }
    }
    return env.PrintCsv(table);
  }
  env.out() << absl::StrFormat("map %s: %dx%d cells\n", args[0], grid->width(),
                               grid->height());
  for (const GeometricStructure& s : structures) {
    env.out() << "  " << StructureSummary(s) << "\n";
  }
  return kExitOk;
}

constexpr absl::string_view kStatsFlags[] = {"overlay", "unknown_is_free"};

}  // namespace

const Command kMapsStatsCommand = {
    .name = "maps stats",
    .synopsis = "NAME [--overlay KIND] [--unknown_is_free]",
    .help = "Builds what the geometric planners build from map NAME (polygons,\n"
            "visibility graph, navigation mesh, cell decomposition, Voronoi graph;\n"
            "only KIND with --overlay) with their own code, here, and prints each\n"
            "one's sizes, memory and build time.",
    .flags = kStatsFlags,
    .run = MapsStats,
    .map_arg = MapArg::kExisting,
};

}  // namespace pathd::pathctl
