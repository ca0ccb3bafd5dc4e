// Map I/O entry points shared by every format: reading files, choosing a
// reader by extension, and the benchmark's comparison tolerance. The format
// parsers live in movingai.cc and ros_map.cc.
#include "core/map_io/map_io.h"

#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <string_view>
#include <system_error>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"

namespace pathd {
namespace {

std::string ErrnoMessage(int error_number) {
  // std::error_code rather than strerror: strerror is not thread-safe and
  // the server reads maps from worker threads.
  return std::error_code(error_number, std::generic_category()).message();
}

// Number of digits after the decimal point in a number's text ("2.41421356"
// -> 8, "105.77" -> 2, "1" -> 0); an exponent ends the count.
int DecimalsIn(absl::string_view text) {
  const size_t point = text.find('.');
  if (point == absl::string_view::npos) return 0;
  int decimals = 0;
  for (size_t i = point + 1; i < text.size() && absl::ascii_isdigit(text[i]);
       ++i) {
    ++decimals;
  }
  return decimals;
}

}  // namespace

absl::StatusOr<std::string> ReadFileToString(const std::string& path) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(
      std::fopen(path.c_str(), "rb"), &std::fclose);
  if (file == nullptr) {
    const int error_number = errno;
    if (error_number == ENOENT || error_number == ENOTDIR) {
      return absl::NotFoundError(absl::StrCat(path, ": no such file"));
    }
    return absl::InternalError(
        absl::StrCat(path, ": cannot open: ", ErrnoMessage(error_number)));
  }
  std::string contents;
  // One allocation for a regular file (a 256 MiB map would otherwise grow
  // through a dozen copies); the loop below still reads to the real end.
  struct stat info;
  if (fstat(fileno(file.get()), &info) == 0 && S_ISREG(info.st_mode) &&
      info.st_size > 0) {
    contents.reserve(static_cast<size_t>(info.st_size));
  }
  char buffer[1 << 16];
  while (true) {
    const size_t n = std::fread(buffer, 1, sizeof(buffer), file.get());
    contents.append(buffer, n);
    if (n < sizeof(buffer)) {
      // A directory opens fine on Linux and fails here with EISDIR.
      if (std::ferror(file.get())) {
        return absl::InternalError(
            absl::StrCat(path, ": read error: ", ErrnoMessage(errno)));
      }
      break;
    }
  }
  return contents;
}

absl::StatusOr<Grid> ReadMapFile(const std::string& path, int64_t max_cells) {
  const std::string lower = absl::AsciiStrToLower(path);
  if (absl::EndsWith(lower, ".map"))
    return ReadMovingAiMapFile(path, max_cells);
  if (absl::EndsWith(lower, ".yaml") || absl::EndsWith(lower, ".yml")) {
    return ReadRosMapFile(path, max_cells);
  }
  return absl::InvalidArgumentError(absl::StrCat(
      path,
      ": unknown map file type; expected .map (Moving AI) or .yaml/.yml "
      "(ROS map_server)"));
}

double ScenarioTolerance(const Scenario& scenario, std::string_view version) {
  // bg512 files print two decimals.
  if (version == "1.0") return 0.005 + 1e-9;
  // The street files print 8 decimals of a double-precision length.
  if (DecimalsIn(scenario.optimal_text) >= 8) return 1e-6;
  // The rest print %g (6 significant digits) of a single-precision length,
  // so the last digit can be off by one rounding step: allow half a unit in
  // the 6th significant digit plus slack for the float error.
  const double stored = scenario.optimal_length;
  if (!(stored > 0.0) || !std::isfinite(stored)) return 1e-5;
  return 0.5 * std::pow(10.0, std::floor(std::log10(stored)) - 5.0) + 1e-5;
}

}  // namespace pathd
