// pathctl cache-stats, health and metrics: the commands that ask a server
// about itself rather than about a map.
#ifndef PATHD_CLIENT_PATHCTL_ADMIN_CMD_H_
#define PATHD_CLIENT_PATHCTL_ADMIN_CMD_H_

#include <string>
#include <vector>

#include "absl/strings/string_view.h"

namespace pathd::pathctl {

// The lines of Prometheus text `text` that belong to a metric whose name
// starts with one of `prefixes` (its samples and its # HELP / # TYPE lines);
// all of `text` when `prefixes` is empty.
std::string FilterMetricsText(absl::string_view text,
                              const std::vector<std::string>& prefixes);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_ADMIN_CMD_H_
