// The one pathd process launcher of the e2e tests and the load benchmark:
// spawns the daemon on a free loopback port, reads its listening line
// (server/listening_line.h) for the address, sends its log (stderr) to a
// file or to the caller's stderr, and stops it with SIGTERM and a bounded
// wait that falls back to SIGKILL. Free of gtest: errors are statuses.
#ifndef PATHD_TESTS_TESTING_PATHD_PROCESS_H_
#define PATHD_TESTS_TESTING_PATHD_PROCESS_H_

#include <sys/types.h>

#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "server/listening_line.h"
#include "tests/testing/subprocess.h"

namespace pathd::testing {

using server::kListeningPrefix;

// Hang guard of every wait below: generous for a loaded CI machine, there
// only so that a broken daemon fails the test instead of hanging it. Never a
// timing assertion.
inline constexpr absl::Duration kProcessBound = absl::Seconds(120);

struct PathdProcessOptions {
  // The pathd binary (tests get it as PATHD_BIN from CMake).
  std::string binary;
  // Given as --address first; empty = no --address flag.
  std::string address = "127.0.0.1:0";
  // Flags after --address (a later --address wins).
  std::vector<std::string> flags;
  // stderr (the daemon's log) goes to this file, truncated first; empty =
  // the caller's own stderr.
  std::filesystem::path log_file;
  // "NAME=value" added to the environment (PATHD_SERVER is always removed).
  std::vector<std::string> extra_env;
  absl::Duration bound = kProcessBound;
};

// Started by the constructor; the destructor kills (SIGKILL) a daemon still
// running, so a failing test never leaves one behind. The kernel kills it
// too if the thread that started it dies.
class PathdProcess {
 public:
  explicit PathdProcess(PathdProcessOptions options);
  ~PathdProcess();
  PathdProcess(const PathdProcess&) = delete;
  PathdProcess& operator=(const PathdProcess&) = delete;

  // OK once the listening line arrived; else why not (it could not be
  // started, exited first -- with the log's end when it is in a file --
  // printed another first line, or said nothing within the bound).
  const absl::Status& status() const { return status_; }
  bool listening() const { return status_.ok(); }
  // "host:port" from the listening line; empty unless listening().
  const std::string& address() const { return address_; }
  // -1 once waited for.
  pid_t pid() const { return pid_; }

  // The log file's contents; empty when stderr was not redirected.
  std::string Log() const;
  // The first log line containing every one of `parts`, waiting for it
  // until the bound; empty if none came.
  std::string WaitForLogLine(const std::vector<std::string>& parts) const;

  // Whether the process has not exited yet (an exited one is reaped and its
  // code kept for WaitForExit).
  bool Running();
  void Signal(int signal_number);
  // SIGTERM, then WaitForExit.
  int Stop();
  // The exit code (0-255), kKilledBySignal, or kDidNotExit when it still ran
  // at the bound and was killed with SIGKILL (also said on stderr).
  int WaitForExit();
  // SIGKILL, and reap.
  void Kill();

  // What the daemon printed on stdout after the listening line (the contract
  // is: nothing). Complete once the process has exited.
  std::string StdoutAfterListening() const;

 private:
  void ReadListeningLine();
  // Reaps the process and joins the stdout reader.
  void Finish(int exit_code);

  const PathdProcessOptions options_;
  pid_t pid_ = -1;
  int exit_code_ = kDidNotExit;
  int stdout_fd_ = -1;
  absl::Status status_;
  std::string address_;
  // Reads stdout after the listening line so the daemon never blocks on a
  // full pipe nor dies of SIGPIPE.
  std::thread drain_;
  mutable absl::Mutex stdout_mu_;
  std::string stdout_after_ ABSL_GUARDED_BY(stdout_mu_);
};

}  // namespace pathd::testing

#endif  // PATHD_TESTS_TESTING_PATHD_PROCESS_H_
