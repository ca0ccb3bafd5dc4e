#include "server/config_file.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

#include "absl/flags/commandlineflag.h"
#include "absl/flags/reflection.h"
#include "absl/strings/ascii.h"
#include "absl/strings/escaping.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_replace.h"
#include "absl/strings/strip.h"

namespace pathd::server {
namespace {

// The flag that names the config file; the file itself may not set it.
constexpr absl::string_view kConfigFlag = "config";

// Quotes text from the file for an error message: escaped and cut short, so
// a binary file or a huge line cannot flood the terminal.
std::string Quote(absl::string_view text) {
  constexpr size_t kMaxQuoted = 40;
  if (text.size() <= kMaxQuoted)
    return absl::StrCat("'", absl::CHexEscape(text), "'");
  return absl::StrCat("'", absl::CHexEscape(text.substr(0, kMaxQuoted)),
                      "...'");
}

std::string Where(absl::string_view source, int line) {
  return line > 0 ? absl::StrCat(source, ":", line) : std::string(source);
}

int LineOf(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.is_null() || mark.line < 0 ? 0 : mark.line + 1;
}

absl::Status KeyError(absl::string_view source, int line, absl::string_view key,
                      absl::string_view problem) {
  return absl::InvalidArgumentError(
      absl::StrCat(Where(source, line), ": key ", Quote(key), ": ", problem));
}

absl::StatusOr<std::vector<ConfigSetting>> ParseConfigYamlOrThrow(
    absl::string_view yaml, absl::string_view source) {
  const YAML::Node root = YAML::Load(std::string(yaml));
  std::vector<ConfigSetting> settings;
  if (root.IsNull()) return settings;  // empty, or only comments
  if (!root.IsMap()) {
    return absl::InvalidArgumentError(
        absl::StrCat(Where(source, LineOf(root)),
                     ": expected a YAML mapping of flag names to values, e.g. "
                     "'threads: 2'"));
  }
  std::set<std::string, std::less<>> seen;
  for (const auto& entry : root) {
    const YAML::Node& key = entry.first;
    const YAML::Node& value = entry.second;
    const int line = LineOf(key);
    if (!key.IsScalar()) {
      return absl::InvalidArgumentError(
          absl::StrCat(Where(source, line), ": keys must be flag names"));
    }
    const std::string name = CanonicalFlagName(key.Scalar());
    if (!seen.insert(name).second) {
      return KeyError(source, line, name, "set twice in this file");
    }
    if (value.IsNull()) {
      return KeyError(source, line, name,
                      "has no value (write \"\" for an empty string)");
    }
    if (!value.IsScalar()) {
      return KeyError(source, line, name,
                      "must be a single value, not a list or mapping");
    }
    settings.push_back(ConfigSetting{name, value.Scalar(), line});
  }
  return settings;
}

}  // namespace

absl::StatusOr<std::vector<ConfigSetting>> ParseConfigYaml(
    absl::string_view yaml, absl::string_view source) {
  try {
    return ParseConfigYamlOrThrow(yaml, source);
  } catch (const YAML::Exception& e) {
    return absl::InvalidArgumentError(
        absl::StrCat(Where(source, e.mark.is_null() ? 0 : e.mark.line + 1),
                     ": invalid YAML: ", e.msg));
  }
}

void ConfigOrigins::Record(const std::string& flag_name,
                           const std::string& source, int line,
                           const std::string& value) {
  origins_[flag_name] = Origin{Where(source, line), value};
}

std::string ConfigOrigins::Of(absl::string_view flag_name) const {
  const auto it = origins_.find(flag_name);
  if (it == origins_.end()) return "";
  const absl::CommandLineFlag* flag = absl::FindCommandLineFlag(flag_name);
  if (flag == nullptr || flag->CurrentValue() != it->second.value) return "";
  return it->second.where;
}

absl::Status ApplyConfigSettings(absl::Span<const ConfigSetting> settings,
                                 absl::string_view source,
                                 absl::Span<const std::string> settable,
                                 ConfigOrigins* origins) {
  for (const ConfigSetting& setting : settings) {
    const bool allowed = std::find(settable.begin(), settable.end(),
                                   setting.name) != settable.end();
    absl::CommandLineFlag* flag =
        allowed ? absl::FindCommandLineFlag(setting.name) : nullptr;
    if (flag == nullptr) {
      if (setting.name == kConfigFlag) {
        return KeyError(source, setting.line, setting.name,
                        "only the command line can name the config file");
      }
      std::vector<std::string> valid(settable.begin(), settable.end());
      std::sort(valid.begin(), valid.end());
      return KeyError(
          source, setting.line, setting.name,
          absl::StrCat("not a pathd setting",
                       absl::StartsWith(setting.name, "-")
                           ? " (write flag names without dashes)"
                           : "",
                       "; valid keys: ", absl::StrJoin(valid, ", ")));
    }
    std::string error;
    if (!flag->ParseFrom(setting.value, &error)) {
      return KeyError(source, setting.line, setting.name, error);
    }
    if (origins != nullptr) {
      origins->Record(setting.name, std::string(source), setting.line,
                      flag->CurrentValue());
    }
  }
  return absl::OkStatus();
}

absl::Status LoadConfigFile(const std::string& path,
                            absl::Span<const std::string> settable,
                            ConfigOrigins* origins) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int error = errno;
    const std::string message = absl::StrCat("cannot read config file ", path,
                                             ": ", std::strerror(error));
    return error == ENOENT ? absl::NotFoundError(message)
                           : absl::InvalidArgumentError(message);
  }
  std::stringstream text;
  text << in.rdbuf();
  if (in.bad()) {
    return absl::InvalidArgumentError(
        absl::StrCat("cannot read config file ", path));
  }
  absl::StatusOr<std::vector<ConfigSetting>> settings =
      ParseConfigYaml(text.str(), path);
  if (!settings.ok()) return settings.status();
  return ApplyConfigSettings(*settings, path, settable, origins);
}

