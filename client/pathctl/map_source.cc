// Reading map files into CreateMapRequest sources.
#include "client/pathctl/map_source.h"

#include <filesystem>
#include <string>
#include <utility>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "core/map_io/map_io.h"
#include "core/status_macros.h"

namespace pathd::pathctl {

MapFileKind DetectMapFileKind(const std::string& path) {
  const std::string lower = absl::AsciiStrToLower(path);
  if (absl::EndsWith(lower, ".map")) return MapFileKind::kMovingAi;
  if (absl::EndsWith(lower, ".yaml") || absl::EndsWith(lower, ".yml")) {
    return MapFileKind::kRosYaml;
  }
  return MapFileKind::kUnknown;
}

absl::Status SetMapSourceFromFile(const std::string& path,
                                  v1::CreateMapRequest* request) {
  switch (DetectMapFileKind(path)) {
    case MapFileKind::kMovingAi: {
      PATHD_ASSIGN_OR_RETURN(std::string text, ReadFileToString(path));
      request->set_movingai_text(std::move(text));
      return absl::OkStatus();
    }
    case MapFileKind::kRosYaml: {
      PATHD_ASSIGN_OR_RETURN(std::string yaml, ReadFileToString(path));
      // Only the image name is needed here; the server re-parses the YAML, so
      // the two can never disagree about thresholds or origin.
      PATHD_ASSIGN_OR_RETURN(RosMapMetadata metadata,
                             ParseRosMapYaml(yaml, path));
      if (metadata.image.empty()) {
        return absl::InvalidArgumentError(
            absl::StrCat(path, ": the YAML names no image"));
      }
      // map_server resolves a relative image against the YAML's folder, not
      // the working directory.
      std::filesystem::path image_path(metadata.image);
      if (image_path.is_relative()) {
        image_path = std::filesystem::path(path).parent_path() / image_path;
      }
      PATHD_ASSIGN_OR_RETURN(std::string image,
                             ReadFileToString(image_path.string()));
      v1::RosMap* ros_map = request->mutable_ros_map();
      ros_map->set_yaml(std::move(yaml));
      ros_map->set_image(std::move(image));
      return absl::OkStatus();
    }
    case MapFileKind::kUnknown:
      break;
  }
  return absl::InvalidArgumentError(
      absl::StrCat(path,
                   ": unknown map file type; expected .map (Moving AI) or "
                   ".yaml/.yml (ROS map_server)"));
}

}  // namespace pathd::pathctl
