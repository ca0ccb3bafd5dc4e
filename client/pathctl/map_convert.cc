// PNG occupancy import and Moving AI / map_server export.
#include "client/pathctl/map_convert.h"

#include <yaml-cpp/yaml.h>

#include <charconv>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "client/pathctl/map_source.h"
#include "client/pathctl/files.h"
#include "client/pathctl/png_io.h"
#include "core/status_macros.h"

namespace pathd::pathctl {
namespace {

// The shortest text that reads back as the same double ("0.1", not yaml-cpp's
// 17-digit "0.10000000000000001").
std::string ShortestDouble(double value) {
  char buffer[32];
  const std::to_chars_result result =
      std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

bool HasExtension(const std::string& path,
                  std::initializer_list<const char*> extensions) {
  const std::string lower = absl::AsciiStrToLower(path);
  for (const char* extension : extensions) {
    if (absl::EndsWith(lower, extension)) return true;
  }
  return false;
}

void RequestFromGrid(const Grid& grid, v1::CreateMapRequest* request) {
  v1::RawCells* raw = request->mutable_raw();
  raw->set_width(grid.width());
  raw->set_height(grid.height());
  raw->set_cells(std::string(grid.cells().begin(), grid.cells().end()));
  request->set_resolution(grid.resolution());
  request->mutable_origin()->set_x(grid.origin().x);
  request->mutable_origin()->set_y(grid.origin().y);
  request->mutable_origin()->set_yaw(grid.origin().yaw);
}

}  // namespace

absl::StatusOr<Grid> GridFromOccupancyPng(std::string_view png,
                                          const RosMapMetadata& metadata,
                                          std::string_view source,
                                          int64_t max_cells) {
  PATHD_ASSIGN_OR_RETURN(const Image image,
                         DecodePngRgba(png, source, max_cells));
  // A binary PGM of the grey levels lets core apply map_server's rules, so a
  // PNG and a PGM of the same picture always load the same cells.
  const size_t pixels =
      static_cast<size_t>(image.width) * static_cast<size_t>(image.height);
  std::string pgm =
      absl::StrCat("P5\n", image.width, " ", image.height, "\n255\n");
  const size_t header = pgm.size();
  pgm.resize(header + pixels);
  for (size_t i = 0; i < pixels; ++i) {
    const uint8_t* p = &image.pixels[4 * i];
    pgm[header + i] = static_cast<char>((p[0] + p[1] + p[2]) / 3);
  }
  PATHD_ASSIGN_OR_RETURN(Grid grid,
                         ParseRosMap(metadata, pgm, source, max_cells));
  if (metadata.mode == RosMapMetadata::Mode::kScale) {
    for (size_t i = 0; i < pixels; ++i) {
      if (image.pixels[4 * i + 3] != 0) continue;
      // Image row r is grid row height-1-r.
      const int32_t x =
          static_cast<int32_t>(i % static_cast<size_t>(image.width));
      const int32_t y =
          image.height - 1 -
          static_cast<int32_t>(i / static_cast<size_t>(image.width));
      const uint8_t cost = grid.cost(x, y);
      if (cost != kFreeCost && cost <= kMaxTraversableCost) {
        grid.set_cost(x, y, kUnknownCost);
      }
    }
  }
  return grid;
}

std::string ToMovingAiText(const Grid& grid, ExportLoss* loss) {
  std::string text = absl::StrCat("type octile\nheight ", grid.height(),
                                  "\nwidth ", grid.width(), "\nmap\n");
  text.reserve(text.size() + (static_cast<size_t>(grid.width()) + 1) *
                                 static_cast<size_t>(grid.height()));
  for (int32_t y = 0; y < grid.height(); ++y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      const uint8_t cost = grid.cost(x, y);
      char c = '@';
      if (cost == kFreeCost) {
        c = '.';
      } else if (cost <= kMaxTraversableCost) {
        c = 'S';
        ++loss->weighted;
      } else if (cost == kInscribedCost) {
        ++loss->inscribed;
      } else if (cost == kUnknownCost) {
        c = 'O';
        ++loss->unknown;
      }
      text.push_back(c);
    }
    text.push_back('\n');
  }
  return text;
}

RosMapFiles ToRosMapFiles(const Grid& grid, const std::string& image_name,
                          ExportLoss* loss) {
  RosMapFiles files;
  YAML::Emitter yaml;
  yaml << YAML::BeginMap;
  yaml << YAML::Key << "image" << YAML::Value << image_name;
  yaml << YAML::Key << "resolution" << YAML::Value
       << ShortestDouble(grid.resolution());
  yaml << YAML::Key << "origin" << YAML::Value << YAML::Flow << YAML::BeginSeq
       << ShortestDouble(grid.origin().x) << ShortestDouble(grid.origin().y)
       << ShortestDouble(grid.origin().yaw) << YAML::EndSeq;
  yaml << YAML::Key << "negate" << YAML::Value << 0;
  yaml << YAML::Key << "occupied_thresh" << YAML::Value << "0.65";
  yaml << YAML::Key << "free_thresh" << YAML::Value << "0.196";
  yaml << YAML::Key << "mode" << YAML::Value << "trinary";
  yaml << YAML::EndMap;
  files.yaml = absl::StrCat(yaml.c_str(), "\n");

  // Binary PGM: a fixed three-line header, then the samples. Writing it needs
  // no library; reading it back is core's ParseRosMap.
  files.pgm = absl::StrCat("P5\n", grid.width(), " ", grid.height(), "\n255\n");
  const size_t header = files.pgm.size();
  files.pgm.resize(header + grid.size());
  size_t i = header;
  for (int32_t y = grid.height() - 1; y >= 0; --y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      const uint8_t cost = grid.cost(x, y);
      uint8_t value = kPgmOccupied;
      if (cost == kFreeCost) {
        value = kPgmFree;
      } else if (cost <= kMaxTraversableCost) {
        value = kPgmFree;
        ++loss->weighted;
      } else if (cost == kInscribedCost) {
        ++loss->inscribed;
      } else if (cost == kUnknownCost) {
        value = kPgmUnknown;
      }
      files.pgm[i++] = static_cast<char>(value);
    }
  }
  return files;
}

