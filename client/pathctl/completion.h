// The bash completion script `pathctl completion bash` prints. It is built
// from the same tables pathctl runs on (commands, flags, planner names), so
// completion cannot fall behind the CLI; map names come from `pathctl maps
// list` against the server named on the line being completed.
#ifndef PATHD_CLIENT_PATHCTL_COMPLETION_H_
#define PATHD_CLIENT_PATHCTL_COMPLETION_H_

#include <map>
#include <string>
#include <vector>

namespace pathd::pathctl {

// What the script completes.
struct CompletionSpec {
  // First words: maps, plan, ...
  std::vector<std::string> commands;
  // Second words by first word, e.g. "maps" -> create, list, ...
  std::map<std::string, std::vector<std::string>> subcommands;
  // Command paths (words joined by spaces, e.g. "plan", "maps get") whose
  // next argument is a map name.
  std::vector<std::string> map_name_after;
  // Command paths whose next argument is a file (e.g. "batch").
  std::vector<std::string> file_after;
  // Flag names without "--". Boolean flags take no value word.
  std::vector<std::string> value_flags;
  std::vector<std::string> bool_flags;
  // The values a flag takes, e.g. "planner" -> astar, dijkstra, ...
  std::map<std::string, std::vector<std::string>> flag_values;
  // Flags whose value is a file name.
  std::vector<std::string> file_flags;
};

// A bash script defining `_pathctl` and registering it with `complete` for
// pathctl. Map names are fetched by running the binary being completed
// (COMP_WORDS[0]) with `--output=csv --timeout=1s maps list` and the
// line's --server, so an unreachable server costs at most a second and
// completes nothing.
std::string BashCompletionScript(const CompletionSpec& spec);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_COMPLETION_H_
