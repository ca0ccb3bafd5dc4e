// The fixture and helpers of e2e_test, whose tests are split by topic over
// tests/e2e/e2e_*_test.cc: the test starts the real pathd binary on a free
// loopback port and drives it with the real pathctl binary, checking exit
// codes, stderr and the --json output exactly as a user or script would see
// them. Each test gets its own daemon, stopped with SIGTERM in TearDown (which
// also checks the graceful exit status), so a failing test never leaves a
// daemon behind.
#ifndef PATHD_TESTS_E2E_E2E_FIXTURE_H_
#define PATHD_TESTS_E2E_E2E_FIXTURE_H_

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "proto/planner_names.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "google/protobuf/struct.pb.h"
#include "google/protobuf/util/json_util.h"
#include "gtest/gtest.h"
#include "client/pathctl/pathctl.h"
#include "client/pathctl/png_io.h"
#include "client/pathctl/render.h"
#include "pathd/v1/map_service.pb.h"
#include "pathd/v1/planner_service.pb.h"
#include "tests/e2e/process.h"
#include "tests/testing/temp_dir.h"
#include "tests/testing/test_certs.h"

namespace pathd::e2e_test {

namespace fs = std::filesystem;
using e2e::ReadFile;
using e2e::WriteFile;
using Clock = std::chrono::steady_clock;

// Hang guards, not timing assertions: generous enough for a loaded CI
// machine, there only so a broken binary fails the test instead of hanging it.
constexpr auto kCommandBound = std::chrono::seconds(120);

using e2e::kListeningPrefix;
inline const double kSqrt2 = std::sqrt(2.0);

// A 10x10 open room in Moving AI format.
inline std::string OpenRoomMap(int width = 10, int height = 10) {
  std::string text = absl::StrCat("type octile\nheight ", height, "\nwidth ",
                                  width, "\nmap\n");
  for (int y = 0; y < height; ++y) text += std::string(width, '.') + "\n";
  return text;
}

struct ProcessResult {
  int exit_code = -1;  // -1: killed by a signal
  std::string out;
  std::string err;
};

inline std::ostream& operator<<(std::ostream& os, const ProcessResult& r) {
  return os << "exit " << r.exit_code << "\n--- stdout ---\n"
            << r.out << "--- stderr ---\n"
            << r.err;
}

using e2e::MakePipe;
using e2e::Spawn;
using e2e::WaitForExit;

// A pathctl process (or another `binary`, e.g. pathd) whose stdout and stderr
// are collected as they arrive, so a test can act while it runs (a navigate
// session waiting for a push) and wait for what it prints.
class PathctlProcess {
 public:
  explicit PathctlProcess(const std::vector<std::string>& args,
                          const std::vector<std::string>& extra_env = {},
                          const std::string& binary = PATHCTL_BIN) {
    int out_pipe[2], err_pipe[2];
    MakePipe(out_pipe);
    MakePipe(err_pipe);
    std::vector<std::string> argv = {binary};
    argv.insert(argv.end(), args.begin(), args.end());
    pid_ = Spawn(argv, extra_env, out_pipe[1], err_pipe[1], true);
    close(out_pipe[1]);
    close(err_pipe[1]);
    fds_[0] = {out_pipe[0], POLLIN, 0};
    fds_[1] = {err_pipe[0], POLLIN, 0};
    if (pid_ < 0) {
      ADD_FAILURE() << "fork failed: " << strerror(errno);
      CloseAll();
    }
  }

  PathctlProcess(const PathctlProcess&) = delete;
  PathctlProcess& operator=(const PathctlProcess&) = delete;

  ~PathctlProcess() {
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      WaitForExit(pid_);
    }
    CloseAll();
  }

  // Reads until stdout holds a whole line containing `text` (true) or the
  // process closed its output or ran past kCommandBound (false).
  bool WaitForLine(const std::string& text) {
    const Clock::time_point bound = Clock::now() + kCommandBound;
    while (true) {
      const size_t at = result_.out.find(text);
      if (at != std::string::npos &&
          result_.out.find('\n', at) != std::string::npos) {
        return true;
      }
      if (open_count_ == 0 || Clock::now() > bound) return false;
      Pump();
    }
  }

  // Reads everything and waits for the exit.
  ProcessResult Finish() {
    const Clock::time_point bound = Clock::now() + kCommandBound;
    while (open_count_ > 0) {
      if (Clock::now() > bound) {
        ADD_FAILURE() << "pathctl did not finish; killing it";
        kill(pid_, SIGKILL);
        break;
      }
      Pump();
    }
    CloseAll();
    if (pid_ > 0) {
      result_.exit_code = WaitForExit(pid_);
      pid_ = -1;
    }
    return result_;
  }

  const std::string& out() const { return result_.out; }
  const std::string& err() const { return result_.err; }

