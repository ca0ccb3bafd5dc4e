// Local files pathctl reads and writes (scripts, paths, batch files, CSV,
// exported maps), with errors that say what is wrong: a missing file or
// folder is NOT_FOUND naming it, an unwritable one PERMISSION_DENIED.
#ifndef PATHD_CLIENT_PATHCTL_FILES_H_
#define PATHD_CLIENT_PATHCTL_FILES_H_

#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace pathd::pathctl {

// The whole file; NOT_FOUND "cannot read PATH" when it cannot be opened,
// DATA_LOSS on a read error.
absl::StatusOr<std::string> ReadTextFile(const std::string& path);

// Why `path` could not be opened for writing, as a status: NOT_FOUND
// "cannot write PATH: folder DIR does not exist" when its folder is missing,
// otherwise PERMISSION_DENIED "cannot write PATH" (with the system's reason).
// Call right after the open failed (it reads errno).
absl::Status CannotWrite(const std::string& path);

// Writes `contents` to `path`, replacing it; CannotWrite's errors, DATA_LOSS
// on a write error.
absl::Status WriteTextFile(const std::string& path, const std::string& contents);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_FILES_H_
