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

absl::Status UploadFromCreateRequest(const v1::CreateMapRequest& request,
                                     v1::UploadMapHeader* header,
                                     std::string* cells) {
  // The server enforces its own --max_map_cells at the header; here the
  // readers' default bound (16384 x 16384) keeps a hostile file from making
  // pathctl allocate gigabytes.
  constexpr int64_t kAnySize = kDefaultMaxReaderCells;
  header->set_name(request.name());
  header->set_replace(request.replace());
  Grid grid;
  switch (request.source_case()) {
    case v1::CreateMapRequest::kRaw:
      header->set_width(request.raw().width());
      header->set_height(request.raw().height());
      header->set_resolution(request.resolution());
      *header->mutable_origin() = request.origin();
      *cells = request.raw().cells();
      return absl::OkStatus();
    case v1::CreateMapRequest::kMovingaiText: {
      PATHD_ASSIGN_OR_RETURN(
          grid, ParseMovingAiMap(request.movingai_text(), "movingai_text", kAnySize));
      header->set_resolution(request.resolution());
      *header->mutable_origin() = request.origin();
      break;
    }
    case v1::CreateMapRequest::kRosMap: {
      PATHD_ASSIGN_OR_RETURN(
          const RosMapMetadata metadata,
          ParseRosMapYaml(request.ros_map().yaml(), "ros_map.yaml"));
      PATHD_ASSIGN_OR_RETURN(grid, ParseRosMap(metadata, request.ros_map().image(),
                                               "ros_map.image", kAnySize));
      header->set_resolution(grid.resolution());
      header->mutable_origin()->set_x(grid.origin().x);
      header->mutable_origin()->set_y(grid.origin().y);
      header->mutable_origin()->set_yaw(grid.origin().yaw);
      break;
    }
    default:
      return absl::InvalidArgumentError(
          "only raw, movingai_text and ros_map sources can be uploaded");
  }
  header->set_width(grid.width());
  header->set_height(grid.height());
  cells->assign(grid.cells().begin(), grid.cells().end());
  return absl::OkStatus();
}

}  // namespace pathd::pathctl
