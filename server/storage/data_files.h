// The file names of --data_dir and the small POSIX helpers DurableStore's
// log, checkpoint and recovery code share (server/storage/durable_store.h).
// Internal to server/storage/.
#ifndef PATHD_SERVER_STORAGE_DATA_FILES_H_
#define PATHD_SERVER_STORAGE_DATA_FILES_H_

#include <cstdint>
#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace pathd::server::data_files {

inline constexpr char kSegmentPrefix[] = "wal-";
inline constexpr char kSegmentSuffix[] = ".log";
inline constexpr char kSnapshotPrefix[] = "map-";
inline constexpr char kSnapshotSuffix[] = ".snap";
inline constexpr char kTempSuffix[] = ".tmp";
inline constexpr char kCorruptSuffix[] = ".corrupt";
inline constexpr char kCheckpointFile[] = "CHECKPOINT";

// wal-<20 digits>.log
std::string SegmentName(uint64_t first_sequence);
// map-<name>.snap
std::string SnapshotName(std::string_view map);
// The first sequence number a segment file name holds; 0 for other names.
uint64_t SegmentFirst(const std::string& file);

// INTERNAL "WHAT PATH: strerror(errno)".
absl::Status IoError(std::string_view what, const std::string& path);
absl::StatusOr<std::string> ReadWholeFile(const std::string& path);
absl::Status WriteAll(int fd, std::string_view data, const std::string& path);

}  // namespace pathd::server::data_files

#endif  // PATHD_SERVER_STORAGE_DATA_FILES_H_
