// Implementation of pathctl's local file helpers.
#include "client/pathctl/files.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

#include "absl/strings/str_cat.h"

namespace pathd::pathctl {

absl::StatusOr<std::string> ReadTextFile(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return absl::NotFoundError(absl::StrCat("cannot read ", path));
  std::stringstream text;
  text << file.rdbuf();
  if (file.bad()) return absl::DataLossError(absl::StrCat("error reading ", path));
  return text.str();
}

absl::Status CannotWrite(const std::string& path) {
  const int error = errno;
  std::filesystem::path folder = std::filesystem::path(path).parent_path();
  if (folder.empty()) folder = ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(folder, ec)) {
    return absl::NotFoundError(absl::StrCat("cannot write ", path, ": folder ",
                                            folder.string(), " does not exist"));
  }
  return absl::PermissionDeniedError(
      error != 0 ? absl::StrCat("cannot write ", path, ": ", std::strerror(error))
                 : absl::StrCat("cannot write ", path));
}

absl::Status WriteTextFile(const std::string& path, const std::string& contents) {
  errno = 0;
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) return CannotWrite(path);
  file.write(contents.data(), static_cast<std::streamsize>(contents.size()));
  file.flush();
  if (!file) return absl::DataLossError(absl::StrCat("error writing ", path));
  return absl::OkStatus();
}

}  // namespace pathd::pathctl
