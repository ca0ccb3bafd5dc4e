// The map name rule, checked by pathctl before a name goes into a request
// and its x-pathd-map routing header (a 100 KiB name would otherwise fail in
// gRPC's metadata limit, not with the rule). A copy of the rule and messages
// of server/map_store.cc MapStore::ValidateName: the client may not include
// server code; tests/client/pathctl/map_name_test.cc checks the two agree.
#ifndef PATHD_CLIENT_PATHCTL_MAP_NAME_H_
#define PATHD_CLIENT_PATHCTL_MAP_NAME_H_

#include <cstddef>
#include "absl/strings/string_view.h"

#include "absl/status/status.h"

namespace pathd::pathctl {

// The server's MapStore::kMaxNameLength.
inline constexpr size_t kMaxMapNameLength = 128;

// OK for a name a map can have: 1..128 characters of A-Z a-z 0-9 . _ -, not
// starting with '.'. INVALID_ARGUMENT with the server's message otherwise.
absl::Status ValidateMapName(absl::string_view name);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_MAP_NAME_H_
