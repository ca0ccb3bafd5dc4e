// pathctl check: IsPathValid on a path given on the line or in a file, and
// the parser of such path files.
#ifndef PATHD_CLIENT_PATHCTL_CHECK_CMD_H_
#define PATHD_CLIENT_PATHCTL_CHECK_CMD_H_

#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "pathd/v1/planner_service.pb.h"

namespace pathd::pathctl {

// The poses of a path file: one "X Y" pair per line, separated by spaces,
// tabs or a comma (cells, or metres when `world`), blank lines and lines
// starting with '#' skipped. INVALID_ARGUMENT "FILE:LINE: ..." for a malformed
// line.
absl::StatusOr<std::vector<v1::Position>> ParsePathFile(
    absl::string_view text, absl::string_view file_name, bool world);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_CHECK_CMD_H_
