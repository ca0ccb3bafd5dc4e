// File names and POSIX helpers of --data_dir.
#include "server/storage/data_files.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace pathd::server::data_files {

std::string SegmentName(uint64_t first_sequence) {
  return absl::StrFormat("%s%020d%s", kSegmentPrefix, first_sequence, kSegmentSuffix);
}

std::string SnapshotName(std::string_view map) {
  return absl::StrCat(kSnapshotPrefix, std::string(map), kSnapshotSuffix);
}

uint64_t SegmentFirst(const std::string& file) {
  if (!absl::StartsWith(file, kSegmentPrefix) || !absl::EndsWith(file, kSegmentSuffix)) {
    return 0;
  }
  const absl::string_view digits = absl::string_view(file).substr(
      sizeof(kSegmentPrefix) - 1,
      file.size() - (sizeof(kSegmentPrefix) - 1) - (sizeof(kSegmentSuffix) - 1));
  uint64_t first = 0;
  if (digits.size() != 20 || !absl::SimpleAtoi(digits, &first)) return 0;
  return first;
}

absl::Status IoError(std::string_view what, const std::string& path) {
  return absl::InternalError(
      absl::StrFormat("%s %s: %s", what, path, std::strerror(errno)));
}

absl::StatusOr<std::string> ReadWholeFile(const std::string& path) {
  const int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return IoError("cannot open", path);
  std::string bytes;
  char buffer[1 << 16];
  for (;;) {
    const ssize_t n = read(fd, buffer, sizeof(buffer));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      absl::Status error = IoError("cannot read", path);
      close(fd);
      return error;
    }
    if (n == 0) break;
    bytes.append(buffer, static_cast<size_t>(n));
  }
  close(fd);
  return bytes;
}

absl::Status WriteAll(int fd, std::string_view data, const std::string& path) {
  while (!data.empty()) {
    const ssize_t n = write(fd, data.data(), data.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return IoError("cannot write", path);
    data.remove_prefix(static_cast<size_t>(n));
  }
  return absl::OkStatus();
}

}  // namespace pathd::server::data_files