std::string CanonicalFlagName(absl::string_view name) {
  return absl::StrReplaceAll(name, {{"-", "_"}});
}

std::vector<std::string> NormalizeFlagSpelling(absl::Span<char* const> argv) {
  std::vector<std::string> normalized(argv.begin(), argv.end());
  for (size_t i = 1; i < normalized.size(); ++i) {
    std::string& arg = normalized[i];
    if (arg == "--") break;
    // Only "-name..." / "--name...": a value such as "-3" stays as it is.
    const size_t start = absl::StartsWith(arg, "--") ? 2 : 1;
    if (arg.size() <= start || arg[0] != '-' ||
        !absl::ascii_isalpha(static_cast<unsigned char>(arg[start]))) {
      continue;
    }
    const size_t end = std::min(arg.find('='), arg.size());
    std::replace(arg.begin() + start, arg.begin() + end, '-', '_');
  }
  return normalized;
}

std::string FlagValueInArgv(absl::Span<char* const> argv,
                            absl::string_view flag_name) {
  std::string found;
  for (size_t i = 1; i < argv.size(); ++i) {
    absl::string_view arg = argv[i];
    // A positional argument ("x" or a lone "-").
    if (!absl::ConsumePrefix(&arg, "-") || arg.empty()) continue;
    absl::ConsumePrefix(&arg, "-");
    if (arg.empty()) break;  // "--" ends the flags
    const size_t equals = arg.find('=');
    const absl::string_view name = arg.substr(0, equals);
    const bool has_value = equals != absl::string_view::npos;
    if (name == flag_name) {
      if (has_value) {
        found = std::string(arg.substr(equals + 1));
      } else if (i + 1 < argv.size()) {
        found = argv[++i];
      }
      continue;
    }
    // Any other flag written "--name VALUE" takes the next argument as its
    // value, which is then not a flag of its own.
    const absl::CommandLineFlag* other = absl::FindCommandLineFlag(name);
    if (!has_value && other != nullptr && !other->IsOfType<bool>()) ++i;
  }
  return found;
}

}  // namespace pathd::server
