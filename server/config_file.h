// pathd's optional config file (`pathd --config FILE`): a YAML mapping whose
// keys are flag names and whose scalar values are written as on the command
// line (`threads: 2`, `shutdown_grace: 5s`). The file is applied to the Abseil
// flags before the command line is parsed, so a flag given on the command line
// overrides the file, and the file overrides the defaults.
#ifndef PATHD_SERVER_CONFIG_FILE_H_
#define PATHD_SERVER_CONFIG_FILE_H_

#include <map>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/types/span.h"

namespace pathd::server {

// One `name: value` line of a config file.
struct ConfigSetting {
  std::string name;
  std::string value;  // the scalar's text, handed to the flag's own parser
  int line = 0;       // 1-based
};

// Parses config file text into its settings in file order. `source` names the
// file in errors. An empty file has no settings. INVALID_ARGUMENT
// "SOURCE:LINE: ..." for YAML syntax errors, a top level that is not a
// mapping, and keys naming a flag twice or with a value that is not a scalar
// (a list, a mapping, or nothing: write "" for an empty string).
absl::StatusOr<std::vector<ConfigSetting>> ParseConfigYaml(
    absl::string_view yaml, absl::string_view source);

// Where the config file set flags, for error messages about their values.
class ConfigOrigins {
 public:
  // Records that `source`:`line` set `flag_name` to `value` (the flag's
  // CurrentValue() right after).
  void Record(const std::string& flag_name, const std::string& source, int line,
              const std::string& value);

  // "SOURCE:LINE" of the setting that gave `flag_name` its current value, or
  // "" when the flag does not hold the value the file gave it (never set by
  // the file, or overridden on the command line).
  std::string Of(absl::string_view flag_name) const;

 private:
  struct Origin {
    std::string where;
    std::string value;
  };
  std::map<std::string, Origin, std::less<>> origins_;
};

// Sets every setting's Abseil flag through the flag's own parser, in order.
// Only the flags named in `settable` may be set. INVALID_ARGUMENT
// "SOURCE:LINE: key 'NAME': ..." for a name outside `settable` (listing the
// valid ones) or a value the flag rejects (with the flag's message); flags set
// before the failing line keep their new values.
absl::Status ApplyConfigSettings(absl::Span<const ConfigSetting> settings,
                                 absl::string_view source,
                                 absl::Span<const std::string> settable,
                                 ConfigOrigins* origins);

// Reads, parses and applies the config file at `path` (see above). NOT_FOUND
// or INVALID_ARGUMENT naming `path` when it cannot be read.
absl::Status LoadConfigFile(const std::string& path,
                            absl::Span<const std::string> settable,
                            ConfigOrigins* origins);

// Flag names spelled with hyphens (`--data-dir`, as the docs of some tools
// write them) rewritten to pathd's underscores (`--data_dir`); values and
// everything after a bare `--` are kept as they are. argv[0] is copied.
std::vector<std::string> NormalizeFlagSpelling(absl::Span<char* const> argv);

// The flag name a config file key or command-line flag stands for: hyphens
// read as underscores.
std::string CanonicalFlagName(absl::string_view name);

// The value of flag `flag_name` in argv (argv[0] is the program) as
// absl::ParseCommandLine will read it: `--name=V`, `-name=V`, `--name V` or
// `-name V`, the last occurrence winning, none after a bare `--`; other
// non-boolean flags given without `=` consume the next argument, as in absl.
// "" when absent. The config file has to be found before the command line is
// parsed, because the command line must be applied after it.
std::string FlagValueInArgv(absl::Span<char* const> argv,
                            absl::string_view flag_name);

}  // namespace pathd::server

#endif  // PATHD_SERVER_CONFIG_FILE_H_