std::string PgmPathFor(const std::string& yaml_path) {
  return std::filesystem::path(yaml_path).replace_extension(".pgm").string();
}

absl::StatusOr<ExportLoss> ExportMapFile(const Grid& grid,
                                         const std::string& path) {
  ExportLoss loss;
  if (HasExtension(path, {".map"})) {
    PATHD_RETURN_IF_ERROR(WriteTextFile(path, ToMovingAiText(grid, &loss)));
    return loss;
  }
  if (HasExtension(path, {".yaml", ".yml"})) {
    const std::string pgm_path = PgmPathFor(path);
    const RosMapFiles files = ToRosMapFiles(
        grid, std::filesystem::path(pgm_path).filename().string(), &loss);
    PATHD_RETURN_IF_ERROR(WriteTextFile(pgm_path, files.pgm));
    PATHD_RETURN_IF_ERROR(WriteTextFile(path, files.yaml));
    return loss;
  }
  return absl::InvalidArgumentError(
      absl::StrCat(path,
                   ": unknown map file type; export writes .map (Moving AI) or "
                   ".yaml/.yml (ROS map_server YAML + PGM)"));
}

absl::StatusOr<ImportKind> SetImportSource(const std::string& path,
                                           const PngImportOptions& png_options,
                                           v1::CreateMapRequest* request) {
  if (HasExtension(path, {".png"})) {
    RosMapMetadata metadata;
    metadata.image = path;
    metadata.resolution = png_options.resolution;
    metadata.occupied_thresh = png_options.occupied_thresh;
    metadata.free_thresh = png_options.free_thresh;
    metadata.negate = png_options.negate;
    PATHD_ASSIGN_OR_RETURN(const std::string png, ReadFileToString(path));
    PATHD_ASSIGN_OR_RETURN(const Grid grid,
                           GridFromOccupancyPng(png, metadata, path));
    RequestFromGrid(grid, request);
    return ImportKind::kPng;
  }
  if (HasExtension(path, {".yaml", ".yml"})) {
    PATHD_ASSIGN_OR_RETURN(const std::string yaml, ReadFileToString(path));
    PATHD_ASSIGN_OR_RETURN(const RosMapMetadata metadata,
                           ParseRosMapYaml(yaml, path));
    if (HasExtension(metadata.image, {".png"})) {
      // The server reads PGM only; a PNG is decoded here with the YAML's rules.
      std::filesystem::path image(metadata.image);
      if (image.is_relative())
        image = std::filesystem::path(path).parent_path() / image;
      PATHD_ASSIGN_OR_RETURN(const std::string png,
                             ReadFileToString(image.string()));
      PATHD_ASSIGN_OR_RETURN(
          const Grid grid, GridFromOccupancyPng(png, metadata, image.string()));
      RequestFromGrid(grid, request);
      return ImportKind::kRosYamlPng;
    }
    PATHD_RETURN_IF_ERROR(SetMapSourceFromFile(path, request));
    return ImportKind::kRosYaml;
  }
  if (HasExtension(path, {".map"})) {
    PATHD_RETURN_IF_ERROR(SetMapSourceFromFile(path, request));
    return ImportKind::kMovingAi;
  }
  return absl::InvalidArgumentError(absl::StrCat(
      path,
      ": unknown map file type; import reads .map (Moving AI), .yaml/.yml "
      "(ROS map_server, naming a PGM or PNG image) or .png (occupancy "
      "image)"));
}

}  // namespace pathd::pathctl
