#include "tests/testing/subprocess.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <thread>

#include "absl/strings/match.h"
#include "absl/time/clock.h"

extern char** environ;

namespace pathd::testing {
namespace {

int DecodeStatus(int status) {
  return WIFEXITED(status) ? WEXITSTATUS(status) : kKilledBySignal;
}

}  // namespace

pid_t Spawn(const std::vector<std::string>& argv,
            const std::vector<std::string>& extra_env, int stdout_fd,
            int stderr_fd, bool die_with_parent) {
  // Everything the child needs is built before fork: after it only
  // async-signal-safe calls are allowed.
  std::vector<std::string> env_strings;
  for (char** e = environ; *e != nullptr; ++e) {
    if (!absl::StartsWith(*e, "PATHD_SERVER=")) env_strings.emplace_back(*e);
  }
  env_strings.insert(env_strings.end(), extra_env.begin(), extra_env.end());
  std::vector<char*> envp;
  for (std::string& s : env_strings) envp.push_back(s.data());
  envp.push_back(nullptr);
  std::vector<std::string> argv_copy = argv;
  std::vector<char*> args;
  for (std::string& s : argv_copy) args.push_back(s.data());
  args.push_back(nullptr);
  const pid_t parent = getpid();
  sigset_t empty_mask;
  sigemptyset(&empty_mask);

  const pid_t pid = fork();
  if (pid != 0) return pid;
  // Child.
  if (die_with_parent) {
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent) _exit(127);
  }
  sigprocmask(SIG_SETMASK, &empty_mask, nullptr);
  signal(SIGTERM, SIG_DFL);
  signal(SIGPIPE, SIG_DFL);
  if (stdout_fd >= 0) dup2(stdout_fd, STDOUT_FILENO);
  if (stderr_fd >= 0) dup2(stderr_fd, STDERR_FILENO);
  execve(args[0], args.data(), envp.data());
  _exit(127);
}

bool MakePipe(int fds[2]) { return pipe2(fds, O_CLOEXEC) == 0; }

int WaitForExit(pid_t pid) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return DecodeStatus(status);
}

int PollExit(pid_t pid) {
  int status = 0;
  pid_t waited = 0;
  while ((waited = waitpid(pid, &status, WNOHANG)) < 0 && errno == EINTR) {
  }
  // An error (no such child) counts as exited: there is nothing to wait for.
  if (waited < 0) return kKilledBySignal;
  return waited == 0 ? kDidNotExit : DecodeStatus(status);
}

int WaitForExitWithin(pid_t pid, absl::Duration bound) {
  const absl::Time deadline = absl::Now() + bound;
  while (true) {
    const int code = PollExit(pid);
    if (code != kDidNotExit) return code;
    if (absl::Now() >= deadline) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  kill(pid, SIGKILL);
  WaitForExit(pid);
  return kDidNotExit;
}

}  // namespace pathd::testing
