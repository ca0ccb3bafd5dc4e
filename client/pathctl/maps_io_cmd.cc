// pathctl maps import and export: map files converted on this side of the
// wire (PNG occupancy images in, Moving AI and map_server YAML + PGM out).
#include <cmath>
#include <string>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/pathctl/command.h"
#include "client/pathctl/map_convert.h"
#include "client/pathctl/maps_cmd.h"
#include "google/protobuf/struct.pb.h"

namespace pathd::pathctl {
namespace {

// `maps import NAME FILE`: like `maps create --from`, plus PNG occupancy
// images (alone, or named by a map_server YAML), decoded here.
int MapsImport(CommandEnv& env, Args args) {
  const MapsOptions& options = env.options().maps;
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
  if (env.json()) return env.PrintJson(*response);
  if (env.csv()) {
    const v1::MapInfo* info[] = {&response->info()};
    return env.PrintCsv(MapInfoCsv(info));
  }
  env.out() << (response->info().version() > 1 ? "replaced" : "created")
            << " map " << args[0] << " from " << file << "\n";
  PrintMapInfo(env.out(), response->info());
  return kExitOk;
}

// `maps export NAME FILE`: .map or .yaml (+ .pgm), warning on stderr about
// the cells the format cannot hold.
int MapsExport(CommandEnv& env, Args args) {
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
  if (env.json()) {
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

constexpr absl::string_view kImportFlags[] = {"replace", "resolution", "occupied_thresh",
                                             "free_thresh", "negate"};

}  // namespace

const Command kMapsImportCommand = {
    .name = "maps import",
    .synopsis = "NAME FILE [--replace] [--resolution R]\n"
                "                     [--occupied_thresh T] [--free_thresh T] [--negate]",
    .help = "Creates map NAME from FILE: .map and .yaml/.yml as maps create --from,\n"
            "and PNG occupancy images (a bare .png, or one a YAML names), decoded\n"
            "here with map_server's rules: p = (255 - grey) / 255 (grey / 255 with\n"
            "--negate), p > occupied_thresh lethal, p < free_thresh free, otherwise\n"
            "unknown. A bare .png gets --resolution (default 1 m) and origin (0, 0).",
    .flags = kImportFlags,
    .run = MapsImport,
    .map_arg = MapArg::kNew,
};

const Command kMapsExportCommand = {
    .name = "maps export",
    .synopsis = "NAME FILE",
    .help = "Writes map NAME to FILE by its extension: .map (Moving AI) or .yaml/.yml\n"
            "plus a .pgm of the same name (map_server trinary). Cells the format\n"
            "cannot hold are counted in a warning on stderr. A missing folder is\n"
            "NOT_FOUND naming it.",
    .flags = {},
    .run = MapsExport,
    .map_arg = MapArg::kExisting,
};

}  // namespace pathd::pathctl
