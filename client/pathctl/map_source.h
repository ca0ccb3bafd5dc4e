// Turns a map file on the client's disk into the source of a CreateMapRequest:
// Moving AI .map files travel as text, ROS map_server maps as the YAML text
// plus the bytes of the image it names. The server parses both, so the client
// only reads files and never interprets cells.
#ifndef PATHD_CLIENT_PATHCTL_MAP_SOURCE_H_
#define PATHD_CLIENT_PATHCTL_MAP_SOURCE_H_

#include <string>

#include "absl/status/status.h"
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

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_MAP_SOURCE_H_
