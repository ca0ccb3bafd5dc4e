// The command table and what is generated from it: dispatch with the flag
// check, `pathctl help`, and the completion spec.
#include "client/pathctl/command.h"

#include <algorithm>
#include <string>

#include "absl/flags/commandlineflag.h"
#include "absl/flags/reflection.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "client/pathctl/map_name.h"
#include "proto/planner_names.h"

namespace pathd::pathctl {
namespace {

// In synopsis order; completion lists the first words in this order too.
const Command* const kCommands[] = {
    &kMapsCreateCommand, &kMapsListCommand,   &kMapsGetCommand,
    &kMapsDeleteCommand, &kMapsSetCommand,    &kMapsRectCommand,
    &kMapsWatchCommand,  &kMapsImportCommand, &kMapsExportCommand,
    &kMapsStatsCommand,
    &kPlanCommand,       &kBatchCommand,      &kNavigateCommand,
    &kCostToGoCommand,   &kCheckCommand,      &kCacheStatsCommand, &kSessionsCommand,
    &kHealthCommand,     &kMetricsCommand,    &kBenchCommand,
    &kTableCommand,      &kNearestCommand,    &kTripCommand,
    &kIsochroneCommand,  &kFleetPlanCommand,  &kSimulateCommand,
    &kRenderCommand,     &kCompletionCommand, &kHelpCommand,
};

absl::string_view FirstWord(absl::string_view name) {
  return name.substr(0, name.find(' '));
}

// First words in table order, each once: maps, plan, batch, ...
std::vector<std::string> FirstWords() {
  std::vector<std::string> words;
  for (const Command* c : kCommands) {
    const std::string word(FirstWord(c->name));
    if (std::find(words.begin(), words.end(), word) == words.end()) {
      words.push_back(word);
    }
  }
  return words;
}

// The second words of a group: create, list, ...
std::vector<std::string> SubcommandsOf(absl::string_view group) {
  std::vector<std::string> subs;
  for (const Command* c : CommandsOfGroup(group)) {
    subs.emplace_back(c->name.substr(group.size() + 1));
  }
  return subs;
}

bool Lists(std::span<const absl::string_view> flags, absl::string_view flag) {
  return std::find(flags.begin(), flags.end(), flag) != flags.end();
}

// "-o does not apply to plan; render reads it".
std::string FlagDoesNotApply(const std::string& flag, const Command& command) {
  std::vector<absl::string_view> readers;
  for (const Command* c : kCommands) {
    if (Lists(c->flags, flag)) readers.push_back(c->name);
  }
  return absl::StrCat(flag.size() == 1 ? "-" : "--", flag, " does not apply to ",
                      command.name,
                      readers.empty() ? std::string()
                                      : absl::StrCat("; ", absl::StrJoin(readers, ", "),
                                                     readers.size() == 1 ? " reads it"
                                                                         : " read it"));
}

// An error about a group's subcommand: the problem, then the group's usage.
int GroupUsageError(CommandEnv& env, absl::string_view group, absl::string_view problem) {
  env.err() << "error: " << problem << "\n\n" << GroupUsage(group);
  return kExitUsage;
}

// The command `words` names (all of them), or the group they name.
int Help(CommandEnv& env, Args args) {
  if (args.empty()) {
    env.out() << UsageText();
    return kExitOk;
  }
  const std::string name = absl::StrJoin(args, " ");
  if (const Command* command = FindCommand(name)) {
    env.out() << CommandHelp(*command);
    return kExitOk;
  }
  if (args.size() == 1 && !CommandsOfGroup(args[0]).empty()) {
    env.out() << GroupUsage(args[0]);
    return kExitOk;
  }
  return env.Usage(absl::StrCat("help: unknown command '", name, "'; expected ",
                                absl::StrJoin(FirstWords(), ", ")));
}

}  // namespace

const Command kHelpCommand = {
    .name = "help",
    .synopsis = "[COMMAND]",
    .help = "Prints the help of COMMAND (e.g. 'pathctl help maps create'), or of\n"
            "every command without one (the same as 'pathctl --help'). 'pathctl\n"
            "COMMAND --help' is the same as 'pathctl help COMMAND'.",
    .flags = {},
    .run = Help,
    .connects = false,
};

std::span<const Command* const> Commands() { return kCommands; }

const Command* FindCommand(absl::string_view name) {
  for (const Command* c : kCommands) {
    if (c->name == name) return c;
  }
  return nullptr;
}

std::vector<const Command*> CommandsOfGroup(absl::string_view group) {
  std::vector<const Command*> commands;
  for (const Command* c : kCommands) {
    if (c->name.size() > group.size() && absl::StartsWith(c->name, group) &&
        c->name[group.size()] == ' ') {
      commands.push_back(c);
    }
  }
  return commands;
}

int Run(const Options& options, const std::vector<std::string>& args,
        std::ostream& out, std::ostream& err) {
  CommandEnv env(options, out, err);
  if (args.empty()) return env.Usage("missing command");
  const Command* command = nullptr;
  size_t words = 2;
  if (args.size() >= 2) command = FindCommand(absl::StrCat(args[0], " ", args[1]));
  if (command == nullptr) {
    command = FindCommand(args[0]);
    words = 1;
  }
  if (command == nullptr) {
    const std::vector<std::string> subs = SubcommandsOf(args[0]);
    if (!subs.empty() && args.size() == 1) {
      return GroupUsageError(env, args[0],
                             absl::StrCat(args[0], " needs a subcommand: ",
                                          absl::StrJoin(subs, ", ")));
    }
    if (!subs.empty()) {
      return GroupUsageError(env, args[0],
                             absl::StrCat("unknown ", args[0], " subcommand '", args[1],
                                          "'; expected ", absl::StrJoin(subs, ", ")));
    }
    return env.Usage(absl::StrCat("unknown command '", args[0], "'; expected ",
                                  absl::StrJoin(FirstWords(), ", ")));
  }
  env.set_command(command);
  for (const std::string& flag : options.given_flags) {
    if (!Lists(kGlobalFlags, flag) && !Lists(command->flags, flag)) {
      return env.Usage(FlagDoesNotApply(flag, *command));
    }
  }
  if (env.options().global.output == OutputFormat::kGeoJson && !command->geojson) {
    return env.Usage(absl::StrCat("--output geojson: ", command->name,
                                  " prints table, json or csv (geojson is for plan and isochrone)"));
  }
  const Args rest = Args(args).subspan(words);
  if (command->map_arg != MapArg::kNone && !rest.empty()) {
    // As the server would answer, but before the name goes into a header
    // (gRPC refuses metadata past its size limit with an unrelated error).
    if (absl::Status s = ValidateMapName(rest[0]); !s.ok()) return env.Fail(s);
  }
  if (command->connects) {
    if (std::optional<int> failed = env.LoadCredentials()) return *failed;
  }
  return command->run(env, rest);
}

CompletionSpec PathctlCompletionSpec() {
  CompletionSpec spec;
  spec.commands = FirstWords();
  for (const Command* c : kCommands) {
    const absl::string_view first = FirstWord(c->name);
    if (first.size() < c->name.size()) {
      spec.subcommands[std::string(first)].emplace_back(c->name.substr(first.size() + 1));
    }
    if (c->map_arg == MapArg::kExisting) spec.map_name_after.emplace_back(c->name);
    if (c->file_first) spec.file_after.emplace_back(c->name);
  }
  spec.subcommands["completion"] = {"bash"};
  // pathctl's own flags, not the ones Abseil and gRPC register.
  for (const auto& [name, flag] : absl::GetAllFlags()) {
    if (flag->IsRetired() || !absl::EndsWith(flag->Filename(), "pathctl/main.cc")) {
      continue;
    }
    (flag->IsOfType<bool>() ? spec.bool_flags : spec.value_flags).emplace_back(name);
  }
  std::sort(spec.value_flags.begin(), spec.value_flags.end());
  std::sort(spec.bool_flags.begin(), spec.bool_flags.end());
  for (const WirePlanner& p : WirePlanners()) {
    spec.flag_values["planner"].emplace_back(p.name);
  }
  spec.flag_values["output"] = {"table", "json", "csv"};
  spec.flag_values["connectivity"] = {"4", "8"};
  spec.flag_values["pf_attractive"] = {"quadratic", "conic"};
  spec.flag_values["path_encoding"] = {"packed", "readable", "both"};
  spec.flag_values["solver"] = {"lacam", "pibt", "prioritized", "cbs"};
  spec.file_flags = {"from",     "path_file", "script", "cost_to_go_file",
                     "movingai", "out",       "o",      "robots"};
  return spec;
}

}  // namespace pathd::pathctl
