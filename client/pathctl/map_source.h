// Turns a map file on the client's disk into the source of a CreateMapRequest:
// Moving AI .map files travel as text, ROS map_server maps as the YAML text
// plus the bytes of the image it names. The server parses both, so the client
// only reads files and never interprets cells, except for maps over one
// default-sized message: those are parsed here and streamed (UploadMap).
#ifndef PATHD_CLIENT_PATHCTL_MAP_SOURCE_H_
#define PATHD_CLIENT_PATHCTL_MAP_SOURCE_H_

#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "pathd/v1/map_service.pb.h"

namespace pathd::pathctl {

enum class MapFileKind {
  kUnknown,
  kMovingAi,  // .map
  kRosYaml,   // .yaml or .yml (+ the PGM it names)
};

// Classifies a path by its extension, case-insensitively.
MapFileKind DetectMapFileKind(const std::string& path);

// Reads `path` (and for ROS maps the image its YAML names, relative to the
// YAML's folder unless absolute) and sets request->source accordingly; other
// fields are left alone. INVALID_ARGUMENT for an unknown extension or a YAML
// without a usable image entry; NOT_FOUND / INTERNAL naming the file when a
// file cannot be read.
absl::Status SetMapSourceFromFile(const std::string& path,
                                  v1::CreateMapRequest* request);

// A CreateMapRequest larger than this goes through UploadMap instead
// (CreateMapWithProgress): gRPC's default message limit, which any pathd
// accepts, whatever its --max_message_bytes.
inline constexpr size_t kUnaryCreateMapBytes = size_t{4} << 20;

// The UploadMap call equivalent to `request`: its source parsed here (the
// same core readers the server uses; errors name "movingai_text",
// "ros_map.yaml" or "ros_map.image" as the server's would), the header
// filled from the request and, for ROS maps, the YAML's pose. `cells`
// receives the row-major cost bytes. INVALID_ARGUMENT for a map_dir_file
// source (the server reads that itself) or no source.
absl::Status UploadFromCreateRequest(const v1::CreateMapRequest& request,
                                     v1::UploadMapHeader* header,
                                     std::string* cells);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_MAP_SOURCE_H_
