// pathctl batch: the lines of a file sent through one PlanBatch stream,
// and the parser of that file.
#ifndef PATHD_CLIENT_PATHCTL_BATCH_CMD_H_
#define PATHD_CLIENT_PATHCTL_BATCH_CMD_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "pathd/v1/planner_service.pb.h"

namespace pathd::pathctl {

// One item of a `pathctl batch` file.
struct BatchItem {
  std::string id;
  v1::PlanRequest request;
};

// The items of a batch file: one "ID MAP SX SY GX GY [PLANNER]" per line
// (cells; world metres with `world`), fields separated by spaces or tabs,
// blank lines and lines starting with '#' skipped. INVALID_ARGUMENT
// "FILE:LINE: ..." for a malformed line or a MAP the map name rule refuses.
// Only the positions and the planner are set; the caller adds the options
// shared by every item.
absl::StatusOr<std::vector<BatchItem>> ParseBatchFile(absl::string_view text,
                                                      absl::string_view file_name,
                                                      bool world);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_BATCH_CMD_H_
