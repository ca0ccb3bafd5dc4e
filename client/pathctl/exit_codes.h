// pathctl's process exit codes and the one map from a failed call's status
// code to them. Scripts branch on these numbers; `pathctl --help` lists them.
#ifndef PATHD_CLIENT_PATHCTL_EXIT_CODES_H_
#define PATHD_CLIENT_PATHCTL_EXIT_CODES_H_

#include "absl/status/status.h"

namespace pathd::pathctl {

enum ExitCode : int {
  kExitOk = 0,
  kExitError = 1,   // the RPC or server failed, or a local file was unreadable
  kExitUsage = 2,   // bad command line
  kExitNoPath = 3,  // plan ran but found no path
  kExitInvalidPath = 4,  // check ran and the path is not valid on the map
  // Status codes scripts react to differently from a plain failure; the rest
  // exit kExitError. ExitCodeForStatus is the one place that maps them.
  kExitUnavailable = 5,  // UNAVAILABLE: server unreachable or shutting down
  kExitDeadline = 6,     // DEADLINE_EXCEEDED: --timeout ran out
  kExitNotFound = 7,     // NOT_FOUND: no such map (or local file or folder)
  kExitDenied = 8,       // UNAUTHENTICATED or PERMISSION_DENIED
  // simulate ran, and a robot collided or did not arrive.
  kExitSimulationFailed = 9,
};

// The exit code of a command that failed with `code`: kExitUnavailable,
// kExitDeadline, kExitNotFound or kExitDenied for those codes, kExitOk for
// OK, kExitError for every other code.
int ExitCodeForStatus(absl::StatusCode code);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_EXIT_CODES_H_
