// Child processes for tests and benchmarks: fork/exec with the caller's
// environment, pipes, and waits with and without a bound. The pathd launcher
// (pathd_process.h) is built on it; the e2e tests also run pathctl, nginx and
// scripts with it. Free of gtest, so benchmarks can use it too.
#ifndef PATHD_TESTS_TESTING_SUBPROCESS_H_
#define PATHD_TESTS_TESTING_SUBPROCESS_H_

#include <sys/types.h>

#include <string>
#include <vector>

#include "absl/time/time.h"

namespace pathd::testing {

// WaitForExit's answers besides an exit code (0-255).
inline constexpr int kKilledBySignal = -1;
// The process was still running at the bound; it has been killed with
// SIGKILL and reaped.
inline constexpr int kDidNotExit = -2;

// Starts argv[0] with this process's environment minus PATHD_SERVER plus
// `extra_env` ("NAME=value"), stdout/stderr redirected to the given fds (or
// inherited when -1). With `die_with_parent` the kernel kills the child if
// the calling thread dies, so even a crashed test leaves no daemon running.
// Returns the pid, or -1 when fork failed (errno says why).
pid_t Spawn(const std::vector<std::string>& argv,
            const std::vector<std::string>& extra_env, int stdout_fd,
            int stderr_fd, bool die_with_parent);

// pipe2 with O_CLOEXEC; false (errno set) when it failed.
bool MakePipe(int fds[2]);

// Blocks until `pid` exits; its exit code, or kKilledBySignal.
int WaitForExit(pid_t pid);

// Waits up to `bound` for `pid` to exit; past it, kills it with SIGKILL,
// reaps it and answers kDidNotExit. Otherwise as WaitForExit.
int WaitForExitWithin(pid_t pid, absl::Duration bound);

// `pid`'s exit code (or kKilledBySignal) when it has exited, reaping it;
// kDidNotExit while it still runs.
int PollExit(pid_t pid);

}  // namespace pathd::testing

#endif  // PATHD_TESTS_TESTING_SUBPROCESS_H_
