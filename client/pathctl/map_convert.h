// The map files `pathctl maps import` and `maps export` handle beyond what
// `maps create --from` sends as is: PNG occupancy images read with map_server's
// rules, and grids written back as Moving AI .map text or ROS map_server
// YAML + PGM. Formats that cannot hold every cost byte lose information in
// documented ways, counted in ExportLoss.
#ifndef PATHD_CLIENT_PATHCTL_MAP_CONVERT_H_
#define PATHD_CLIENT_PATHCTL_MAP_CONVERT_H_

#include <cstdint>
#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/map/grid.h"
#include "core/map_io/map_io.h"
#include "pathd/v1/map_service.pb.h"

namespace pathd::pathctl {

// Converts a PNG occupancy image to a grid exactly as map_server converts a
// PGM (core's ParseRosMap, with the metadata's thresholds, negate, mode,
// resolution and origin; bottom image row becomes row 0), the grey level of
// a colour pixel being the truncated mean of its R, G and B, as map_server's
// image loader computes it. As in map_server, alpha matters only in scale
// mode: a fully transparent pixel between the thresholds is unknown.
// INVALID_ARGUMENT naming `source` for undecodable data or more than
// `max_cells` pixels.
absl::StatusOr<Grid> GridFromOccupancyPng(
    std::string_view png, const RosMapMetadata& metadata,
    std::string_view source, int64_t max_cells = kDefaultMaxReaderCells);

// Cells an export could not write as they are.
struct ExportLoss {
  int64_t weighted = 0;   // costs 1..252, written as passable
  int64_t inscribed = 0;  // cost 253, written as an obstacle
  int64_t unknown = 0;    // cost 255 in a .map, written as out of bounds
};

// Moving AI text ("type octile", height, width, "map", rows, row 0 first):
// free '.', weighted 'S' (swamp: passable; read back as free), inscribed and
// lethal '@', unknown 'O' (out of bounds; read back as lethal).
std::string ToMovingAiText(const Grid& grid, ExportLoss* loss);

// Values map_server's map_saver writes in trinary mode.
inline constexpr uint8_t kPgmFree = 254;
inline constexpr uint8_t kPgmOccupied = 0;
inline constexpr uint8_t kPgmUnknown = 205;

// A ROS map_server map: the YAML (image, resolution, origin, negate 0,
// occupied_thresh 0.65, free_thresh 0.196, mode trinary) and a binary (P5)
// 8-bit PGM, top image row = the grid's last row. Free 254, weighted 254
// (passable), inscribed and lethal 0, unknown 205; read back with those
// thresholds they give free, lethal and unknown.
struct RosMapFiles {
  std::string yaml;
  std::string pgm;
};
RosMapFiles ToRosMapFiles(const Grid& grid, const std::string& image_name,
                          ExportLoss* loss);

// The PGM ExportMapFile writes beside a YAML: the same path ending in .pgm.
std::string PgmPathFor(const std::string& yaml_path);

// Writes `grid` by `path`'s extension: .map as Moving AI text; .yaml/.yml as
// ROS YAML plus PgmPathFor(path), the YAML naming the image relative to its
// own folder. Returns what the format lost. INVALID_ARGUMENT for another
// extension; PERMISSION_DENIED / DATA_LOSS naming a file that cannot be
// written.
absl::StatusOr<ExportLoss> ExportMapFile(const Grid& grid,
                                         const std::string& path);

// What `maps import` does with a file, by extension.
enum class ImportKind {
  kUnknown,
  kMovingAi,    // .map: sent as text, the server parses it
  kRosYaml,     // .yaml/.yml naming a PGM: sent as YAML + image
  kRosYamlPng,  // .yaml/.yml naming a .png: decoded here, sent as cells
  kPng,         // .png: decoded here with the PNG options, sent as cells
};

// Options for a bare .png (a YAML carries its own): map_server's defaults.
struct PngImportOptions {
  double resolution = 1.0;
  double occupied_thresh = 0.65;
  double free_thresh = 0.196;
  bool negate = false;
};

// Sets request->source (and, for images decoded here, its resolution and
// origin) from the file at `path`: Moving AI and PGM maps go through
// SetMapSourceFromFile, PNG images through GridFromOccupancyPng as
// raw cells. Returns the kind handled. INVALID_ARGUMENT for an unknown
// extension or bad file contents, NOT_FOUND / INTERNAL for unreadable files,
// each naming the file.
absl::StatusOr<ImportKind> SetImportSource(const std::string& path,
                                           const PngImportOptions& png_options,
                                           v1::CreateMapRequest* request);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_MAP_CONVERT_H_