  // WaitForLine for stderr (where pathd logs).
  bool WaitForStderrLine(const std::string& text) {
    const Clock::time_point bound = Clock::now() + kCommandBound;
    while (true) {
      const size_t at = result_.err.find(text);
      if (at != std::string::npos &&
          result_.err.find('\n', at) != std::string::npos) {
        return true;
      }
      if (open_count_ == 0 || Clock::now() > bound) return false;
      Pump();
    }
  }

  // Sends `signal_number` to the process (while it runs).
  void Signal(int signal_number) {
    if (pid_ > 0) kill(pid_, signal_number);
  }

 private:
  // Both pipes are read together so neither can fill up and block pathctl.
  void Pump() {
    if (poll(fds_, 2, 1000) < 0 && errno != EINTR) {
      CloseAll();
      return;
    }
    std::string* sinks[2] = {&result_.out, &result_.err};
    for (int i = 0; i < 2; ++i) {
      if (fds_[i].fd < 0 || fds_[i].revents == 0) continue;
      char buffer[4096];
      const ssize_t n = read(fds_[i].fd, buffer, sizeof(buffer));
      if (n > 0) {
        sinks[i]->append(buffer, static_cast<size_t>(n));
      } else if (n == 0 || errno != EINTR) {
        close(fds_[i].fd);
        fds_[i].fd = -1;
        --open_count_;
      }
    }
  }

  void CloseAll() {
    for (pollfd& p : fds_) {
      if (p.fd >= 0) close(p.fd);
      p.fd = -1;
    }
    open_count_ = 0;
  }

  pid_t pid_ = -1;
  pollfd fds_[2] = {{-1, POLLIN, 0}, {-1, POLLIN, 0}};
  int open_count_ = 2;
  ProcessResult result_;
};

// Runs pathctl with `args` and returns its exit code and output.
inline ProcessResult RunPathctl(const std::vector<std::string>& args,
                         const std::vector<std::string>& extra_env = {}) {
  return PathctlProcess(args, extra_env).Finish();
}

template <typename Message>
Message ParseJson(const std::string& json) {
  Message message;
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = true;
  auto status =
      google::protobuf::util::JsonStringToMessage(json, &message, options);
  EXPECT_TRUE(status.ok()) << status.ToString() << "\n" << json;
  return message;
}

inline std::vector<std::pair<int, int>> PathCells(const v1::PlanResponse& response) {
  std::vector<std::pair<int, int>> cells;
  for (const v1::Cell& c : response.path()) cells.emplace_back(c.x(), c.y());
  return cells;
}

// The status code whose name is `name`, e.g. "NOT_FOUND"; kUnknown if none.
inline absl::StatusCode StatusCodeNamed(const std::string& name) {
  for (int c = 0; c <= static_cast<int>(absl::StatusCode::kUnauthenticated); ++c) {
    const auto code = static_cast<absl::StatusCode>(c);
    if (absl::StatusCodeToString(code) == name) return code;
  }
  return absl::StatusCode::kUnknown;
}

