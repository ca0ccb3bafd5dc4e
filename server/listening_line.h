// The one line pathd prints on stdout once it serves, "pathd listening on
// HOST:PORT": the prefix is defined here only, for server/main.cc, which
// prints it, and for the tests' launcher (tests/testing/pathd_process.h).
#ifndef PATHD_SERVER_LISTENING_LINE_H_
#define PATHD_SERVER_LISTENING_LINE_H_

namespace pathd::server {

// Followed by the bound "host:port" and a newline.
inline constexpr char kListeningPrefix[] = "pathd listening on ";

// With --http_address, the second line: followed by the bound "host:port"
// of the HTTP API and a newline.
inline constexpr char kHttpListeningPrefix[] = "pathd http on ";

}  // namespace pathd::server

#endif  // PATHD_SERVER_LISTENING_LINE_H_
