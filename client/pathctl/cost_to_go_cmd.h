// pathctl cost-to-go: the goal-rooted cost-to-go field of a map (or a
// window of it), and the CSV writer plan --cost_to_go_file shares.
#ifndef PATHD_CLIENT_PATHCTL_COST_TO_GO_CMD_H_
#define PATHD_CLIENT_PATHCTL_COST_TO_GO_CMD_H_

#include <cstdint>
#include <string>

#include "absl/status/status.h"
#include "google/protobuf/repeated_field.h"

namespace pathd::pathctl {

// Writes a row-major cost-to-go field as CSV, one map row per line, "inf"
// for unreachable cells. DATA_LOSS when the values do not fill whole rows;
// NOT_FOUND naming the folder when it does not exist, PERMISSION_DENIED when
// the file cannot be written.
absl::Status WriteCostToGoCsv(const std::string& path, int32_t width,
                              const google::protobuf::RepeatedField<double>& field);
// The same for CostToGo's 4-byte field.
absl::Status WriteCostToGoCsv(const std::string& path, int32_t width,
                              const google::protobuf::RepeatedField<float>& field);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_COST_TO_GO_CMD_H_
