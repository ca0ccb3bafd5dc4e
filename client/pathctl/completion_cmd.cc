// pathctl completion bash: the completion script generated from the
// command table (command.cc PathctlCompletionSpec).
#include "client/pathctl/command.h"

namespace pathd::pathctl {
namespace {

int Completion(CommandEnv& env, Args args) {
  if (args.size() != 1 || args[0] != "bash") {
    return env.Usage("completion takes the shell: bash");
  }
  if (env.global().output != OutputFormat::kTable) {
    return env.Unsupported("completion", "it prints a bash script");
  }
  env.out() << BashCompletionScript(PathctlCompletionSpec());
  return kExitOk;
}

}  // namespace

const Command kCompletionCommand = {
    .name = "completion",
    .synopsis = "bash",
    .help = "Prints a bash completion script: 'source <(pathctl completion bash)'\n"
            "completes commands, flags, planner names, --output formats, files and,\n"
            "when the server answers within a second, map names.",
    .flags = {},
    .run = Completion,
};

}  // namespace pathd::pathctl
