// What the maps commands share (maps_cmd.cc, maps_io_cmd.cc): printing a
// map's info as text or CSV, and CreateMap with a progress line.
#ifndef PATHD_CLIENT_PATHCTL_MAPS_CMD_H_
#define PATHD_CLIENT_PATHCTL_MAPS_CMD_H_

#include <ostream>
#include <span>
#include <string>

#include "absl/status/statusor.h"
#include "client/pathctl/command_env.h"
#include "client/pathctl/output.h"
#include "pathd/v1/map_service.pb.h"

namespace pathd::pathctl {

// The "name: ... version: ..." block of maps create / get.
void PrintMapInfo(std::ostream& out, const v1::MapInfo& info);

// Maps as CSV: one row per map, every MapInfo figure in its own column.
Table MapInfoCsv(std::span<const v1::MapInfo* const> maps);

// CreateMap, with a progress line on stderr while the server receives and
// parses `request` (progress bars only): the call is unary, so the line
// shows what is being sent and for how long, not a fraction. `file` names it.
// A request over kUnaryCreateMapBytes (map_source.h) is parsed here and
// sent through UploadMap in 1 MiB bands instead.
absl::StatusOr<v1::CreateMapResponse> CreateMapWithProgress(
    CommandEnv& env, const v1::CreateMapRequest& request, const std::string& file);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_MAPS_CMD_H_
