// Readers for the map formats pathd accepts: Moving AI .map and .map.scen
// files and ROS map_server maps (PGM P2/P5 + YAML). Every error names the
// source (file name), the line where it applies, and the problem.
#ifndef PATHD_CORE_MAP_IO_MAP_IO_H_
#define PATHD_CORE_MAP_IO_MAP_IO_H_

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "core/map/grid.h"

namespace pathd {

// Upper bound on width * height any reader accepts before allocating, so a
// hostile header cannot make it allocate gigabytes. Callers (the server's
// --max_map_cells) may pass a smaller limit.
inline constexpr int64_t kDefaultMaxReaderCells = int64_t{1} << 28;

// Parses the text of a Moving AI .map file ("type octile", "height H",
// "width W", "map", then H rows of W characters). Passable '.', 'G', 'S' become
// kFreeCost; '@', 'O', 'T', 'W' become kLethalCost; any other character is an
// error. Accepts CRLF line endings and a missing final newline. Resolution 1,
// origin 0. Errors are INVALID_ARGUMENT "<source>:<line>: <problem>", or
// RESOURCE_EXHAUSTED when the header's width x height exceeds max_cells
// (checked before anything is allocated).
absl::StatusOr<Grid> ParseMovingAiMap(std::string_view text,
                                      std::string_view source,
                                      int64_t max_cells = kDefaultMaxReaderCells);
absl::StatusOr<Grid> ReadMovingAiMapFile(const std::string& path,
                                         int64_t max_cells = kDefaultMaxReaderCells);

// One line of a Moving AI scenario file.
struct Scenario {
  int bucket = 0;
  std::string map;  // as stored; do not resolve
  int32_t map_width = 0;
  int32_t map_height = 0;
  Cell start;
  Cell goal;
  double optimal_length = 0.0;
  // The stored length's text, to derive its precision.
  std::string optimal_text;
  int line = 0;  // 1-based line in the file
};

// Parses a .map.scen file: a "version 1" or "version 1.0" header, then lines
// of 9 whitespace-separated fields. Lines with fewer than 9 fields are skipped
// (the benchmark files end with blank lines); malformed fields are errors.
absl::StatusOr<std::vector<Scenario>> ParseMovingAiScenarios(std::string_view text,
                                                             std::string_view source);
absl::StatusOr<std::vector<Scenario>> ReadMovingAiScenarioFile(const std::string& path);

// A whole scenario file. The version ("1" or "1.0") decides how precise the
// stored lengths are; pass it to ScenarioTolerance.
struct ScenarioFile {
  std::string version;
  std::vector<Scenario> scenarios;
};

// As ParseMovingAiScenarios / ReadMovingAiScenarioFile, also returning the
// header's version.
absl::StatusOr<ScenarioFile> ParseMovingAiScenarioFile(std::string_view text,
                                                       std::string_view source);
absl::StatusOr<ScenarioFile> ReadMovingAiScenarioFileWithVersion(
    const std::string& path);

// Tolerance for comparing a computed optimal length with the stored one, per
// the benchmark README: bg512 ("version 1.0") 2 decimals; 8-decimal files
// 1e-6; otherwise half a unit in the 6th significant digit plus 1e-5.
double ScenarioTolerance(const Scenario& scenario, std::string_view version);

// Fields of a ROS map_server YAML file.
struct RosMapMetadata {
  std::string image;
  double resolution = 0.0;
  GridOrigin origin;
  bool negate = false;
  double occupied_thresh = 0.65;
  double free_thresh = 0.196;
  enum class Mode { kTrinary, kScale, kRaw } mode = Mode::kTrinary;
};

// Parses map_server YAML (image, resolution, origin required; negate,
// occupied_thresh, free_thresh, mode optional).
absl::StatusOr<RosMapMetadata> ParseRosMapYaml(std::string_view yaml,
                                               std::string_view source);

// Converts PGM bytes (P2 or P5, maxval up to 65535) with the YAML's rules to a
// grid: p = (maxval - v) / maxval (or v / maxval when negate); trinary: p >
// occupied_thresh -> kLethalCost, p < free_thresh -> kFreeCost, else
// kUnknownCost; scale: between the thresholds costs 1..252 linearly; raw: the
// value itself (clamped to 255). Rows are flipped so row 0 is the image's
// bottom row (OccupancyGrid convention). Also checks the metadata (resolution,
// origin, thresholds), since callers may build it without ParseRosMapYaml.
// RESOURCE_EXHAUSTED when the image has more than max_cells pixels.
absl::StatusOr<Grid> ParseRosMap(const RosMapMetadata& metadata,
                                 std::string_view pgm, std::string_view source,
                                 int64_t max_cells = kDefaultMaxReaderCells);

// Reads a .yaml file and the image it names (relative to the YAML's folder).
absl::StatusOr<Grid> ReadRosMapFile(const std::string& yaml_path,
                                    int64_t max_cells = kDefaultMaxReaderCells);

// Reads a map file by extension: ".map" Moving AI, ".yaml"/".yml" ROS.
absl::StatusOr<Grid> ReadMapFile(const std::string& path,
                                 int64_t max_cells = kDefaultMaxReaderCells);

// Reads a whole file into a string; NOT_FOUND / INTERNAL naming the path.
absl::StatusOr<std::string> ReadFileToString(const std::string& path);

}  // namespace pathd

#endif  // PATHD_CORE_MAP_IO_MAP_IO_H_
