// map_tile: writes a large map made from a small one, for huge-map tests,
// benchmarks and `make serve` (docs/performance.md, "Huge maps"). Each
// source cell first becomes a --scale x --scale block; the scaled map is then
// tiled over --side x --side cells with geometric_bench's MirrorTile rule
// (odd tile columns mirrored in x, odd tile rows in y, so walls continue
// across tile borders), the last tile column and row cropped:
//
//   map_tile --source maps/arena2.map --side 16384 --out build/huge16384.yaml
//
// The output is what pathd's --map_dir loads: a ROS map_server YAML plus a
// binary PGM (P5) next to it when --out ends in .yaml (trinary when every
// cell is free, lethal or unknown, else raw costs, so no cost is lost), or
// Moving AI text when it ends in .map (costs 253..255 as '@', others '.').
// Prints the size, time and the checksum of the cells (FNV-1a 64, row 0
// first) on stdout.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/map/grid.h"
#include "core/map_io/map_io.h"

ABSL_FLAG(std::string, source, "maps/arena2.map",
          "source map: a Moving AI .map or a ROS map_server .yaml (e.g. a "
          "shared Moving AI map)");
ABSL_FLAG(int32_t, side, 16384,
          "width and height of the output, cells (1..65536)");
ABSL_FLAG(int32_t, scale, 1,
          "each source cell becomes scale x scale cells (1..64)");
ABSL_FLAG(double, resolution, 0.05,
          "metres per output cell (written to the YAML)");
ABSL_FLAG(std::string, out, "",
          "output file: NAME.yaml (+ NAME.pgm) or NAME.map");

