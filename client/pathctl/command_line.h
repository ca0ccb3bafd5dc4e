// pathctl's command line before any command runs: argv split into flags and
// positional arguments (flags may appear anywhere, and a bad flag is exit
// code 2, not Abseil's exit 1), and the server address from the flag or the
// environment.
#ifndef PATHD_CLIENT_PATHCTL_COMMAND_LINE_H_
#define PATHD_CLIENT_PATHCTL_COMMAND_LINE_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"

namespace pathd::pathctl {

// Environment variable naming the server when --server is not given.
inline constexpr char kServerEnvVar[] = "PATHD_SERVER";
// Environment variable holding the token when neither --token nor
// --token_file is given.
inline constexpr char kTokenEnvVar[] = "PATHD_TOKEN";

// argv split into flag arguments (normalised to "--name=value" / "--name" /
// "--noname") and positional arguments.
struct CommandLine {
  std::vector<std::string> flags;
  std::vector<std::string> positional;
  // The names of the flags given (a negated boolean by its own name), for
  // the check that each applies to the command.
  std::vector<std::string> names;
  bool help = false;     // --help, -h or -help was given
  bool version = false;  // --version was given
};

// Splits argv using the process's registered Abseil flags, validating each
// flag name and value up front. absl::ParseCommandLine would exit(1) on a bad
// flag, but pathctl promises exit code 2 for every usage error. Arguments
// that parse as numbers (e.g. "-3") are positional, not flags; "--" ends
// flags. INVALID_ARGUMENT names the offending argument.
absl::StatusOr<CommandLine> SplitCommandLine(int argc, const char* const* argv);

// The server address: `flag_value` if non-empty, else `env_value` if non-null
// and non-empty, else client::kDefaultServerAddress.
std::string ResolveServerAddress(const std::string& flag_value, const char* env_value);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_COMMAND_LINE_H_