class E2eTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_FALSE(temp_dir_.empty()) << scratch_.error();
    // map_dir stays empty: the daemon preloads whatever it finds there, and
    // the tests want to create every map themselves.
    map_dir_ = temp_dir_ / "map_dir";
    fs::create_directory(map_dir_);
    ASSERT_NO_FATAL_FAILURE(StartDaemon());
  }

  void TearDown() override {
    if (daemon_ != nullptr) {
      const int exit_code = StopDaemon();
      EXPECT_EQ(exit_code, 0) << "pathd did not exit cleanly on SIGTERM";
    }
  }

  // Starts pathd on a free port with this test's map_dir and `extra_flags`;
  // its log goes to the test's stderr.
  void StartDaemon(const std::vector<std::string>& extra_flags = {}) {
    std::vector<std::string> flags = {absl::StrCat("--map_dir=", map_dir_.string())};
    flags.insert(flags.end(), extra_flags.begin(), extra_flags.end());
    daemon_ = std::make_unique<e2e::PathdProcess>(
        e2e::PathdProcessOptions{.binary = PATHD_BIN, .flags = flags});
    ASSERT_TRUE(daemon_->listening()) << daemon_->status();
    address_ = daemon_->address();
  }

  // Sends SIGTERM and returns the daemon's exit code (-1: killed by a signal).
  int StopDaemon() {
    const int exit_code = daemon_->Stop();
    EXPECT_EQ(daemon_->StdoutAfterListening(), "")
        << "pathd must print only the listening line on stdout";
    daemon_.reset();
    return exit_code;
  }

  // A pathd of the test's own besides the fixture's, with `flags` and its
  // log in the temp folder; fails the test unless it listens.
  std::unique_ptr<e2e::PathdProcess> StartOwnPathd(const std::vector<std::string>& flags) {
    auto pathd = std::make_unique<e2e::PathdProcess>(e2e::PathdProcessOptions{
        .binary = PATHD_BIN, .flags = flags, .log_file = temp_dir_ / "own_pathd.log"});
    EXPECT_TRUE(pathd->listening()) << pathd->status();
    return pathd;
  }

  // SIGTERM to `pathd`: its exit code, later stdout and log (as err).
  static ProcessResult StopOwnPathd(e2e::PathdProcess& pathd) {
    ProcessResult result;
    result.exit_code = pathd.Stop();
    result.out = pathd.StdoutAfterListening();
    result.err = pathd.Log();
    return result;
  }

  // Runs pathctl against this test's daemon.
  ProcessResult Ctl(std::vector<std::string> args) {
    args.insert(args.begin(), absl::StrCat("--server=", address_));
    return RunPathctl(args);
  }

  // Starts pathctl against this test's daemon without waiting for it.
  std::unique_ptr<PathctlProcess> StartCtl(std::vector<std::string> args) {
    args.insert(args.begin(), absl::StrCat("--server=", address_));
    return std::make_unique<PathctlProcess>(args);
  }

  // Writes a map file into the temp folder and returns its path.
  std::string MapFile(const std::string& name, const std::string& contents) {
    const fs::path path = temp_dir_ / name;
    WriteFile(path, contents);
    return path.string();
  }

  // Creates `name` from Moving AI text; fails the test unless it worked.
  void CreateMap(const std::string& name, const std::string& text,
                 std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"maps", "create", name, "--from",
                                     MapFile(name + ".map", text)};
    args.insert(args.end(), extra.begin(), extra.end());
    const ProcessResult r = Ctl(args);
    ASSERT_EQ(r.exit_code, 0) << r;
  }

  // Runs `plan ... --json` and parses the response; `expected_exit` is 0 for
  // a found path and 3 for none.
  v1::PlanResponse PlanJson(std::vector<std::string> args,
                            int expected_exit = 0) {
    args.insert(args.begin(), "plan");
    args.push_back("--json");
    const ProcessResult r = Ctl(args);
    EXPECT_EQ(r.exit_code, expected_exit) << r;
    return ParseJson<v1::PlanResponse>(r.out);
  }

  // Expects pathctl to fail with the exit code of `code` (1, or 5-8 for the
  // codes scripts tell apart) and "error: <code>: ..." on stderr containing
  // every one of `words`.
  void ExpectRpcError(const std::vector<std::string>& args,
                      const std::string& code,
                      const std::vector<std::string>& words = {}) {
    const ProcessResult r = Ctl(args);
    EXPECT_EQ(r.exit_code, pathctl::ExitCodeForStatus(StatusCodeNamed(code))) << r;
    EXPECT_TRUE(absl::StartsWith(r.err, absl::StrCat("error: ", code, ": ")))
        << r;
    for (const std::string& word : words) {
      EXPECT_TRUE(absl::StrContains(r.err, word))
          << "missing '" << word << "'\n"
          << r;
    }
  }

  // Removed with the fixture, after TearDown has stopped the daemon.
  testing::TempDir scratch_{"pathd_e2e"};
  fs::path temp_dir_ = scratch_.path();
  fs::path map_dir_;
  std::unique_ptr<e2e::PathdProcess> daemon_;
  std::string address_;
};

// A 20 x 12 room split by a wall at x = 10 with a gap in rows 8..9, so no
// planner gets there in a straight line.
inline std::string WalledRoomMap() {
  std::string text = "type octile\nheight 12\nwidth 20\nmap\n";
  for (int y = 0; y < 12; ++y) {
    std::string row(20, '.');
    if (y < 8 || y > 9) row[10] = '@';
    text += row + "\n";
  }
  return text;
}

// A corridor 9 cells wide between walls in rows 0 and 10, 40 cells long.
inline std::string CorridorMap() {
  std::string text = "type octile\nheight 11\nwidth 40\nmap\n";
  for (int y = 0; y < 11; ++y) {
    text += std::string(40, y == 0 || y == 10 ? '@' : '.') + "\n";
  }
  return text;
}

// WalledRoomMap with the goal corner (17..19, 0..1) walled off by column 16
// and row 2 there.
inline std::string PocketRoomMap() {
  std::string text = "type octile\nheight 12\nwidth 20\nmap\n";
  for (int y = 0; y < 12; ++y) {
    std::string row(20, '.');
    if (y < 8 || y > 9) row[10] = '@';
    if (y <= 2) row[16] = '@';
    if (y == 2) row.replace(16, 4, "@@@@");
    text += row + "\n";
  }
  return text;
}

}  // namespace pathd::e2e_test

#endif  // PATHD_TESTS_E2E_E2E_FIXTURE_H_