namespace {

absl::StatusOr<pathd::Grid> ReadSource(const std::string& path) {
  // The source is small; the readers' default bound is plenty.
  if (absl::EndsWith(path, ".map")) return pathd::ReadMovingAiMapFile(path);
  if (absl::EndsWith(path, ".yaml") || absl::EndsWith(path, ".yml")) {
    return pathd::ReadRosMapFile(path);
  }
  return absl::InvalidArgumentError(
      absl::StrCat("--source ", path, ": expected a .map or .yaml file"));
}

// The source cell output cell (x, y) copies: MirrorTile over the scaled map.
int32_t SourceIndex(int32_t out, int32_t scaled, int32_t scale) {
  const int32_t tile = out / scaled;
  const int32_t in_tile = out % scaled;
  const int32_t mirrored = tile % 2 == 0 ? in_tile : scaled - 1 - in_tile;
  return mirrored / scale;
}

pathd::Grid Tile(const pathd::Grid& source, int32_t side, int32_t scale) {
  const int32_t w = source.width() * scale;
  const int32_t h = source.height() * scale;
  pathd::Grid out = *pathd::Grid::Create(side, side);
  std::vector<int32_t> column(side);
  for (int32_t x = 0; x < side; ++x) column[x] = SourceIndex(x, w, scale);
  for (int32_t y = 0; y < side; ++y) {
    const int32_t sy = SourceIndex(y, h, scale);
    uint8_t* row = out.mutable_cells().data() + out.Index(0, y);
    for (int32_t x = 0; x < side; ++x) row[x] = source.cost(column[x], sy);
  }
  return out;
}

uint64_t Fnv1a(const std::vector<uint8_t>& bytes) {
  uint64_t hash = 14695981039346656037ull;
  for (const uint8_t b : bytes) {
    hash ^= b;
    hash *= 1099511628211ull;
  }
  return hash;
}

absl::Status WriteFile(const std::string& path, const std::string& head,
                       const char* body, size_t body_size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(head.data(), static_cast<std::streamsize>(head.size()));
  out.write(body, static_cast<std::streamsize>(body_size));
  out.close();
  if (!out) return absl::InternalError(absl::StrCat("cannot write ", path));
  return absl::OkStatus();
}

// map_server YAML + P5 PGM. Rows are written last row first: the reader
// flips them back (the OccupancyGrid convention, core/map_io).
absl::Status WriteRosMap(const pathd::Grid& grid, const std::string& yaml_path,
                         double resolution) {
  const bool trinary =
      std::all_of(grid.cells().begin(), grid.cells().end(), [](uint8_t c) {
        return c == pathd::kFreeCost || c == pathd::kLethalCost ||
               c == pathd::kUnknownCost;
      });
  std::vector<uint8_t> pixels(grid.size());
  const size_t width = static_cast<size_t>(grid.width());
  for (int32_t y = 0; y < grid.height(); ++y) {
    const uint8_t* row = grid.cells().data() + grid.Index(0, y);
    uint8_t* dst = pixels.data() + (grid.height() - 1 - y) * width;
    for (size_t x = 0; x < width; ++x) {
      if (!trinary) {
        dst[x] = row[x];
      } else {
        // map_server's trinary: white free, black occupied, grey unknown.
        dst[x] = row[x] == pathd::kFreeCost     ? 254
                 : row[x] == pathd::kLethalCost ? 0
                                                : 205;
      }
    }
  }
  const std::filesystem::path yaml(yaml_path);
  const std::filesystem::path pgm =
      std::filesystem::path(yaml).replace_extension(".pgm");
  const std::string header =
      absl::StrFormat("P5\n%d %d\n255\n", grid.width(), grid.height());
  if (absl::Status s = WriteFile(pgm.string(), header,
                                 reinterpret_cast<const char*>(pixels.data()),
                                 pixels.size());
      !s.ok()) {
    return s;
  }
  const std::string text = absl::StrFormat(
      "# Written by tools/map_tile (docs/performance.md, \"Huge maps\").\n"
      "image: %s\nresolution: %g\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
      "occupied_thresh: 0.65\nfree_thresh: 0.196\nmode: %s\n",
      pgm.filename().string(), resolution, trinary ? "trinary" : "raw");
  return WriteFile(yaml_path, text, nullptr, 0);
}

absl::Status WriteMovingAi(const pathd::Grid& grid, const std::string& path) {
  std::string text = absl::StrFormat("type octile\nheight %d\nwidth %d\nmap\n",
                                     grid.height(), grid.width());
  std::string body;
  body.reserve(grid.size() + grid.height());
  for (int32_t y = 0; y < grid.height(); ++y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      const uint8_t c = grid.cost(x, y);
      // Moving AI has two classes here: passable or not.
      body.push_back(c < pathd::kInscribedCost ? '.' : '@');
    }
    body.push_back('\n');
  }
  return WriteFile(path, text, body.data(), body.size());
}

}  // namespace

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "Writes a --side x --side map mirror-tiled from --source.\n"
      "  map_tile --source maps/arena2.map --side 16384 --out huge16384.yaml");
  absl::ParseCommandLine(argc, argv);
  const std::string source_path = absl::GetFlag(FLAGS_source);
  const int32_t side = absl::GetFlag(FLAGS_side);
  const int32_t scale = absl::GetFlag(FLAGS_scale);
  const double resolution = absl::GetFlag(FLAGS_resolution);
  const std::string out = absl::GetFlag(FLAGS_out);
  if (side < 1 || side > pathd::kMaxGridDimension) {
    std::cerr << "--side must be in 1.." << pathd::kMaxGridDimension << "\n";
    return 2;
  }
  if (scale < 1 || scale > 64) {
    std::cerr << "--scale must be in 1..64\n";
    return 2;
  }
  if (!(resolution > 0) || !std::isfinite(resolution)) {
    std::cerr << "--resolution must be a positive number of metres\n";
    return 2;
  }
  const bool yaml = absl::EndsWith(out, ".yaml") || absl::EndsWith(out, ".yml");
  if (!yaml && !absl::EndsWith(out, ".map")) {
    std::cerr
        << "--out must name a .yaml (ROS map_server + PGM) or .map file\n";
    return 2;
  }
  const absl::Time start = absl::Now();
  absl::StatusOr<pathd::Grid> source = ReadSource(source_path);
  if (!source.ok()) {
    std::cerr << "--source: " << source.status().message() << "\n";
    return 1;
  }
  const pathd::Grid grid = Tile(*source, side, scale);
  const absl::Status written =
      yaml ? WriteRosMap(grid, out, resolution) : WriteMovingAi(grid, out);
  if (!written.ok()) {
    std::cerr << "--out: " << written.message() << "\n";
    return 1;
  }
  std::cout << absl::StrFormat(
      "wrote %s: %d x %d cells from %s (%d x %d, scale %d), %d free, %d "
      "blocked, fnv1a64 %016x, %.2f s\n",
      out, side, side, source_path, source->width(), source->height(), scale,
      grid.CountFree(), grid.CountBlocked(), Fnv1a(grid.cells()),
      absl::ToDoubleSeconds(absl::Now() - start));
  return 0;
}
