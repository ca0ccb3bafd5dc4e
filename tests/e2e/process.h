// Child processes for the end-to-end tests: spawn a binary with the test's
// environment, pipes, and waiting for its exit. Shared by e2e_test.cc
// (pathctl and pathd) and admission_test.cc (pathd driven over gRPC).
#ifndef PATHD_TESTS_E2E_PROCESS_H_
#define PATHD_TESTS_E2E_PROCESS_H_

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "absl/strings/match.h"
#include "gtest/gtest.h"

extern char** environ;

namespace pathd::e2e {

// A file's whole content, "" when it cannot be read (a log not written yet).
inline std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Writes `contents` to `path`, failing the test when it cannot.
inline void WriteFile(const std::filesystem::path& path,
                      const std::string& contents) {
  std::ofstream out(path, std::ios::binary);
  out << contents;
  ASSERT_TRUE(out.good()) << "cannot write " << path;
}

// Starts argv[0] with the test's environment minus PATHD_SERVER plus
// `extra_env` ("NAME=value"), stdout/stderr redirected to the given fds (or
// inherited when -1). With `die_with_parent` the kernel kills the child if the
// test process dies, so even a crashed test leaves no daemon running.
inline pid_t Spawn(const std::vector<std::string>& argv,
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

inline void MakePipe(int fds[2]) {
  ASSERT_EQ(pipe2(fds, O_CLOEXEC), 0) << strerror(errno);
}

// Blocks until `pid` exits; returns its exit code, or -1 for a signal.
inline int WaitForExit(pid_t pid) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace pathd::e2e

#endif  // PATHD_TESTS_E2E_PROCESS_H_
