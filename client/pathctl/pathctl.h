// pathctl's entry points for main.cc and the tests that drive it as a
// library: exit codes, command-line splitting, the command table and Run().
// The commands themselves live one per file in <cmd>_cmd.cc.
#ifndef PATHD_CLIENT_PATHCTL_PATHCTL_H_
#define PATHD_CLIENT_PATHCTL_PATHCTL_H_

#include "client/pathctl/command.h"       // IWYU pragma: export
#include "client/pathctl/command_env.h"   // IWYU pragma: export
#include "client/pathctl/command_line.h"  // IWYU pragma: export
#include "client/pathctl/exit_codes.h"    // IWYU pragma: export
#include "client/pathctl/options.h"       // IWYU pragma: export

#endif  // PATHD_CLIENT_PATHCTL_PATHCTL_H_
