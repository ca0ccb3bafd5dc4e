// Drives one Navigate stream for `pathctl navigate`: opens the session,
// replays a script against it and prints every NavigateResponse as it
// arrives, including the paths the server pushes unasked.
#ifndef PATHD_CLIENT_PATHCTL_NAVIGATE_SESSION_H_
#define PATHD_CLIENT_PATHCTL_NAVIGATE_SESSION_H_

#include <ostream>
#include <vector>

#include "absl/status/status.h"
#include "client/client.h"
#include "client/pathctl/navigate_script.h"
#include "pathd/v1/planner_service.pb.h"

namespace pathd::pathctl {

// Opens a session with `open`, waits for its path, runs `script` step by step
// (each message waits for its answer), then closes the client side and waits
// for the server to end the stream. Output goes to `out`: a log line per
// script step and a summary plus path per response, or with `json` one
// NavigateResponse per line as proto3 JSON; pushed responses are printed as
// soon as they arrive, from a reader thread.
//
// Every wait (an answer, the close) is bounded by client.timeout(). Returns
// the server's status when it ended the stream with an error;
// DEADLINE_EXCEEDED naming the script line for a missing answer or a failed
// expect-push; FAILED_PRECONDITION when `follow` has no path to follow.
// A kinematic session's poses are printed in cell coordinates, or with
// `world` in metres and the world frame's headings.
absl::Status RunNavigateSession(const client::PathdClient& client,
                                const v1::NavigateOpen& open,
                                const std::vector<ScriptStep>& script, bool json,
                                std::ostream& out, bool world = false);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_NAVIGATE_SESSION_H_
