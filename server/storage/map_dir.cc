// Safe path resolution and loading for --map_dir files.
#include "server/storage/map_dir.h"

#include <algorithm>
#include <system_error>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "core/map_io/map_io.h"
#include "core/status_macros.h"

namespace pathd::server {
namespace {

namespace fs = std::filesystem;

// True when `path` is `root` or below it, comparing whole components (so
// "/maps2" is not inside "/maps"). Both must be canonical.
bool IsWithin(const fs::path& root, const fs::path& path) {
  auto [root_end, path_it] =
      std::mismatch(root.begin(), root.end(), path.begin(), path.end());
  return root_end == root.end();
}

absl::StatusOr<fs::path> CanonicalDir(const std::string& map_dir) {
  if (map_dir.empty()) {
    return absl::FailedPreconditionError(
        "the server was started without --map_dir");
  }
  std::error_code ec;
  fs::path root = fs::weakly_canonical(fs::absolute(map_dir, ec), ec);
  if (ec) {
    return absl::InternalError(
        absl::StrFormat("cannot resolve --map_dir '%s': %s", map_dir, ec.message()));
  }
  return root;
}

bool HasExtension(const fs::path& p, std::initializer_list<std::string_view> exts) {
  const std::string ext = p.extension().string();
  return std::any_of(exts.begin(), exts.end(),
                     [&](std::string_view e) { return ext == e; });
}

}  // namespace

absl::StatusOr<fs::path> ResolveMapDirFile(const std::string& map_dir,
                                           std::string_view relative) {
  PATHD_ASSIGN_OR_RETURN(const fs::path root, CanonicalDir(map_dir));
  if (relative.empty()) {
    return absl::InvalidArgumentError("map_dir_file is empty");
  }
  // Checked before the path is quoted in any message: a 1 MiB path would not
  // fit in gRPC's metadata and reach the client as an unrelated error.
  if (relative.size() > kMaxMapDirFileLength) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "map_dir_file is %d bytes long; the limit is %d", relative.size(),
        kMaxMapDirFileLength));
  }
  if (relative.find('\0') != std::string_view::npos) {
    return absl::InvalidArgumentError("map_dir_file contains a NUL byte");
  }
  const fs::path rel(relative);
  if (rel.is_absolute() || rel.has_root_name() || rel.has_root_directory()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "map_dir_file '%s' must be a path relative to --map_dir", relative));
  }
  // weakly_canonical follows symlinks and folds "..", so the prefix check
  // below sees where the file really is, not how the client spelled it.
  std::error_code ec;
  const fs::path resolved = fs::weakly_canonical(root / rel, ec);
  if (ec) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "map_dir_file '%s' cannot be resolved: %s", relative, ec.message()));
  }
  if (!IsWithin(root, resolved) || resolved == root) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "map_dir_file '%s' resolves outside --map_dir", relative));
  }
  const fs::file_status status = fs::status(resolved, ec);
  if (ec || !fs::exists(status)) {
    return absl::NotFoundError(
        absl::StrFormat("map_dir_file '%s' not found in --map_dir", relative));
  }
  if (!fs::is_regular_file(status)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("map_dir_file '%s' is not a regular file", relative));
  }
  return resolved;
}

absl::StatusOr<Grid> LoadMapDirFile(const std::string& map_dir,
                                    std::string_view relative, int64_t max_cells) {
  PATHD_ASSIGN_OR_RETURN(const fs::path path, ResolveMapDirFile(map_dir, relative));
  if (HasExtension(path, {".map"})) {
    PATHD_ASSIGN_OR_RETURN(const std::string text, ReadFileToString(path.string()));
    return ParseMovingAiMap(text, relative, max_cells);
  }
  if (HasExtension(path, {".yaml", ".yml"})) {
    PATHD_ASSIGN_OR_RETURN(const std::string yaml, ReadFileToString(path.string()));
    PATHD_ASSIGN_OR_RETURN(const RosMapMetadata metadata,
                           ParseRosMapYaml(yaml, relative));
    // The image is read here rather than by ReadRosMapFile so that a YAML
    // inside the directory cannot name an image outside it.
    PATHD_ASSIGN_OR_RETURN(const fs::path root, CanonicalDir(map_dir));
    std::error_code ec;
    const fs::path image_rel =
        fs::relative(path.parent_path() / metadata.image, root, ec);
    if (ec || image_rel.empty() || *image_rel.begin() == "..") {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s: image '%s' lies outside --map_dir", relative, metadata.image));
    }
    PATHD_ASSIGN_OR_RETURN(const fs::path image,
                           ResolveMapDirFile(map_dir, image_rel.string()));
    PATHD_ASSIGN_OR_RETURN(const std::string pgm, ReadFileToString(image.string()));
    return ParseRosMap(metadata, pgm, image_rel.string(), max_cells);
  }
  return absl::InvalidArgumentError(absl::StrFormat(
      "map_dir_file '%s' has an unknown extension (expected .map, .yaml or .yml)",
      relative));
}

absl::StatusOr<std::vector<std::string>> ListMapDirFiles(const std::string& map_dir) {
  PATHD_ASSIGN_OR_RETURN(const fs::path root, CanonicalDir(map_dir));
  std::error_code ec;
  if (!fs::exists(root, ec)) {
    return absl::NotFoundError(
        absl::StrFormat("--map_dir '%s' does not exist", map_dir));
  }
  if (!fs::is_directory(root, ec)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("--map_dir '%s' is not a directory", map_dir));
  }
  std::vector<std::string> names;
  for (fs::directory_iterator it(root, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path& p = it->path();
    // is_regular_file follows symlinks; ResolveMapDirFile later rejects a
    // link that points out of the directory.
    std::error_code entry_ec;  // a dangling link skips the entry, not the dir
    if (it->is_regular_file(entry_ec) && HasExtension(p, {".map", ".yaml"})) {
      names.push_back(p.filename().string());
    }
  }
  if (ec) {
    return absl::InternalError(absl::StrFormat("cannot list --map_dir '%s': %s",
                                               map_dir, ec.message()));
  }
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace pathd::server
