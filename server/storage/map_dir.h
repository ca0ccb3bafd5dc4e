// Reading maps from the server's --map_dir: resolving a client-supplied
// relative path without letting it escape the directory, and listing the map
// files to load at start-up.
#ifndef PATHD_SERVER_STORAGE_MAP_DIR_H_
#define PATHD_SERVER_STORAGE_MAP_DIR_H_

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "core/map/grid.h"

namespace pathd::server {

// Longest map_dir_file accepted (Linux's PATH_MAX).
inline constexpr size_t kMaxMapDirFileLength = 4096;

// The canonical path of `relative` inside `map_dir`. Errors:
// FAILED_PRECONDITION when map_dir is empty (no --map_dir);
// INVALID_ARGUMENT for an empty, absolute or over-long (kMaxMapDirFileLength)
// path, one with a NUL byte, or one that resolves outside
// map_dir (through "..", or a symlink pointing out); NOT_FOUND when it does
// not exist; INVALID_ARGUMENT when it is not a regular file.
absl::StatusOr<std::filesystem::path> ResolveMapDirFile(const std::string& map_dir,
                                                        std::string_view relative);

// Reads the map `relative` names inside map_dir (".map" Moving AI,
// ".yaml"/".yml" ROS map_server), refusing maps over max_cells before they are
// allocated. A ROS YAML's image must also lie inside map_dir. Errors as
// ResolveMapDirFile, plus INVALID_ARGUMENT for an unknown extension or a
// parse error (naming file and line) and RESOURCE_EXHAUSTED for size.
absl::StatusOr<Grid> LoadMapDirFile(const std::string& map_dir,
                                    std::string_view relative, int64_t max_cells);

// Names (relative to map_dir) of the regular ".map" and ".yaml" files directly
// in map_dir, sorted. NOT_FOUND / INVALID_ARGUMENT when map_dir is missing or
// not a directory.
absl::StatusOr<std::vector<std::string>> ListMapDirFiles(const std::string& map_dir);

}  // namespace pathd::server

#endif  // PATHD_SERVER_STORAGE_MAP_DIR_H_
