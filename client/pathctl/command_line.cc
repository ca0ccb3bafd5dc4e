// Implementation of pathctl's command-line splitting.
#include "client/pathctl/command_line.h"

#include <optional>

#include "absl/flags/commandlineflag.h"
#include "absl/flags/reflection.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_replace.h"
#include "absl/strings/string_view.h"
#include "client/client.h"

namespace pathd::pathctl {
namespace {

bool IsNumber(absl::string_view text) {
  double unused;
  return absl::SimpleAtod(text, &unused);
}

}  // namespace

absl::StatusOr<CommandLine> SplitCommandLine(int argc,
                                             const char* const* argv) {
  CommandLine line;
  bool flags_ended = false;
  for (int i = 1; i < argc; ++i) {
    const absl::string_view arg = argv[i];
    if (flags_ended || arg.size() < 2 || arg[0] != '-' || IsNumber(arg)) {
      line.positional.emplace_back(arg);
      continue;
    }
    if (arg == "--") {
      flags_ended = true;
      continue;
    }
    absl::string_view body = arg.substr(arg[1] == '-' ? 2 : 1);
    std::optional<absl::string_view> value;
    if (size_t eq = body.find('='); eq != absl::string_view::npos) {
      value = body.substr(eq + 1);
      body = body.substr(0, eq);
    }
    // --tls-ca reads as --tls_ca: the issues and other tools spell flags
    // with hyphens, absl with underscores.
    const std::string name = absl::StrReplaceAll(body, {{"-", "_"}});
    if (name == "help" || name == "h") {
      line.help = true;
      continue;
    }
    if (name == "version" && !value.has_value()) {
      line.version = true;
      continue;
    }
    absl::CommandLineFlag* flag = absl::FindCommandLineFlag(name);
    if (flag == nullptr && absl::StartsWith(name, "no") && !value.has_value()) {
      // --nofoo clears boolean flag foo.
      absl::CommandLineFlag* negated =
          absl::FindCommandLineFlag(name.substr(2));
      if (negated != nullptr && negated->IsOfType<bool>()) {
        line.flags.emplace_back(absl::StrCat("--", name));
        line.names.push_back(name.substr(2));
        continue;
      }
    }
    if (flag == nullptr || flag->IsRetired()) {
      return absl::InvalidArgumentError(absl::StrCat("unknown flag --", name));
    }
    line.names.push_back(name);
    if (flag->IsOfType<bool>() && !value.has_value()) {
      line.flags.emplace_back(absl::StrCat("--", name));
      continue;
    }
    if (!value.has_value()) {
      if (i + 1 >= argc) {
        return absl::InvalidArgumentError(
            absl::StrCat("flag --", name, " needs a value"));
      }
      value = argv[++i];
    }
    // Parsing here sets the flag to the same value absl::ParseCommandLine will
    // set it to, so validating is harmless.
    std::string error;
    if (!flag->ParseFrom(*value, &error)) {
      return absl::InvalidArgumentError(
          absl::StrCat("flag --", name, "='", *value, "': ", error));
    }
    line.flags.emplace_back(absl::StrCat("--", name, "=", *value));
  }
  return line;
}

std::string ResolveServerAddress(const std::string& flag_value,
                                 const char* env_value) {
  if (!flag_value.empty()) return flag_value;
  if (env_value != nullptr && env_value[0] != '\0') return env_value;
  return client::kDefaultServerAddress;
}

}  // namespace pathd::pathctl
